//! Tests on ../shared/data never skip silently: every test that needs the data
//! is marked so that, without it, the runner lists it as ignored with the
//! reason (see `build.rs`), and the mark matches the folder on disk.

use crate::common;

use proc_macro2::{TokenStream, TokenTree};
use quote::ToTokens;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The line every test on the shared data carries.
const GATE: &str =
    r#"#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]"#;

/// One function of a test file.
struct Func {
    is_test: bool,
    gated: bool,
    /// Calls `data_dir()` itself.
    direct: bool,
    /// Names of the functions it calls (any `name(...)` in its body).
    calls: BTreeSet<String>,
}

/// Every `name(` in a token stream, macro bodies included.
fn called_names(ts: TokenStream, out: &mut BTreeSet<String>) {
    let mut prev: Option<String> = None;
    for tt in ts {
        match tt {
            TokenTree::Group(g) => {
                if g.delimiter() == proc_macro2::Delimiter::Parenthesis
                    && let Some(name) = prev.take()
                {
                    out.insert(name);
                }
                called_names(g.stream(), out);
                prev = None;
            }
            TokenTree::Ident(i) => prev = Some(i.to_string()),
            _ => prev = None,
        }
    }
}

fn collect(items: &[syn::Item], out: &mut BTreeMap<String, Func>) {
    for item in items {
        match item {
            syn::Item::Fn(f) => {
                let is_test = f.attrs.iter().any(|a| a.path().is_ident("test"));
                let gated = f
                    .attrs
                    .iter()
                    .any(|a| a.to_token_stream().to_string() == gate_tokens());
                let mut calls = BTreeSet::new();
                called_names(f.block.to_token_stream(), &mut calls);
                out.insert(
                    f.sig.ident.to_string(),
                    Func {
                        is_test,
                        gated,
                        direct: calls.contains("data_dir"),
                        calls,
                    },
                );
            }
            syn::Item::Mod(m) => {
                if let Some((_, items)) = &m.content {
                    collect(items, out);
                }
            }
            _ => {}
        }
    }
}

fn gate_tokens() -> String {
    let attr: syn::File = syn::parse_str(&format!("{GATE} fn f() {{}}")).unwrap();
    match &attr.items[0] {
        syn::Item::Fn(f) => f.attrs[0].to_token_stream().to_string(),
        _ => unreachable!(),
    }
}

/// The problems of one test file's source: tests that need the data (they
/// call `data_dir()`, or a function of the file that does) without the gate
/// line, and gated tests that need no data. Also returns how many tests are
/// gated.
fn check_source(file: &str, src: &str) -> (Vec<String>, usize) {
    let parsed = syn::parse_file(src).unwrap_or_else(|e| panic!("{file}: {e}"));
    let mut funcs = BTreeMap::new();
    collect(&parsed.items, &mut funcs);
    // Functions that need the data: direct callers, then their callers.
    let mut needs: BTreeSet<String> = funcs
        .iter()
        .filter(|(_, f)| f.direct)
        .map(|(n, _)| n.clone())
        .collect();
    loop {
        let more: Vec<String> = funcs
            .iter()
            .filter(|(n, f)| !needs.contains(*n) && f.calls.iter().any(|c| needs.contains(c)))
            .map(|(n, _)| n.clone())
            .collect();
        if more.is_empty() {
            break;
        }
        needs.extend(more);
    }
    let mut problems = Vec::new();
    let mut gated = 0;
    for (name, f) in &funcs {
        let need = needs.contains(name);
        if f.is_test && need && !f.gated {
            problems.push(format!(
                "{file}: test `{name}` needs the shared data (calls data_dir()) but lacks the line\n    {GATE}"
            ));
        }
        if f.gated && !(f.is_test && need) {
            problems.push(format!(
                "{file}: `{name}` carries the shared-data ignore line but does not need the data"
            ));
        }
        gated += usize::from(f.gated && f.is_test);
    }
    (problems, gated)
}

#[test]
fn every_test_on_shared_data_is_reported_as_ignored_without_it() {
    // Every module of the test binary (`tests/it/**.rs`); the helpers in
    // `common` hold no test.
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/it");
    let mut problems = Vec::new();
    let mut gated = 0;
    let mut files = 0;
    for p in common::files_with_ext(&dir, "rs") {
        let name = p.strip_prefix(&dir).unwrap().to_string_lossy().into_owned();
        if name.starts_with("common/") {
            continue;
        }
        let src = std::fs::read_to_string(&p).unwrap();
        let (pr, g) = check_source(&name, &src);
        problems.extend(pr);
        gated += g;
        files += 1;
    }
    assert!(
        problems.is_empty(),
        "{} problem(s):\n{}",
        problems.len(),
        problems.join("\n")
    );
    // The scan saw the suite (not an empty folder or a parser that found
    // nothing): at the time of writing 57 tests in 18 files need the data.
    assert!(files >= 18 && gated >= 50, "{files} files, {gated} gated");
    eprintln!("{gated} tests on shared data in {files} files, all marked");
}

#[test]
fn the_scan_catches_unmarked_tests_direct_or_through_a_helper() {
    let src = format!(
        r#"
        fn helper() -> u32 {{ let d = common::data_dir(); 1 }}
        fn unrelated() {{}}
        #[test] fn direct() {{ let Some(d) = common::data_dir() else {{ return }}; }}
        #[test] fn through_helper() {{ assert_eq!(helper(), 1); }}
        #[test] fn in_a_macro() {{ println!("{{:?}}", common::data_dir()); }}
        #[test] {GATE} fn marked() {{ helper(); }}
        #[test] {GATE} fn marked_needlessly() {{ unrelated(); }}
        #[test] fn optional() {{ let _ = common::optional_data_dir(); }}
        #[test] fn no_data() {{ let s = "data_dir()"; }}
        mod inner {{ #[test] fn nested() {{ super::helper(); }} }}
        "#
    );
    let (problems, gated) = check_source("t.rs", &src);
    let named: Vec<&str> = problems
        .iter()
        .map(|p| p.split('`').nth(1).unwrap())
        .collect();
    assert_eq!(
        named,
        [
            "direct",
            "in_a_macro",
            "marked_needlessly",
            "nested",
            "through_helper"
        ],
        "{problems:#?}"
    );
    assert_eq!(gated, 2);
}

#[test]
fn data_tests_are_ignored_exactly_when_the_data_is_missing() {
    let path = common::data_path();
    let present = path.join("README.md").is_file();
    let ci = std::env::var("CI").is_ok_and(|v| v == "true");
    let ignored = cfg!(no_shared_data);
    if ignored && present {
        panic!(
            "the shared data at {} appeared after this crate was built, so the tests on it \
             are still marked ignored (cargo cannot watch for a folder that does not exist \
             without rebuilding on every run): `touch build.rs` and rerun",
            path.display()
        );
    }
    if ignored && ci {
        panic!("CI=true but the build marked the data tests ignored: `touch build.rs` and rerun");
    }
    assert_eq!(ignored, !present && !ci, "data at {}", path.display());
}
