//! The README's commands run as written, as doc-tests do for Rust: every
//! ```` ```sh ```` block is run with bash (`-eu -o pipefail`, so every command
//! must exit 0), in order, in one scratch folder laid out like a clone beside
//! the data: `../shared/data` is the shared data, `tests/fixtures` and
//! `mocap/` are the repository's, and `surfmotion` (also what
//! `cargo run --release --` becomes) is the binary under test. Blocks marked
//! ```` ```sh no-run ```` are illustrations (a cluster job, the test command
//! itself) and are kept few. Every repository path the README names must
//! exist, and every page of docs/ (the investigation history moved out of
//! the README) must be linked from it, with its own links resolving; a
//! link to a section (`#anchor`, in the README or a page) must land on a
//! heading.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// A fenced block of the README.
#[derive(Debug, PartialEq)]
struct Block {
    /// 1-based line of the opening fence.
    line: usize,
    /// The info string (`sh`, `sh no-run`, `toml`, ...; empty when none).
    info: String,
    body: String,
}

/// Every fenced block, including fences indented inside list items.
fn blocks(text: &str) -> Vec<Block> {
    let mut out = Vec::new();
    let mut lines = text.lines().enumerate();
    while let Some((i, l)) = lines.next() {
        let t = l.trim_start();
        let Some(info) = t.strip_prefix("```") else {
            continue;
        };
        let indent = l.len() - t.len();
        let mut body = String::new();
        for (_, l) in lines.by_ref() {
            if l.trim() == "```" {
                break;
            }
            body.push_str(l.get(indent..).unwrap_or(l.trim_start()));
            body.push('\n');
        }
        out.push(Block {
            line: i + 1,
            info: info.trim().to_string(),
            body,
        });
    }
    out
}

/// The blocks to run and the problems of the README's marking: a block of
/// surfmotion commands without the `sh` tag, a runnable block that calls
/// cargo for anything but `cargo run --release --`, too many no-run blocks.
fn plan(text: &str) -> (Vec<Block>, Vec<String>) {
    let mut run = Vec::new();
    let mut problems = Vec::new();
    let mut no_run = 0;
    for mut b in blocks(text) {
        let commands = b
            .body
            .lines()
            .any(|l| l.trim_start().starts_with("surfmotion ") || l.contains("cargo run"));
        match b.info.as_str() {
            "sh" => {
                b.body = b.body.replace("cargo run --release --", "surfmotion");
                if b.body.lines().any(|l| {
                    let code = l.split('#').next().unwrap_or("");
                    code.split_whitespace().any(|w| w == "cargo")
                }) {
                    problems.push(format!(
                        "README.md:{}: a runnable block calls cargo (only `cargo run --release --` \
                         is run, as the built binary); mark it `sh no-run`",
                        b.line
                    ));
                }
                run.push(b);
            }
            "sh no-run" => no_run += 1,
            "" if commands => problems.push(format!(
                "README.md:{}: a block of commands without a tag: make it ```sh (or ```sh no-run)",
                b.line
            )),
            _ => {}
        }
    }
    if no_run > 3 {
        problems.push(format!(
            "{no_run} blocks are `sh no-run`; keep illustrations few (at most 3)"
        ));
    }
    (run, problems)
}

/// A scratch folder laid out like a clone beside the shared data.
fn scratch(data: &Path) -> (tempfile::TempDir, PathBuf, String) {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let tmp = tempfile::tempdir().unwrap();
    let shared = tmp.path().join("shared");
    std::fs::create_dir_all(&shared).unwrap();
    std::os::unix::fs::symlink(data.canonicalize().unwrap(), shared.join("data")).unwrap();
    let work = tmp.path().join("surfmotion");
    for dir in ["tests/fixtures", "mocap"] {
        copy_dir(&repo.join(dir), &work.join(dir));
    }
    let bin = tmp.path().join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    std::os::unix::fs::symlink(common::bin(), bin.join("surfmotion")).unwrap();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    (tmp, work, path)
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &to.join(e.file_name()));
        } else {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn every_readme_command_runs_as_written() {
    let Some(d) = common::data_dir() else { return };
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).unwrap();
    let (run, problems) = plan(&text);
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    assert!(run.len() >= 5, "only {} runnable blocks found", run.len());
    let (_tmp, work, path) = scratch(&d);
    let all = Instant::now();
    for b in &run {
        let t = Instant::now();
        let mut child = Command::new("bash")
            .args(["-eu", "-o", "pipefail", "-x", "-c", &b.body])
            .current_dir(&work)
            .env("PATH", &path)
            .env_remove("SURFMOTION_DATA")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Drain stderr in a thread so a chatty command cannot block on a full pipe.
        let mut err = child.stderr.take().unwrap();
        let reader = std::thread::spawn(move || {
            let mut s = String::new();
            std::io::Read::read_to_string(&mut err, &mut s).ok();
            s
        });
        let limit = Duration::from_secs(600);
        let status = loop {
            if let Some(s) = child.try_wait().unwrap() {
                break Some(s);
            }
            if t.elapsed() > limit {
                child.kill().ok();
                child.wait().ok();
                break None;
            }
            std::thread::sleep(Duration::from_millis(50));
        };
        let stderr = reader.join().unwrap();
        let tail: Vec<&str> = stderr.lines().rev().take(15).collect();
        let tail: Vec<&str> = tail.into_iter().rev().collect();
        match status {
            Some(s) if s.success() => {}
            Some(s) => panic!(
                "README.md:{}: the block failed ({s}); the last command is the last `+` line:\n{}",
                b.line,
                tail.join("\n")
            ),
            None => panic!(
                "README.md:{}: the block ran over {limit:?}:\n{}",
                b.line,
                tail.join("\n")
            ),
        }
        eprintln!(
            "README.md:{}: ok in {:.1} s",
            b.line,
            t.elapsed().as_secs_f64()
        );
    }
    eprintln!(
        "{} README blocks in {:.1} s",
        run.len(),
        all.elapsed().as_secs_f64()
    );
}

#[test]
fn the_readme_plan_flags_untagged_and_cargo_blocks() {
    let text = "intro\n```sh\ncargo run --release -- demo\n```\n\
        ```sh no-run\ncargo test --release\n```\n\
        - item\n\n  ```sh\n  surfmotion inspect x.bvh   # a comment with cargo\n  ```\n\
        ```\nsurfmotion db info DB\n```\n\
        ```sh\ncargo bench --bench transfer\n```\n\
        ```toml\nname = \"samba\"\n```\n";
    let (run, problems) = plan(text);
    let bodies: Vec<&str> = run.iter().map(|b| b.body.as_str()).collect();
    assert_eq!(
        bodies,
        [
            "surfmotion demo\n",
            "surfmotion inspect x.bvh   # a comment with cargo\n",
            "cargo bench --bench transfer\n"
        ]
    );
    assert_eq!(run[1].line, 10);
    assert_eq!(problems.len(), 2, "{problems:#?}");
    assert!(problems[0].starts_with("README.md:13: a block of commands without a tag"));
    assert!(problems[1].starts_with("README.md:16: a runnable block calls cargo"));
}

/// The repository paths a Markdown text names: words starting with one of
/// the repository's top-level folders (`src/`, `tests/`, `docs/`, ...) after
/// a space, a backtick, `(` or `[` (so `$S/mocap/...`, a path in the shared
/// data, is not one), and the targets of relative links `](...)`. A path
/// ends at the first character that cannot be in one (`:`, a backtick, a
/// space, `)`, ...); a trailing `.` ends a sentence.
fn named_paths(text: &str) -> Vec<String> {
    const ROOTS: [&str; 9] = [
        ".ci/",
        "src/",
        "tests/",
        "docs/",
        "scripts/",
        "benches/",
        "examples/",
        "fuzz/",
        "mocap/",
    ];
    let path_char = |c: char| c.is_ascii_alphanumeric() || "_.-/".contains(c);
    let mut out = Vec::new();
    let bytes: Vec<char> = text.chars().collect();
    for (i, _) in bytes.iter().enumerate() {
        let before = if i == 0 { ' ' } else { bytes[i - 1] };
        let rest: String = bytes[i..].iter().take_while(|c| path_char(**c)).collect();
        let is_link = before == '(' && i >= 2 && bytes[i - 2] == ']';
        let starts = ROOTS.iter().any(|r| rest.starts_with(r));
        if (starts && (before.is_whitespace() || "`([".contains(before)))
            || (is_link && !rest.is_empty())
        {
            let p = rest.trim_end_matches('.').to_string();
            if is_link && (p.starts_with("http") || p.starts_with('#')) {
                continue;
            }
            out.push(p);
        }
    }
    out.sort();
    out.dedup();
    out
}

/// Every file or folder the README names exists in the repository, and so
/// does every relative link of the docs/ pages (relative to docs/): a
/// moved or renamed file leaves no dangling reference in the manual.
#[test]
fn every_path_the_readme_and_docs_name_exists() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(repo.join("README.md")).unwrap();
    let mut missing = Vec::new();
    let paths = named_paths(&readme);
    assert!(
        paths.len() > 40,
        "only {} paths found: {paths:?}",
        paths.len()
    );
    for p in &paths {
        if !repo.join(p).exists() {
            missing.push(format!("README.md names {p}"));
        }
    }
    let mut pages = 0;
    for e in std::fs::read_dir(repo.join("docs")).unwrap() {
        let f = e.unwrap().path();
        if f.extension().is_none_or(|x| x != "md") {
            continue;
        }
        pages += 1;
        let name = format!("docs/{}", f.file_name().unwrap().to_string_lossy());
        assert!(
            readme.contains(&format!("]({name})")),
            "{name} is not linked from README.md"
        );
        let text = std::fs::read_to_string(&f).unwrap();
        for target in link_targets(&text) {
            if target.starts_with("http") {
                continue;
            }
            let (file, anchor) = target.split_once('#').unwrap_or((&target, ""));
            let path = if file.is_empty() {
                f.clone()
            } else {
                repo.join("docs").join(file)
            };
            if !path.exists() {
                missing.push(format!("{name} links {target}"));
            } else if !anchor.is_empty() && !has_anchor(&path, anchor) {
                missing.push(format!("{name} links {target}: no such heading"));
            }
        }
    }
    // The README's own links with an anchor (its contents, and sections of
    // docs/ pages) land on a heading.
    for target in link_targets(&readme) {
        let Some((file, anchor)) = target.split_once('#') else {
            continue;
        };
        if target.starts_with("http") {
            continue;
        }
        let path = repo.join(if file.is_empty() { "README.md" } else { file });
        if !has_anchor(&path, anchor) {
            missing.push(format!("README.md links {target}: no such heading"));
        }
    }
    assert!(pages >= 5, "only {pages} docs pages");
    assert!(missing.is_empty(), "{}", missing.join("\n"));
}

/// The targets of a Markdown text's links `](...)`.
fn link_targets(text: &str) -> Vec<String> {
    text.match_indices("](")
        .map(|(i, _)| text[i + 2..].chars().take_while(|c| *c != ')').collect())
        .collect()
}

/// GitHub's anchor of a heading: lower case, spaces to `-`, every other
/// character but letters, digits, `-` and `_` dropped.
fn slug(heading: &str) -> String {
    let mut out = String::new();
    for c in heading.trim().chars() {
        if c.is_alphanumeric() || c == '-' || c == '_' {
            out.extend(c.to_lowercase());
        } else if c == ' ' {
            out.push('-');
        }
    }
    out
}

/// The anchors of a Markdown file's headings (outside fenced blocks).
fn anchors(text: &str) -> Vec<String> {
    let mut fenced = false;
    let mut out = Vec::new();
    for l in text.lines() {
        if l.trim_start().starts_with("```") {
            fenced = !fenced;
        } else if !fenced && l.starts_with('#') {
            out.push(slug(l.trim_start_matches('#')));
        }
    }
    out
}

fn has_anchor(file: &Path, anchor: &str) -> bool {
    std::fs::read_to_string(file).is_ok_and(|t| anchors(&t).iter().any(|a| a == anchor))
}

#[test]
fn anchors_are_githubs() {
    let text = "# surfmotion\n```sh\n# a comment\n```\n\
        ### Key-frame animation (Huang et al. 2015, Sec. 5.1)\n\
        ## Geometry kernels (`mesh::`)\n## Retargeting: what is matched and why\n";
    assert_eq!(
        anchors(text),
        [
            "surfmotion",
            "key-frame-animation-huang-et-al-2015-sec-51",
            "geometry-kernels-mesh",
            "retargeting-what-is-matched-and-why"
        ]
    );
}

#[test]
fn named_paths_finds_repository_paths_only() {
    let text = "see `src/rig/names.rs`, tests/db.rs. and $S/mocap/cmu-amc/02_01.amc \
        [a](docs/x.md) [b](https://example.org) (`tests/common::data_dir`) 1/2 src";
    assert_eq!(
        named_paths(text),
        [
            "docs/x.md",
            "src/rig/names.rs",
            "tests/common",
            "tests/db.rs"
        ]
    );
}

/// The README row whose first cell is `first`, split into its cells.
fn readme_row(text: &str, first: &str) -> Vec<String> {
    let row = text
        .lines()
        .find(|l| l.split('|').nth(1).is_some_and(|c| c.trim() == first))
        .unwrap_or_else(|| panic!("README: no table row `| {first} |`"));
    row.split('|').map(|c| c.trim().to_string()).collect()
}

/// The first number after `before` in `cell` (digits, `,` and `.`).
fn number_after(cell: &str, before: &str) -> f64 {
    let at = cell
        .find(before)
        .unwrap_or_else(|| panic!("`{cell}` has no `{before}`"))
        + before.len();
    let s: String = cell[at..]
        .trim_start()
        .chars()
        .take_while(|c| c.is_ascii_digit() || *c == ',' || *c == '.')
        .filter(|c| *c != ',')
        .collect();
    s.parse()
        .unwrap_or_else(|_| panic!("`{cell}`: no number after `{before}`"))
}

/// Issue 39 item 13 (README figures that drift): the skeleton table gave
/// samba's joint span as its "height" (1.47 m against the 1.745 m that
/// `rig embed` prints) and the codec table was for DEFLATE level 6 while
/// the default is 5. Each figure checked here is what the command prints
/// today: the statures against `rig embed --json`, the samba geometry
/// size against `web export` at the default level.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn readme_figures_match_what_the_commands_print() {
    let Some(d) = common::data_dir() else { return };
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("README.md")).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    for (name, capture) in [
        ("samba", "4d/samba/samba.obj"),
        ("crane", "4d/crane/crane.obj"),
    ] {
        let stated = number_after(&readme_row(&text, name)[3], "stature");
        let out = tmp.path().join(format!("{name}.rig.json"));
        let landmarks = root.join(format!("tests/fixtures/{name}.landmarks.json"));
        let run = common::run_ok(
            Command::new(common::bin())
                .args(["rig", "embed", "--json", "-o"])
                .arg(&out)
                .arg("--landmarks")
                .arg(&landmarks)
                .arg(d.join(capture)),
        );
        let json: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
        let height = json["height"].as_f64().expect("rig embed --json: height");
        assert!(
            (height - stated).abs() < 5e-4,
            "README says {name} stands {stated} m; rig embed says {height:.4} m"
        );
    }
    let level = surfmotion::web::codec::DEFAULT_LEVEL;
    let header = text
        .lines()
        .find(|l| l.starts_with("| data | frames × vertices | float32 |"))
        .expect("README: the codec table");
    assert!(
        header.contains(&format!("level {level} (default)")),
        "the codec table's bold column is not the default level {level}: {header}"
    );
    let row = readme_row(&text, "samba (real capture)");
    let stated = number_after(&row[5], "**");
    let site = tmp.path().join("site");
    let run = common::run_ok(
        Command::new(common::bin())
            .args(["web", "export", "--result"])
            .arg(d.join("4d/samba/samba.pc2"))
            .arg("-o")
            .arg(&site),
    );
    let said =
        String::from_utf8_lossy(&run.stdout).to_string() + &String::from_utf8_lossy(&run.stderr);
    let printed = number_after(&said, "geometry");
    assert_eq!(
        printed, stated,
        "README's samba geometry at level {level} is {stated} KB; web export printed: {said}"
    );
}
