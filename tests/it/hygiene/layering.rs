//! The library's layering (issue 19): no import cycle between top-level
//! modules of `src/`, and no `clap` in the library (src/ outside `src/cli`
//! and `src/main.rs`). Imports are read from `crate::` paths (`use
//! crate::x::...`, `use crate::{x, y}`, inline `crate::x::f()`), comments
//! and `#[cfg(test)]` code (at the end of a file by house convention)
//! left out. `scripts/module_graph.py` prints the same graph.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Library files that still use `clap` (none: the CLI mirrors the library's
/// option enums in `src/cli/values.rs`). A new `clap` use fails.
const REMAINING_CLAP: &[&str] = &[];

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// Every library source file (relative to the crate root) and its text,
/// without comments and test code.
fn library_files() -> Vec<(String, String)> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let mut entries: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        entries.sort();
        for p in entries {
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|e| e == "rs") {
                out.push(p);
            }
        }
    }
    let root = src();
    let mut files = Vec::new();
    walk(&root, &mut files);
    files
        .into_iter()
        .filter_map(|p| {
            let rel = p
                .strip_prefix(&root)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            if rel.starts_with("cli/") || rel == "main.rs" {
                return None;
            }
            let text = std::fs::read_to_string(&p).unwrap();
            Some((format!("src/{rel}"), strip(&text)))
        })
        .collect()
}

/// `text` without `//` comments and without anything from `#[cfg(test)]` on.
fn strip(text: &str) -> String {
    let code = text.split("#[cfg(test)]").next().unwrap_or("");
    code.lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The top-level module a library file belongs to (`src/db/build.rs` → `db`,
/// `src/skeleton.rs` → `skeleton`); `None` for lib.rs.
fn module_of(rel: &str) -> Option<String> {
    let rest = rel.strip_prefix("src/")?;
    if rest == "lib.rs" {
        return None;
    }
    Some(match rest.split_once('/') {
        Some((dir, _)) => dir.to_string(),
        None => rest.trim_end_matches(".rs").to_string(),
    })
}

/// Top-level modules named by `crate::` paths in `code`.
fn imports(code: &str) -> BTreeSet<String> {
    let ident = |s: &str| -> String {
        s.trim_start()
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    let mut out = BTreeSet::new();
    let mut rest = code;
    while let Some(i) = rest.find("crate::") {
        let after = &rest[i + "crate::".len()..];
        if let Some(group) = after.strip_prefix('{') {
            // `crate::{a::b, c, d::{e, f}}`: the top-level names of the group.
            let (mut depth, mut item) = (0, String::new());
            for ch in group.chars() {
                match ch {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        out.insert(ident(&item));
                        item.clear();
                        continue;
                    }
                    _ => {}
                }
                if depth == 0 {
                    item.push(ch);
                }
            }
            out.insert(ident(&item));
        } else {
            out.insert(ident(after));
        }
        rest = after;
    }
    out.retain(|m| !m.is_empty() && m != "self");
    out
}

/// Which top-level module imports which.
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (rel, code) in library_files() {
        let Some(m) = module_of(&rel) else { continue };
        let mut deps = imports(&code);
        deps.remove(&m);
        g.entry(m).or_default().extend(deps);
    }
    g
}

/// Strongly connected components with more than one module (the cycles).
fn cycles(g: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    // Reachability by DFS from each module; a cycle class is the set of
    // modules that reach each other (the graph has ~20 nodes).
    let reach = |from: &str| -> BTreeSet<String> {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from.to_string()];
        while let Some(v) = stack.pop() {
            for w in g.get(&v).into_iter().flatten() {
                if seen.insert(w.clone()) {
                    stack.push(w.clone());
                }
            }
        }
        seen
    };
    let all: BTreeMap<&String, BTreeSet<String>> = g.keys().map(|k| (k, reach(k))).collect();
    let mut out: Vec<Vec<String>> = Vec::new();
    for (v, r) in &all {
        let class: Vec<String> = all
            .iter()
            .filter(|(w, rw)| r.contains(**w) && rw.contains(*v))
            .map(|(w, _)| (*w).clone())
            .collect();
        if class.len() > 1 && !out.contains(&class) {
            out.push(class);
        }
    }
    out
}

#[test]
fn no_import_cycle_between_top_level_modules() {
    let g = graph();
    // The reader sees the known edges (guards against a parser that finds nothing).
    assert!(
        g["db"].contains("mesh") && g["retarget"].contains("db"),
        "{g:?}"
    );
    let c = cycles(&g);
    let listing: String = g
        .iter()
        .map(|(m, d)| {
            format!(
                "  {m} -> {}\n",
                d.iter().cloned().collect::<Vec<_>>().join(", ")
            )
        })
        .collect();
    assert!(c.is_empty(), "import cycles {c:?}\n{listing}");
}

#[test]
fn the_cycle_finder_finds_a_cycle() {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    g.entry("mocap".into()).or_default().insert("rig".into());
    g.entry("rig".into()).or_default().insert("mocap".into());
    g.entry("mesh".into()).or_default();
    assert_eq!(
        cycles(&g),
        vec![vec!["mocap".to_string(), "rig".to_string()]]
    );
    let code = "use crate::{a::b, c, d::{e, f}};\nlet x = crate::g::h();";
    let names: Vec<String> = imports(code).into_iter().collect();
    assert_eq!(names, ["a", "c", "d", "g"]);
}

#[test]
fn no_clap_in_the_library_beyond_the_listed_enums() {
    let with_clap: BTreeSet<String> = library_files()
        .into_iter()
        .filter(|(_, code)| code.contains("clap"))
        .map(|(rel, _)| rel)
        .collect();
    let listed: BTreeSet<String> = REMAINING_CLAP.iter().map(|s| s.to_string()).collect();
    let new: Vec<_> = with_clap.difference(&listed).collect();
    assert!(
        new.is_empty(),
        "clap in the library (mirror the option in src/cli instead): {new:?}"
    );
    let gone: Vec<_> = listed.difference(&with_clap).collect();
    assert!(
        gone.is_empty(),
        "no clap left in {gone:?}: delete them from REMAINING_CLAP in tests/layering.rs"
    );
    if !with_clap.is_empty() {
        eprintln!("clap still derived in the library by: {with_clap:?}");
    }
}
