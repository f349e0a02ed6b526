//! Layering and documentation checks on the source tree (issue 19,
//! "Hygiene"). Run without ../shared.

use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Regression (issue 19): five library enums derived `clap::ValueEnum`, so
/// clap was a hard dependency of the library. Only the binary (src/main.rs,
/// src/cli/) may name clap, anyhow, indicatif or tracing_subscriber; the
/// Cargo feature `cli` carries them.
#[test]
fn library_does_not_use_binary_only_crates() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut offenders = Vec::new();
    for f in &files {
        let rel = f.strip_prefix(&src).unwrap();
        if rel.starts_with("cli") || rel == Path::new("main.rs") {
            continue;
        }
        let text = std::fs::read_to_string(f).unwrap();
        for (i, line) in text.lines().enumerate() {
            for krate in ["clap", "anyhow", "indicatif", "tracing_subscriber"] {
                if line.contains(&format!("{krate}::")) || line.contains(&format!("use {krate}")) {
                    offenders.push(format!("{}:{}: {}", rel.display(), i + 1, line.trim()));
                }
            }
        }
    }
    assert!(files.len() > 50, "walked only {} files", files.len());
    assert!(
        offenders.is_empty(),
        "binary-only crates used by the library:\n{}",
        offenders.join("\n")
    );
}

/// Regression (issue 19): the crate docs named 4 of the 18 modules. Every
/// `pub mod` of src/lib.rs is listed in the crate docs with a line of its
/// own, each once, and the missing-docs lint is on.
#[test]
fn crate_docs_list_every_module() {
    let lib =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs")).unwrap();
    assert!(lib.contains("#![warn(missing_docs)]"));
    let modules: Vec<&str> = lib
        .lines()
        .filter_map(|l| l.strip_prefix("pub mod "))
        .map(|l| l.trim_end_matches(';'))
        .collect();
    assert!(modules.len() >= 18, "{modules:?}");
    let docs: Vec<&str> = lib.lines().filter(|l| l.starts_with("//!")).collect();
    for m in &modules {
        let entry = format!("//! - [`{m}`]: ");
        let n = docs.iter().filter(|l| l.starts_with(&entry)).count();
        assert_eq!(n, 1, "module {m} listed {n} times in the crate docs");
    }
    let listed = docs.iter().filter(|l| l.starts_with("//! - [`")).count();
    assert_eq!(
        listed,
        modules.len(),
        "the crate docs list a module lib.rs does not declare"
    );
}

/// The integration tests are one binary (issue 40): cargo makes a binary of
/// every `tests/*.rs` and `tests/*/main.rs`, so only `tests/it/main.rs` may
/// be one; and a file under `tests/it/` that no `mod` line declares is
/// never compiled, its tests silently never run.
#[test]
fn the_tests_are_one_binary_and_every_file_under_it_is_a_module() {
    let tests = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let mut problems = Vec::new();
    for e in std::fs::read_dir(&tests).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if p.extension().is_some_and(|x| x == "rs") {
            problems.push(format!(
                "tests/{name} is a test binary of its own: make it a module under tests/it/"
            ));
        } else if p.join("main.rs").is_file() && name != "it" {
            problems.push(format!("tests/{name}/main.rs is a second test binary"));
        }
    }
    let it = tests.join("it");
    let mut files = Vec::new();
    rust_files(&it, &mut files);
    let declares = |parent: &Path, module: &str| {
        std::fs::read_to_string(parent).is_ok_and(|text| {
            text.lines().any(|l| {
                let l = l.trim_start();
                let l = l.strip_prefix("pub ").unwrap_or(l);
                l.strip_prefix("mod ")
                    .and_then(|rest| rest.strip_prefix(module))
                    .is_some_and(|rest| rest.starts_with(';'))
            })
        })
    };
    for f in &files {
        let rel = f.strip_prefix(&it).unwrap();
        if rel == Path::new("main.rs") {
            continue;
        }
        // `a/b.rs` is declared in `a/mod.rs`; `a/mod.rs` and `b.rs` in the
        // folder above (`main.rs` at the top).
        let (dir, module) = if f.file_name().unwrap() == "mod.rs" {
            let d = f.parent().unwrap();
            (d.parent().unwrap(), d.file_name().unwrap())
        } else {
            (f.parent().unwrap(), f.file_stem().unwrap())
        };
        let parent = if dir == it {
            it.join("main.rs")
        } else {
            dir.join("mod.rs")
        };
        let module = module.to_string_lossy();
        if !declares(&parent, &module) {
            problems.push(format!(
                "tests/it/{}: no `mod {module};` in {}, so it is never compiled",
                rel.display(),
                parent.strip_prefix(&tests).unwrap().display()
            ));
        }
    }
    assert!(
        files.len() > 40,
        "only {} files under tests/it",
        files.len()
    );
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
