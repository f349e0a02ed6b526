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
