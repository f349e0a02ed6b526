//! The README's commands run as written, as doc-tests do for Rust: every
//! ```` ```sh ```` block is run with bash (`-eu -o pipefail`, so every command
//! must exit 0), in order, in one scratch folder laid out like a clone beside
//! the data: `../shared/data` is the shared data, `tests/fixtures` and
//! `mocap/` are the repository's, and `surfmotion` (also what
//! `cargo run --release --` becomes) is the binary under test. Blocks marked
//! ```` ```sh no-run ```` are illustrations (a cluster job, the test command
//! itself) and are kept few.

mod common;

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
