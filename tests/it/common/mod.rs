//! Shared helpers for integration tests: locating ../shared/data, fixture
//! folders, and running the built binary (`run_cli`, `CliRun`).
#![allow(dead_code)]

use std::path::{Path, PathBuf};

pub mod bvh;
pub mod decimate;
pub mod gaits;
pub mod keygraph;
pub mod skel;

/// Where the shared data folder is looked for: `$SURFMOTION_DATA`, else
/// `../shared/data` beside the package (the same rule as `build.rs`).
pub fn data_path() -> PathBuf {
    match std::env::var_os("SURFMOTION_DATA") {
        Some(p) => PathBuf::from(p),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data"),
    }
}

/// The shared data folder (`$SURFMOTION_DATA` or `../shared/data`). When it is
/// absent the test returns early with a message, except under `CI=true`, where
/// the absence is a failure.
///
/// Every `#[test]` that calls this (directly or through a helper in its file)
/// must carry the line
/// `#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]`
/// so that, without the data, the runner lists it as ignored with the reason
/// (`build.rs` sets `no_shared_data`); `tests/data_gate.rs` enforces it.
pub fn data_dir() -> Option<PathBuf> {
    let p = data_path();
    if p.join("README.md").is_file() {
        return Some(p);
    }
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!(
            "shared data not found at {} (CI=true: tests on real data must run)",
            p.display()
        );
    }
    eprintln!(
        "SKIPPED: shared data not found at {}; set SURFMOTION_DATA",
        p.display()
    );
    None
}

/// The shared data folder for a test that runs in full without it and only
/// adds real files when they are there (made-up inputs first, real ones as
/// extra cases). Such a test needs no `ignore` line; under `CI=true` a
/// missing folder still fails.
pub fn optional_data_dir() -> Option<PathBuf> {
    let p = data_path();
    if p.join("README.md").is_file() {
        return Some(p);
    }
    data_dir().or_else(|| {
        eprintln!("(the cases on real files are left out)");
        None
    })
}

/// Every file under `dir` with extension `ext`, sorted.
pub fn files_with_ext(dir: &std::path::Path, ext: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x.eq_ignore_ascii_case(ext)) {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// Path of the built binary.
pub fn bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_surfmotion"))
}

/// A synthetic samba database (CMU walk 02_01, run 02_03, 01_01 capped at
/// 8 s) built once per test binary with the `synth` command.
pub fn synthetic_db(d: &std::path::Path) -> PathBuf {
    use std::sync::OnceLock;
    static DB: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    DB.get_or_init(|| {
        let tmp = tempfile::tempdir().unwrap();
        let db = tmp.path().join("db");
        let m = d.join("mocap");
        let fixture = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures/samba.landmarks.json");
        run_ok(
            std::process::Command::new(env!("CARGO_BIN_EXE_surfmotion"))
                .args(["synth", "--mesh"])
                .arg(d.join("4d/samba/samba.obj"))
                .arg("--landmarks")
                .arg(&fixture)
                .arg("--mocap")
                .arg(m.join("cmu-amc/02/02_01.amc"))
                .arg(m.join("cmu-amc/02/02_03.amc"))
                .arg(m.join("cmu-bvh/01_01.bvh"))
                .args(["--seconds", "8", "-o"])
                .arg(&db),
        );
        (tmp, db)
    })
    .1
    .clone()
}

/// A folder for a fixture that a test binary builds once and keeps in a
/// `static` (statics are never dropped, so a `tempfile::TempDir` there
/// would be left behind in the system temp folder after every run):
/// `target/tmp/fixtures/NAME`, emptied first.
pub fn fixture_dir(name: &str) -> PathBuf {
    let p = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("fixtures")
        .join(name);
    let _ = std::fs::remove_dir_all(&p);
    std::fs::create_dir_all(&p).unwrap();
    p
}

/// The small synthetic database of the key-frame tests (CMU walk 02_01
/// and run 02_03 on the samba character, 25 fps, as `synth` writes it),
/// built into `fixture_dir(name)/db` from the data folder `d`.
pub fn walk_run_db(d: &Path, name: &str) -> PathBuf {
    let db = fixture_dir(name).join("db");
    let m = d.join("mocap/cmu-amc/02");
    let landmarks =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/samba.landmarks.json");
    let o = std::process::Command::new(bin())
        .args(["synth", "--mesh"])
        .arg(d.join("4d/samba/samba.obj"))
        .arg("--landmarks")
        .arg(&landmarks)
        .arg("--mocap")
        .arg(m.join("02_01.amc"))
        .arg(m.join("02_03.amc"))
        .args(["--fps", "25", "-o"])
        .arg(&db)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    db
}

/// A procedural database written to `db` as `synth` writes one: the
/// project's humanoid (meshed at `grid` metres) walking for 3 s and running
/// for 2 s at `fps`, named `name` (tests/procedural_pipeline.rs,
/// tests/retarget_ground.rs).
pub fn procedural_walk_run_database(db: &Path, name: &str, grid: f64, fps: f64) {
    use surfmotion::synth::Gait;
    gaits::write_gaits(
        db,
        &humanoid_character(grid),
        &[(Gait::Walk, 3.0), (Gait::Run, 2.0)],
        name,
        fps,
    );
}

/// The project's procedural humanoid meshed at `grid` metres, with its rig
/// embedded from its landmarks (`SynthCharacter::humanoid` at any grid).
pub fn humanoid_character(grid: f64) -> surfmotion::jobs::SynthCharacter {
    use surfmotion::embed::Embedding;
    use surfmotion::synth::humanoid::{humanoid_landmarks, humanoid_landmarks_json, humanoid_mesh};
    let rest = humanoid_mesh(grid);
    let rig = Embedding::new(&rest, &humanoid_landmarks(&rest), None).unwrap();
    surfmotion::jobs::SynthCharacter {
        rest,
        rig,
        landmarks_json: humanoid_landmarks_json().into_bytes(),
    }
}

/// The fields of a plausibility report (`surfmotion::tools::eval::Plausibility`
/// as `--json` writes it) that every `retarget` and `eval` result carries.
pub const PLAUSIBILITY_FIELDS: [&str; 7] = [
    "head_torso_deg",
    "foot_sliding",
    "ground",
    "knee_hyperextension_deg",
    "turned_over",
    "reference",
    "warnings",
];

/// Asserts that the plausibility report `p` (JSON) of `what` has every one
/// of [`PLAUSIBILITY_FIELDS`] and of `also`, none of them null.
pub fn assert_plausibility_fields(p: &serde_json::Value, what: &str, also: &[&str]) {
    for key in PLAUSIBILITY_FIELDS.iter().chain(also) {
        assert!(!p[key].is_null(), "{what}: no plausibility.{key}");
    }
}

/// Whether the npm package `package` is installed under `.ci/node_modules`
/// and `node` runs (`.ci/run` installs both). When not, the test should
/// return early: this prints why (`what` it would have done), except under
/// `CI=true`, where the absence is a failure.
pub fn npm_package(package: &str, what: &str) -> bool {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let have = root.join(".ci/node_modules").join(package).exists()
        && std::process::Command::new("node")
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success());
    if !have {
        assert!(
            !std::env::var("CI").is_ok_and(|v| v == "true"),
            "CI=true but {package} is not installed (.ci/run installs it)"
        );
        eprintln!("SKIPPED: run `npm install --prefix .ci` to {what}");
    }
    have
}

/// What a run of the built binary gave: exit code (`None` when killed by a
/// signal), standard output and error, and how long it took.
pub struct CliRun {
    /// Exit code; `None` if a signal ended the process.
    pub code: Option<i32>,
    /// Standard output, lossily decoded.
    pub stdout: String,
    /// Standard error, lossily decoded.
    pub stderr: String,
    /// Wall time of the run.
    pub elapsed: std::time::Duration,
}

/// Runs the built binary with `args` in `cwd` (the test's own folder when
/// `None`), `SURFMOTION_LOG` unset and `env` added; captures everything.
/// Runs `cmd` and requires exit 0 (the command and its stderr in the
/// failure message).
pub fn run_ok(cmd: &mut std::process::Command) -> std::process::Output {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{cmd:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

pub fn run_cli<S: AsRef<std::ffi::OsStr>>(
    args: &[S],
    cwd: Option<&std::path::Path>,
    env: &[(&str, &str)],
) -> CliRun {
    let mut cmd = std::process::Command::new(bin());
    cmd.args(args).env_remove("SURFMOTION_LOG");
    if let Some(d) = cwd {
        cmd.current_dir(d);
    }
    for (k, v) in env {
        cmd.env(k, v);
    }
    let t = std::time::Instant::now();
    let o = cmd.output().unwrap();
    CliRun {
        code: o.status.code(),
        stdout: String::from_utf8_lossy(&o.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&o.stderr).into_owned(),
        elapsed: t.elapsed(),
    }
}

/// A key-frame graph of one sequence of `n` frames walking `step` metres
/// a frame along +x, with the extra arcs `loops` (`from`, `to`, cost).
pub fn line_key_graph(
    n: usize,
    step: f64,
    loops: &[(usize, u32, f64)],
) -> surfmotion::keyframe::graph::KeyGraph {
    let centre: Vec<[f64; 2]> = (0..n).map(|f| [step * f as f64, 0.0]).collect();
    use surfmotion::graph::FlatFrame;
    let mut succ: Vec<Vec<(FlatFrame, f64)>> = (0..n)
        .map(|f| {
            if f + 1 < n {
                vec![(FlatFrame::from_index(f + 1), 0.0)]
            } else {
                Vec::new()
            }
        })
        .collect();
    for &(from, to, cost) in loops {
        succ[from].push((FlatFrame::new(to), cost));
    }
    surfmotion::keyframe::graph::KeyGraph::new(&succ, centre, vec![0; n])
}

/// [`run_cli`] without extra environment that must exit 0 (the panic
/// names the arguments and carries stderr).
pub fn cli_ok<S: AsRef<std::ffi::OsStr> + std::fmt::Debug>(
    args: &[S],
    cwd: Option<&std::path::Path>,
) -> CliRun {
    let r = run_cli(args, cwd, &[]);
    assert_eq!(r.code, Some(0), "{args:?}: {}", r.stderr);
    r
}

impl CliRun {
    /// What is wrong with this run as the answer to bad input, by the
    /// exit-code contract: exit 1 (not 2, a panic, nor a signal, an
    /// aborted allocation), no internal error, one line on stderr (a clap
    /// usage error: its first line, the reason), holding every one of
    /// `words` (case-insensitive). Empty when all is well.
    pub fn bad_input_problems(&self, words: &[&str]) -> Vec<String> {
        let mut problems = Vec::new();
        match self.code {
            Some(1) => {}
            Some(c) => problems.push(format!("exit {c}")),
            None => problems.push("killed by a signal".into()),
        }
        let lower = self.stderr.to_lowercase();
        if lower.contains("internal error") || lower.contains("memory allocation") {
            problems.push("internal error".into());
        }
        let lines: Vec<&str> = self
            .stderr
            .lines()
            .filter(|l| !l.trim().is_empty())
            .collect();
        let first = lines.first().copied().unwrap_or("").to_lowercase();
        let clap = first.starts_with("error: ");
        if lines.len() != 1 && !clap {
            problems.push(format!("{} lines on stderr, expected one", lines.len()));
        }
        let said = if clap { first } else { lower };
        for w in words {
            if !said.contains(&w.to_lowercase()) {
                problems.push(format!("no '{w}' in the message"));
            }
        }
        problems
    }

    /// Panics unless [`CliRun::bad_input_problems`] finds nothing; `what`
    /// names the case.
    pub fn assert_bad_input(&self, what: &str, words: &[&str]) {
        let p = self.bad_input_problems(words);
        assert!(
            p.is_empty(),
            "{what}: {} (exit {:?})\n    stderr: {}",
            p.join(", "),
            self.code,
            self.stderr.trim()
        );
    }
}

/// For a test that changes state every thread of the process reads (the
/// environment): whether this process is one it may change it in. The test
/// binary runs its tests on parallel threads, so in the ordinary run this
/// starts the binary again with only the test `module::test` (`--exact`,
/// one thread), requires that run to pass, and returns `false` (the caller
/// returns); in that child it returns `true`. `module` is the caller's
/// `module_path!()`.
pub fn alone_in_process(module: &str, test: &str) -> bool {
    const CHILD: &str = "SURFMOTION_TEST_ALONE";
    let module = module.split_once("::").map_or(module, |(_, m)| m);
    let name = format!("{module}::{test}");
    if std::env::var(CHILD).is_ok_and(|v| v == name) {
        return true;
    }
    let out = std::process::Command::new(std::env::current_exe().unwrap())
        .args([name.as_str(), "--exact", "--test-threads", "1"])
        .env(CHILD, &name)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && stdout.contains("1 passed"),
        "{name} alone in its own process: {}\n{stdout}{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    false
}

/// A BVH whose joint angles are `scale` times `text`'s (root translation
/// kept): a clip a character cannot follow, for tests that need a
/// plausibility warning now that `synth` characters are clean (issue 42).
pub fn scaled_angles_bvh(text: &str, scale: f64) -> String {
    let (head, motion) = text.split_once("MOTION\n").expect("a BVH with MOTION");
    let mut out = format!("{head}MOTION\n");
    for (i, l) in motion.lines().enumerate() {
        if i < 2 {
            out += &format!("{l}\n");
            continue;
        }
        let v: Vec<String> = l
            .split_whitespace()
            .enumerate()
            .map(|(k, x)| match k {
                0..3 => x.to_string(),
                _ => format!("{:.4}", scale * x.parse::<f64>().unwrap()),
            })
            .collect();
        out += &format!("{}\n", v.join(" "));
    }
    out
}

/// A canonical clip mirrored left to right (x negated, left and right
/// joints swapped: arms 5-7 with 8-10, legs 11-14 with 15-18): the other
/// foot swings, the other leg leads.
pub fn mirrored_clip(clip: &[surfmotion::pose::Pose]) -> Vec<surfmotion::pose::Pose> {
    use surfmotion::rig::Canonical;
    clip.iter()
        .map(|p| {
            let mut m = *p;
            for c in Canonical::ALL {
                let i = c.index();
                let j = match i {
                    5..=7 => i + 3,
                    8..=10 => i - 3,
                    11..=14 => i + 4,
                    15..=18 => i - 4,
                    _ => i,
                };
                m[j] = glam::DVec3::new(-p[i].x, p[i].y, p[i].z);
            }
            m
        })
        .collect()
}

/// The character the pose-kernel tests retarget onto: the rest pose of the
/// procedural walk (2 s at 30 fps), and its height (head over left toe).
pub fn walk_character() -> (surfmotion::pose::Pose, f64) {
    use surfmotion::rig::Canonical as C;
    let walk = surfmotion::synth::gait_clip(surfmotion::synth::Gait::Walk, 2.0, 30.0);
    let character = surfmotion::rig::detect_clip(&walk)
        .unwrap()
        .map
        .rest_pose(&walk)
        .unwrap();
    let h = character[C::Head.index()].y - character[C::LToe.index()].y;
    (character, h)
}
