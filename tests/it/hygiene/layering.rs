//! The library's layering (issues 19 and 40): no import circle between
//! library files (`file_level` below: a file uses another when a `use` or
//! an inline `crate::`, `super::`, `self::` or child-module path names an
//! item the other defines, re-exports followed to the defining file, as
//! `scripts/shape.py` reads it), no import cycle between top-level modules
//! of `src/`, and no `clap` in the library (src/ outside `src/cli` and
//! `src/main.rs`). Imports are read from `crate::` paths (`use
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
    source_files(false)
}

/// Every source file of the binary's `src/cli` (relative to the crate root)
/// and its text, without comments and test code.
fn cli_files() -> Vec<(String, String)> {
    source_files(true)
}

/// The library's files, or (`cli`) those of `src/cli`.
fn source_files(cli: bool) -> Vec<(String, String)> {
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
            // A `tests.rs` is a test module in a file of its own (`#[cfg(test)]
            // mod tests;`): test code, as the part of a file after its first
            // `#[cfg(test)]` is (`pose/retarget/tests.rs` drives clips from
            // `synth`, which the library's `pose` never imports).
            if rel.starts_with("cli/") != cli || rel == "main.rs" || rel.ends_with("/tests.rs") {
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
    let top = match rest.split_once('/') {
        Some((dir, _)) => dir.to_string(),
        None => rest.trim_end_matches(".rs").to_string(),
    };
    // `tools` and `util` are folders of independent modules (issue 40):
    // each child is a module of its own here.
    if GROUPS.contains(&top.as_str()) {
        let child = rest[top.len() + 1..].split('/').next().unwrap_or("");
        return Some(format!("{top}::{}", child.trim_end_matches(".rs")));
    }
    Some(top)
}

/// Top-level folders whose children are counted as separate modules.
const GROUPS: &[&str] = &["tools", "util"];

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
            let first = ident(after);
            if GROUPS.contains(&first.as_str()) {
                let child = ident(after[first.len()..].trim_start_matches("::"));
                out.insert(format!("{first}::{child}"));
            } else {
                out.insert(first);
            }
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
        g["db"].contains("mesh") && g["drive"].contains("db"),
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

/// File-level circles: which library file uses which, parsed with `syn`.
mod file_level {
    use proc_macro2::{Delimiter, TokenStream, TokenTree};
    use quote::ToTokens;
    use std::collections::{BTreeMap, BTreeSet};
    use std::path::Path;

    /// Circles outside issue 40's `shape` folders that other engineers are
    /// removing in parallel (rig map/structure, rig embed joints/landmarks):
    /// allowed until their branches merge; the lead empties this list then.
    /// Any other circle fails.
    pub const KNOWN_CIRCLES: &[&[&str]] = &[];

    type Module = Vec<String>;

    /// One `use` entry: re-exported (`pub use`)?, its path, the name it binds.
    struct Use {
        is_pub: bool,
        parts: Vec<String>,
        alias: String,
    }

    /// What one file defines, imports and names inline.
    #[derive(Default)]
    struct FileCode {
        defined: BTreeSet<String>,
        uses: Vec<Use>,
        /// Inline paths starting `crate`, `super`, `self` or a child module.
        paths: Vec<Vec<String>>,
    }

    pub struct Graph {
        files: BTreeMap<Module, String>,
        code: BTreeMap<Module, FileCode>,
    }

    fn flatten_use(
        tree: &syn::UseTree,
        prefix: &mut Vec<String>,
        out: &mut Vec<(Vec<String>, String)>,
    ) {
        match tree {
            syn::UseTree::Path(p) => {
                prefix.push(p.ident.to_string());
                flatten_use(&p.tree, prefix, out);
                prefix.pop();
            }
            syn::UseTree::Name(n) => {
                let name = n.ident.to_string();
                let mut parts = prefix.clone();
                if name != "self" {
                    parts.push(name);
                }
                if let Some(last) = parts.last().cloned() {
                    out.push((parts, last));
                }
            }
            syn::UseTree::Rename(r) => {
                let mut parts = prefix.clone();
                let name = r.ident.to_string();
                if name != "self" {
                    parts.push(name);
                }
                out.push((parts, r.rename.to_string()));
            }
            syn::UseTree::Glob(_) => {
                let mut parts = prefix.clone();
                parts.push("*".into());
                out.push((parts, "*".into()));
            }
            syn::UseTree::Group(g) => {
                for t in &g.items {
                    flatten_use(t, prefix, out);
                }
            }
        }
    }

    fn is_test_cfg(attrs: &[syn::Attribute]) -> bool {
        attrs.iter().any(|a| {
            a.path().is_ident("cfg")
                && a.meta.to_token_stream().to_string().replace(' ', "") == "cfg(test)"
        })
    }

    /// Reads the tokens of one file: definitions, `use` statements (at any
    /// depth) and inline paths.
    fn scan(tokens: TokenStream, kids: &BTreeSet<String>, out: &mut FileCode) {
        let tt: Vec<TokenTree> = tokens.into_iter().collect();
        let ident = |i: usize| match tt.get(i) {
            Some(TokenTree::Ident(x)) => Some(x.to_string()),
            _ => None,
        };
        let colons = |i: usize| {
            matches!((tt.get(i), tt.get(i + 1)), (Some(TokenTree::Punct(a)), Some(TokenTree::Punct(b)))
                if a.as_char() == ':' && b.as_char() == ':')
        };
        let mut i = 0;
        while i < tt.len() {
            match &tt[i] {
                TokenTree::Group(g) => {
                    // `#[...]` attributes (docs, cfgs) name no item.
                    let attr =
                        i > 0 && matches!(&tt[i - 1], TokenTree::Punct(p) if p.as_char() == '#');
                    if !(attr && g.delimiter() == Delimiter::Bracket) {
                        scan(g.stream(), kids, out);
                    }
                    i += 1;
                }
                TokenTree::Ident(id) if id == "use" => {
                    let is_pub = (i >= 1 && ident(i - 1).as_deref() == Some("pub"))
                        || (i >= 2
                            && matches!(&tt[i - 1], TokenTree::Group(g) if g.delimiter() == Delimiter::Parenthesis)
                            && ident(i - 2).as_deref() == Some("pub"));
                    let mut j = i + 1;
                    while j < tt.len()
                        && !matches!(&tt[j], TokenTree::Punct(p) if p.as_char() == ';')
                    {
                        j += 1;
                    }
                    let body: TokenStream = tt[i..=j.min(tt.len() - 1)].iter().cloned().collect();
                    if let Ok(u) = syn::parse2::<syn::ItemUse>(body) {
                        let mut flat = Vec::new();
                        flatten_use(&u.tree, &mut Vec::new(), &mut flat);
                        for (parts, alias) in flat {
                            out.uses.push(Use {
                                is_pub,
                                parts,
                                alias,
                            });
                        }
                    }
                    i = j + 1;
                }
                TokenTree::Ident(id) => {
                    let word = id.to_string();
                    let after_colons = i >= 2 && colons(i - 2);
                    if matches!(
                        word.as_str(),
                        "fn" | "struct"
                            | "enum"
                            | "trait"
                            | "type"
                            | "const"
                            | "static"
                            | "union"
                            | "macro_rules"
                    ) {
                        let k = if word == "macro_rules" { i + 2 } else { i + 1 };
                        if let Some(name) = ident(k) {
                            out.defined.insert(name);
                        }
                    }
                    let starts =
                        matches!(word.as_str(), "crate" | "super" | "self") || kids.contains(&word);
                    if starts && !after_colons && colons(i + 1) {
                        let mut path = vec![word];
                        let mut k = i + 1;
                        while colons(k) {
                            match ident(k + 2) {
                                Some(next) => path.push(next),
                                None => break,
                            }
                            k += 3;
                        }
                        if path.len() > 1 {
                            out.paths.push(path);
                        }
                        i = k;
                    } else {
                        i += 1;
                    }
                }
                _ => i += 1,
            }
        }
    }

    impl Graph {
        /// Every library file (src/ without src/cli and main.rs).
        pub fn read(src: &Path) -> Graph {
            Graph::read_files(src, super::library_files())
        }

        /// The files `sources` (crate-relative paths, as `library_files`
        /// gives them; the binary's `src/cli` resolves the same way, its
        /// `crate::` being `main.rs`).
        pub fn read_files(src: &Path, sources: Vec<(String, String)>) -> Graph {
            let mut files = BTreeMap::new();
            for (rel, _) in sources {
                let inner = rel.strip_prefix("src/").unwrap().trim_end_matches(".rs");
                let mut m: Module = inner.split('/').map(str::to_string).collect();
                if matches!(m.last().map(String::as_str), Some("mod" | "lib")) {
                    m.pop();
                }
                files.insert(m, rel);
            }
            let mut g = Graph {
                files,
                code: BTreeMap::new(),
            };
            for (m, rel) in &g.files {
                let text =
                    std::fs::read_to_string(src.join(rel.strip_prefix("src/").unwrap())).unwrap();
                let file = syn::parse_file(&text).unwrap_or_else(|e| panic!("{rel}: {e}"));
                let mut code = FileCode::default();
                let kids = g.children(m);
                for item in file.items {
                    let attrs = match &item {
                        syn::Item::Mod(x) => &x.attrs,
                        syn::Item::Fn(x) => &x.attrs,
                        syn::Item::Impl(x) => &x.attrs,
                        syn::Item::Use(x) => &x.attrs,
                        syn::Item::Const(x) => &x.attrs,
                        syn::Item::Struct(x) => &x.attrs,
                        _ => &Vec::new(),
                    };
                    if !is_test_cfg(attrs) {
                        scan(item.to_token_stream(), &kids, &mut code);
                    }
                }
                g.code.insert(m.clone(), code);
            }
            g
        }

        fn children(&self, m: &Module) -> BTreeSet<String> {
            self.files
                .keys()
                .filter(|k| k.len() == m.len() + 1 && k[..m.len()] == m[..])
                .map(|k| k[m.len()].clone())
                .collect()
        }

        /// A path as written in module `m`, made absolute; `None` if external.
        fn absolute(&self, m: &Module, parts: &[String]) -> Option<Module> {
            let first = parts.first()?;
            if first == "crate" {
                return Some(parts[1..].to_vec());
            }
            if first == "self" || first == "super" {
                let mut cur = m.clone();
                let mut k = 0;
                while k < parts.len() && (parts[k] == "self" || parts[k] == "super") {
                    if parts[k] == "super" {
                        cur.pop();
                    }
                    k += 1;
                }
                cur.extend_from_slice(&parts[k..]);
                return Some(cur);
            }
            if self.children(m).contains(first) {
                let mut cur = m.clone();
                cur.extend_from_slice(parts);
                return Some(cur);
            }
            None
        }

        /// The file that defines the item an absolute path names, following
        /// imports and re-exports.
        fn resolve(&self, segs: &[String], depth: usize) -> Module {
            let mut cur: Module = Vec::new();
            for (k, seg) in segs.iter().enumerate() {
                let mut next = cur.clone();
                next.push(seg.clone());
                if self.files.contains_key(&next) {
                    cur = next;
                    continue;
                }
                let Some(code) = self.code.get(&cur) else {
                    return cur;
                };
                if code.defined.contains(seg) || depth > 8 {
                    return cur;
                }
                if let Some(u) = code.uses.iter().find(|u| &u.alias == seg) {
                    return match self.absolute(&cur, &u.parts) {
                        Some(mut t) => {
                            t.extend_from_slice(&segs[k + 1..]);
                            self.resolve(&t, depth + 1)
                        }
                        None => cur,
                    };
                }
                for u in code.uses.iter().filter(|u| u.alias == "*") {
                    if let Some(target) = self.absolute(&cur, &u.parts[..u.parts.len() - 1]) {
                        let mut t = target.clone();
                        t.push(seg.clone());
                        let found = self.resolve(&t, depth + 1);
                        let defines = self
                            .code
                            .get(&found)
                            .is_some_and(|c| c.defined.contains(seg));
                        if found[..] != target[..found.len().min(target.len())] || defines {
                            return found;
                        }
                    }
                }
                return cur;
            }
            cur
        }

        /// File → the files it uses (library-relative paths).
        pub fn edges(&self) -> BTreeMap<String, BTreeSet<String>> {
            let mut out: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
            for (m, code) in &self.code {
                let from = &self.files[m];
                let entry = out.entry(from.clone()).or_default();
                let mut found = Vec::new();
                for u in code.uses.iter().filter(|u| !u.is_pub) {
                    if let Some(a) = self.absolute(m, &u.parts) {
                        found.push(self.resolve(&a, 0));
                    }
                }
                for p in &code.paths {
                    if let Some(a) = self.absolute(m, p) {
                        found.push(self.resolve(&a, 0));
                    }
                }
                for t in found {
                    if &t != m {
                        if let Some(to) = self.files.get(&t) {
                            entry.insert(to.clone());
                        }
                    }
                }
            }
            out
        }
    }

    /// Sets of files that reach each other (more than one file each).
    pub fn circles(g: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
        super::cycles(g)
    }
}

#[test]
fn no_import_circle_between_library_files() {
    let g = file_level::Graph::read(&src()).edges();
    // The reader sees known edges (guards against a parser that finds nothing).
    assert!(
        g["src/tools/inspect.rs"].contains("src/mesh/io/gltf/read.rs")
            && g["src/web/windows.rs"].contains("src/web/site.rs")
            && g["src/tools/inspect/other.rs"].contains("src/tools/inspect/json.rs"),
        "{g:?}"
    );
    let known: Vec<Vec<String>> = file_level::KNOWN_CIRCLES
        .iter()
        .map(|c| c.iter().map(|s| s.to_string()).collect())
        .collect();
    let found = file_level::circles(&g);
    let new: Vec<String> = found
        .iter()
        .filter(|c| !known.contains(c))
        .map(|c| {
            let edges: Vec<String> = c
                .iter()
                .flat_map(|a| {
                    g[a].iter()
                        .filter(|b| c.contains(b))
                        .map(move |b| format!("{a} uses {b}"))
                })
                .collect();
            format!("  circle: {}\n    {}", c.join(", "), edges.join("\n    "))
        })
        .collect();
    assert!(
        new.is_empty(),
        "import circles between library files (break them by moving what both need into a file of its own):\n{}",
        new.join("\n")
    );
    for c in known.iter().filter(|c| !found.contains(c)) {
        eprintln!("known circle gone: delete it from KNOWN_CIRCLES: {c:?}");
    }
}

/// The same check inside the binary's `src/cli` (a subcommand file that
/// reached a helper through a re-export of `cli/mod.rs`, which declares every
/// subcommand, made a circle of seven files).
#[test]
fn no_import_circle_between_cli_files() {
    let g = file_level::Graph::read_files(&src(), cli_files()).edges();
    // The reader sees known edges (guards against a parser that finds nothing).
    assert!(
        g["src/cli/app.rs"].contains("src/cli/batch.rs")
            && g["src/cli/batch.rs"].contains("src/cli/out.rs")
            && !g.contains_key("src/mesh/io/load.rs"),
        "{g:?}"
    );
    let found = file_level::circles(&g);
    assert!(
        found.is_empty(),
        "import circles between src/cli files (import the helper from its own file): {found:?}"
    );
}
