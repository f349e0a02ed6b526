//! Parametric motion (Casas et al. 2013, Sec. 3): hybrid blending,
//! parameter maps, online transitions, the controller and `play`.
//!
//! The database is made here from the project's own procedural clips
//! (walk 1.4 m/s, run 3.2 m/s, a walk along a 2 m circle) on the demo
//! humanoid, so the parameters are known and no data is needed; the real
//! samba capture checks blending accuracy.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;
use surfmotion::jobs::SynthCharacter;
use surfmotion::mesh::blend::Blender;
use surfmotion::parametric::hybrid::{HybridBlend, HybridOptions};
use surfmotion::parametric::params::measure;
use surfmotion::parametric::store::load_or_build;
use surfmotion::parametric::{Control, Controller, Motion, MotionOptions, Parameter};
use surfmotion::synth::Gait;

/// A small database of the demo humanoid walking, running and turning
/// (3 s each), with two spaces; built once per test binary.
fn database() -> PathBuf {
    use std::sync::OnceLock;
    static DB: OnceLock<(PathBuf, PathBuf)> = OnceLock::new();
    DB.get_or_init(|| {
        let tmp = common::fixture_dir("parametric-gaits");
        let db = tmp.join("db");
        common::gaits::gaits_database(
            &db,
            &SynthCharacter::humanoid().unwrap(),
            &[Gait::Walk, Gait::Run, Gait::Turn],
            "gaits",
            &[
                ("locomotion", &["walk", "run"], &["speed", "turn"]),
                ("turning", &["walk", "turn"], &["turn"]),
            ],
        );
        (tmp, db)
    })
    .1
    .clone()
}

fn motion() -> &'static Motion {
    use std::sync::OnceLock;
    static M: OnceLock<Motion> = OnceLock::new();
    M.get_or_init(|| {
        load_or_build(&database(), &MotionOptions::default(), false)
            .unwrap()
            .0
    })
}

/// Largest vertex distance between two frames.
fn max_dist(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

/// Checks a hybrid blend: exact at every reference and phase; within `ε`
/// of the true non-linear blend at every weight on a 0.05 grid and every
/// phase sample. Returns the largest error between references.
fn check_hybrid(h: &HybridBlend, blender: &Blender, eps: f64) -> f64 {
    let n = h.n;
    let mut out = vec![[0.0; 3]; n];
    let mut truth = vec![[0.0; 3]; n];
    let mut ws = blender.workspace();
    let frame = |b: usize, k: usize| -> Vec<[f64; 3]> {
        h.blocks[b][k * n * 3..(k + 1) * n * 3]
            .chunks_exact(3)
            .map(|c| [c[0] as f64, c[1] as f64, c[2] as f64])
            .collect()
    };
    for (a, p) in h.pairs.iter().enumerate() {
        for (&w, &b) in p.weights.iter().zip(&p.blocks) {
            for k in 0..h.grid {
                h.eval(a as f64 + w, k as f64, &mut out);
                assert_eq!(
                    max_dist(&out, &frame(b, k)),
                    0.0,
                    "reference {w} of pair {a}, phase {k}"
                );
            }
        }
    }
    let mut worst: f64 = 0.0;
    for a in 0..h.pairs.len() {
        for k in 0..h.grid {
            let ga = blender.decompose(&frame(a, k), &mut ws);
            let gb = blender.decompose(&frame(a + 1, k), &mut ws);
            for i in 1..20 {
                let w = i as f64 * 0.05;
                blender.blend(&ga, &gb, w, &mut truth, &mut ws);
                h.eval(a as f64 + w, k as f64, &mut out);
                let e = max_dist(&out, &truth);
                assert!(
                    e <= eps,
                    "pair {a}, weight {w}, phase {k}: {:.2} mm > ε",
                    e * 1e3
                );
                worst = worst.max(e);
            }
        }
    }
    worst
}

#[test]
fn hybrid_blending_is_exact_at_references_and_within_epsilon_between() {
    let m = motion();
    let blender = Blender::new(&m.topology).unwrap();
    for s in &m.spaces {
        let worst = check_hybrid(s.blend(), &blender, s.epsilon());
        eprintln!(
            "{}: {} intermediate references, worst {:.2} mm (ε {:.0} mm), {} bytes",
            s.name(),
            s.blend().intermediate_count(),
            worst * 1e3,
            s.epsilon() * 1e3,
            s.blend().correction_bytes()
        );
    }
    // Walk and run differ enough that linear blending alone misses ε.
    let loco = &m.spaces[m.space_index("locomotion").unwrap()];
    assert!(loco.blend().intermediate_count() >= 1);
}

/// The real samba capture: frames 0-9 against frames 60-69 as two
/// "sequences" (very different poses), blended with ε = 5 mm.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn hybrid_blending_on_the_samba_capture_is_within_epsilon() {
    let Some(d) = common::data_dir() else { return };
    let seq = surfmotion::mesh::io::load_sequence(
        &d.join("4d/samba/samba.pc2").to_string_lossy(),
        &Default::default(),
    )
    .unwrap();
    let n = seq.mesh().vertex_count();
    let k = 6;
    let block = |start: usize| -> Vec<f32> {
        (0..k)
            .flat_map(|i| {
                seq.frame(start + 2 * i)
                    .iter()
                    .flat_map(|p| p.map(|x| x as f32))
            })
            .collect()
    };
    let blender = Blender::new(seq.mesh()).unwrap();
    let h = HybridBlend::build(
        vec![block(0), block(60)],
        n,
        k,
        &blender,
        &HybridOptions::default(),
    );
    let worst = check_hybrid(&h, &blender, 0.005);
    eprintln!(
        "samba: references {:?}, worst {:.2} mm, {} bytes",
        h.pairs[0].weights,
        worst * 1e3,
        h.correction_bytes()
    );
}

#[test]
fn inverse_map_round_trips_and_the_controller_achieves_it() {
    let m = motion();
    let loco = m.space_index("locomotion").unwrap();
    let turning = m.space_index("turning").unwrap();
    for (s, idx, tol) in [(loco, 0, 0.01), (turning, 1, 0.5)] {
        let sp = &m.spaces[s];
        let map = sp.axis().unwrap();
        let [lo, hi] = map.range;
        for i in 0..=10 {
            let p = lo + (hi - lo) * i as f64 / 10.0;
            let (u, clamped) = map.inverse(p);
            assert!(!clamped);
            let back = measure(sp.steps(), u, m.fps)[idx];
            let e = if idx == 0 {
                (back - p).abs() / p
            } else {
                (back - p).abs()
            };
            assert!(e <= tol, "{}: {p} → w {u} → {back}", sp.name());
        }
    }
    // Known parameters: the procedural walk is 1.4 m/s on a 1.75 m
    // skeleton, the run 3.2 m/s; the turn 0.7 rad/s (40°/s).
    let sp = &m.spaces[loco];
    let [lo, hi] = sp.axis().unwrap().range;
    assert!(
        lo > 0.8 && lo < 1.6 && hi > 2.0 && hi < 3.6,
        "speed range {lo}..{hi}"
    );
    let tr = m.spaces[turning].axis().unwrap().range;
    assert!(
        tr[0].abs() < 1.0 && (tr[1] - 40.1).abs() < 3.0,
        "turn range {tr:?}"
    );
    // Through the controller: asked speed held for whole cycles, achieved
    // within 3 %.
    for p in [lo + 0.1 * (hi - lo), 0.5 * (lo + hi), hi - 0.05 * (hi - lo)] {
        let mut c = Controller::new(m, loco);
        c.control(&Control {
            speed: Some(p),
            ..Default::default()
        });
        for _ in 0..60 {
            c.advance();
        }
        let (r0, p0) = (c.root(), c.phase());
        let mut path = 0.0;
        let mut last = r0;
        let mut frames = 0;
        let mut wraps = 0;
        let mut prev = p0;
        while wraps < 4 {
            c.advance();
            frames += 1;
            path += (c.root() - last).length();
            last = c.root();
            if c.phase() < prev {
                wraps += 1;
            }
            prev = c.phase();
        }
        let speed = path / (frames as f64 / m.fps);
        assert!((speed - p).abs() <= 0.03 * p, "asked {p}, achieved {speed}");
    }
}

#[test]
fn a_transition_never_starts_before_the_request_and_its_path_is_valid() {
    let m = motion();
    let loco = m.space_index("locomotion").unwrap();
    let turning = m.space_index("turning").unwrap();
    for request in [5usize, 17, 40] {
        let mut c = Controller::new(m, loco);
        c.control(&Control {
            speed: Some(2.0),
            ..Default::default()
        });
        for _ in 0..request {
            c.advance();
        }
        let (u, phase) = (c.weight(), c.phase());
        let t0 = std::time::Instant::now();
        c.control(&Control {
            space: Some(turning),
            turn: Some(20.0),
            ..Default::default()
        });
        let decision = t0.elapsed().as_secs_f64();
        let rec = c.transitions.last().unwrap().clone();
        assert!(rec.start_frame >= rec.request_frame && rec.request_frame == request);
        assert!(rec.end_frame >= rec.start_frame);
        // The source path plays the source from the request's state.
        let src = &m.spaces[loco];
        let mut ph = phase;
        for &s in &rec.source_path {
            assert_eq!(s, (ph.round() as usize) % src.grid());
            ph = src.play_phase(u, ph, 1.0).0;
        }
        assert!(rec.entry < m.spaces[turning].grid());
        // Play through: the space switches at the end, and from there the
        // target plays on phase by phase.
        let mut frames = 0;
        while c.space() != turning {
            assert!(c.frame() < rec.end_frame, "no switch by the recorded end");
            c.advance();
            frames += 1;
            assert!(frames < 200);
        }
        assert_eq!(c.frame(), rec.end_frame);
        let tgt = &m.spaces[turning];
        let mut p = c.phase();
        for _ in 0..40 {
            let expect = tgt.play_phase(c.weight(), p, 1.0).0;
            c.advance();
            assert!(
                (c.phase() - expect).abs() < 1e-9,
                "{} vs {expect}",
                c.phase()
            );
            p = c.phase();
        }
        eprintln!(
            "request {request}: start {}, end {}, latency {:.3} s, similarity {:.3}, cost {:.3}, decision {:.1} µs (measured outside {:.1} µs)",
            rec.start_frame,
            rec.end_frame,
            rec.latency,
            rec.similarity,
            rec.cost,
            rec.decision_seconds * 1e6,
            decision * 1e6
        );
    }
}

fn play(db: &Path, script: &str, dir: &Path) -> std::process::Output {
    let s = dir.join("control.json");
    std::fs::write(&s, script).unwrap();
    Command::new(common::bin())
        .args(["play", "--db"])
        .arg(db)
        .arg("--script")
        .arg(&s)
        .arg("-o")
        .arg(dir.join("out.pc2"))
        .arg("--report")
        .arg(dir.join("r.json"))
        .output()
        .unwrap()
}

#[test]
fn an_unreachable_speed_clamps_to_the_range_and_says_so() {
    let db = database();
    let tmp = tempfile::tempdir().unwrap();
    let out = play(
        &db,
        r#"[{"t": 0, "space": "locomotion", "speed": 50}]"#,
        tmp.path(),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("speed 50 m/s is outside the valid range") && stderr.contains("clamped to"),
        "{stderr}"
    );
    // Said once, on stderr as the README says (issue 39, item 9: it went
    // to stdout; two copies were the defect `play_notices_are_printed_once`
    // guards).
    assert_eq!(stderr.matches("clamped to").count(), 1, "{stderr}");
    assert!(!stdout.contains("clamped to"), "{stdout}");
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("r.json")).unwrap()).unwrap();
    assert_eq!(r["notices"][0]["notice"]["kind"], "clamped");
    let hi = r["notices"][0]["notice"]["range"][1].as_f64().unwrap();
    let last = r["per_second"].as_array().unwrap().last().unwrap()["speed"]
        .as_f64()
        .unwrap();
    assert!(
        last <= hi * 1.03 && last >= hi * 0.9,
        "achieved {last}, range max {hi}"
    );
    let seq = surfmotion::mesh::io::load_sequence(
        &tmp.path().join("out.pc2").to_string_lossy(),
        &Default::default(),
    )
    .unwrap();
    assert_eq!(seq.frame_count(), 60);
}

#[test]
fn malformed_spaces_and_scripts_give_one_line_errors() {
    let db = database();
    let tmp = tempfile::tempdir().unwrap();
    for (script, expect) in [
        ("not json", "not JSON"),
        (r#"{"t": 0}"#, "expected a JSON list"),
        ("[]", "no requests"),
        (r#"[{"speed": 1}]"#, "request 0: no \"t\""),
        (r#"[{"t": 0, "sped": 1}]"#, "unknown key \"sped\""),
        (r#"[{"t": 0, "space": "swim"}]"#, "no space 'swim'"),
        (r#"[{"t": 2}, {"t": 1}]"#, "request 1: t = 1 is before"),
        (r#"[{"t": -1}]"#, "t = -1"),
        (r#"[{"t": 0, "speed": "fast"}]"#, "expected a number"),
        (r#"[{"t": 0, "space": 3}]"#, "expected a space's name"),
    ] {
        let out = play(&db, script, tmp.path());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{script}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{script}: {stderr}");
        assert!(
            stderr.contains(expect) && stderr.contains("control.json"),
            "{script}: {stderr}"
        );
    }
    // Malformed [[space]] entries: a copy of the database with each.
    let base = std::fs::read_to_string(db.join("character.toml")).unwrap();
    let head = &base[..base.find("[[space]]").unwrap()];
    for (space, expect) in [
        (
            "[[space]]\nname = \"x\"\nsequences = [\"walk\"]\nspeed = 1\n",
            "unknown field",
        ),
        (
            "[[space]]\nname = \"x\"\nsequences = [\"swim\"]\n",
            "no sequence 'swim'",
        ),
        (
            "[[space]]\nname = \"x\"\nsequences = [\"walk\"]\nparameters = [\"height\"]\n",
            "unknown parameter 'height'",
        ),
        (
            "[[space]]\nname = \"x\"\nsequences = [\"walk\", \"run\"]\nparameters = [\"turn\", \"speed\"]\n",
            "speed must be the first",
        ),
        (
            "[[space]]\nname = \"x\"\nsequences = []\n",
            "sequences is empty",
        ),
        (
            "[[space]]\nname = \"x\"\nsequences = [\"walk\"]\n[[space]]\nname = \"x\"\nsequences = [\"run\"]\n",
            "two spaces are called 'x'",
        ),
        (
            "[[space]]\nname = \"x\"\nsequences = [\"walk\"]\nepsilon_mm = -1\n",
            "epsilon_mm = -1",
        ),
        // The straight and the circle walk have one speed: not a speed space.
        (
            "[[space]]\nname = \"x\"\nsequences = [\"walk\", \"turn\"]\nparameters = [\"speed\"]\n",
            "spans only",
        ),
    ] {
        let d = tmp.path().join("bad");
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        for f in [
            "topology.obj",
            "landmarks.json",
            "walk.pc2",
            "run.pc2",
            "turn.pc2",
        ] {
            std::fs::copy(db.join(f), d.join(f)).unwrap();
        }
        std::fs::write(d.join("character.toml"), format!("{head}{space}")).unwrap();
        let out = play(&d, r#"[{"t": 0}]"#, tmp.path());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{space}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{space}: {stderr}");
        assert!(
            stderr.contains(expect) && stderr.contains("character.toml"),
            "{space}: {stderr}"
        );
    }
}

/// Regression (issue 39, item 9): `play` on a database that declares no
/// `[[space]]` said `unknown key "speed" (expected t, space)`, blaming the
/// script; it says the database declares no space and how to add one.
#[test]
fn play_on_a_database_without_spaces_names_the_database() {
    let db = database();
    let tmp = tempfile::tempdir().unwrap();
    let base = std::fs::read_to_string(db.join("character.toml")).unwrap();
    let d = tmp.path().join("nospace");
    std::fs::create_dir_all(&d).unwrap();
    for f in [
        "topology.obj",
        "landmarks.json",
        "walk.pc2",
        "run.pc2",
        "turn.pc2",
    ] {
        std::fs::copy(db.join(f), d.join(f)).unwrap();
    }
    std::fs::write(
        d.join("character.toml"),
        &base[..base.find("[[space]]").unwrap()],
    )
    .unwrap();
    for script in [
        r#"[{"t": 0, "speed": 1.2}]"#,
        r#"[{"t": 0, "space": "locomotion", "speed": 1.2, "turn": 10}]"#,
        r#"[{"t": 0}]"#,
    ] {
        let out = play(&d, script, tmp.path());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{script}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{script}: {stderr}");
        assert!(
            stderr.contains("character.toml")
                && stderr.contains("declares no [[space]]")
                && stderr.contains("sequences = [\"walk\", \"run\"]")
                && !stderr.contains("unknown key"),
            "{script}: {stderr}"
        );
    }
}

#[test]
fn the_cache_is_reused_and_a_damaged_one_rebuilt() {
    let db = database();
    let _ = motion();
    let (_, cached) = load_or_build(&db, &MotionOptions::default(), false).unwrap();
    assert!(cached);
    let p = surfmotion::parametric::store::cache_path(&db);
    let bytes = std::fs::read(&p).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let copy = tmp.path().join("db");
    std::fs::create_dir_all(copy.join("cache")).unwrap();
    for f in [
        "character.toml",
        "topology.obj",
        "landmarks.json",
        "walk.pc2",
        "run.pc2",
        "turn.pc2",
    ] {
        std::fs::copy(db.join(f), copy.join(f)).unwrap();
    }
    // Truncated: rebuilt, not trusted.
    std::fs::write(
        surfmotion::parametric::store::cache_path(&copy),
        &bytes[..bytes.len() - 7],
    )
    .unwrap();
    let (m, cached) = load_or_build(&copy, &MotionOptions::default(), false).unwrap();
    assert!(!cached);
    assert_eq!(m.spaces.len(), 2);
    assert!(Parameter::parse("speed").is_some());
}

/// `bytes` of a parametric cache with its JSON header changed by `f` and
/// its key kept.
fn tampered(bytes: &[u8], f: impl Fn(&mut serde_json::Value)) -> Vec<u8> {
    let hl = u64::from_le_bytes(bytes[16..24].try_into().unwrap()) as usize;
    let mut h: serde_json::Value = serde_json::from_slice(&bytes[24..24 + hl]).unwrap();
    f(&mut h);
    let h = serde_json::to_vec(&h).unwrap();
    let mut out = bytes[..16].to_vec();
    out.extend_from_slice(&(h.len() as u64).to_le_bytes());
    out.extend_from_slice(&h);
    out.extend_from_slice(&bytes[24 + hl..]);
    out
}

/// Issue 40 (validated constructors): a motion space is made only through
/// `MotionSpace::new`, which checks that its parts agree. Every space of
/// the gaits model goes back through it from its serialised parts (the
/// cache's header) unchanged; each kind of disagreement — a root track
/// missing, a track off the phase grid, a blend on another grid, a block
/// cut short, a pair naming a block the blend lacks, weights out of
/// order, a parameter without its inverse map, a non-finite measurement —
/// is refused with what disagrees, for every space.
#[test]
fn a_motion_space_is_made_only_from_parts_that_agree() {
    use surfmotion::parametric::{MotionSpace, motion_space::SpaceParts};
    type Tamper = fn(&mut SpaceParts, &mut HybridBlend);
    let parts_of = |s: &MotionSpace| -> SpaceParts {
        serde_json::from_value(serde_json::to_value(s).unwrap()).unwrap()
    };
    let cases: [(&str, Tamper, &str); 8] = [
        (
            "a root track missing",
            |p, _| p.steps.truncate(0),
            "root tracks",
        ),
        (
            "a track off the grid",
            |p, _| p.steps[0].duration.truncate(1),
            "root tracks",
        ),
        ("a blend on another grid", |_, b| b.grid += 1, "blend"),
        ("a block cut short", |_, b| b.blocks[0].truncate(3), "blend"),
        (
            "a pair naming a missing block",
            |p, b| {
                let last = p.pairs[0].blocks.len() - 1;
                p.pairs[0].blocks[last] = 1 << 20;
                b.pairs = p.pairs.clone();
            },
            "blend",
        ),
        (
            "weights out of order",
            |p, _| p.pairs[0].weights.reverse(),
            "reference weights",
        ),
        (
            "a parameter without its map",
            |p, _| p.axis = None,
            "inverse map",
        ),
        (
            "a measurement not finite",
            |p, _| p.measured[0][1] = f64::NAN,
            "not finite",
        ),
    ];
    for s in &motion().spaces {
        assert!(!s.parameters().is_empty() && !s.sequences().is_empty());
        let again = MotionSpace::new(parts_of(s), s.blend().clone()).unwrap();
        assert_eq!(
            &again,
            s,
            "space '{}' changed on its way through new()",
            s.name()
        );
        for (what, tamper, words) in &cases {
            let (mut p, mut b) = (parts_of(s), s.blend().clone());
            tamper(&mut p, &mut b);
            match MotionSpace::new(p, b) {
                Ok(_) => panic!("space '{}', {what}: accepted", s.name()),
                Err(why) => assert!(why.contains(words), "space '{}', {what}: {why}", s.name()),
            }
        }
    }
}

/// Regression (issue 46, items 6 and 12): a `parametric.bin` whose header
/// said block index 10¹², or a transition depth of 10⁹, with its key
/// intact, made `play` abort on a 24 TB allocation; a corrupt frame rate
/// made `play` blame its output ("18446744073709551615 frames … do not
/// fit"); `inspect` of the cache said "up to date". Each is now refused
/// on load, naming the cause, and the cache rebuilt.
#[test]
fn a_tampered_parametric_cache_is_refused_and_rebuilt_not_trusted() {
    use surfmotion::parametric::store::{cache_path, parse};
    let db = database();
    let m = motion();
    let bytes = std::fs::read(cache_path(&db)).unwrap();
    let key = u64::from_le_bytes(bytes[8..16].try_into().unwrap());
    let opts = MotionOptions::default();
    assert!(parse(&bytes, key, &m.topology, &opts).is_ok());
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "block index 1e12",
            tampered(&bytes, |h| {
                h["spaces"][0]["pairs"][0]["blocks"][1] = 1_000_000_000_000u64.into()
            }),
            "reference blocks",
        ),
        (
            "transition depth 1e9",
            tampered(&bytes, |h| {
                h["options"]["transition"]["depth"] = 1_000_000_000u64.into()
            }),
            "options",
        ),
        (
            "fps 1e-300",
            tampered(&bytes, |h| h["fps"] = 1e-300.into()),
            "frame rate",
        ),
        (
            "phase grid 1e15",
            tampered(&bytes, |h| {
                h["spaces"][0]["alignment"]["grid"] = 1_000_000_000_000_000u64.into()
            }),
            "phase grid",
        ),
        (
            "one reference weight",
            tampered(&bytes, |h| {
                h["spaces"][1]["pairs"][0]["weights"] = serde_json::json!([0.0])
            }),
            "reference weights",
        ),
    ];
    for (what, b, words) in &cases {
        match parse(b, key, &m.topology, &opts) {
            Ok(_) => panic!("{what}: trusted"),
            Err(why) => assert!(why.contains(words), "{what}: {why}"),
        }
    }
    // In a database: `inspect` of the cache says so, `play`'s loader
    // rebuilds it.
    let tmp = tempfile::tempdir().unwrap();
    let copy = tmp.path().join("db");
    std::fs::create_dir_all(copy.join("cache")).unwrap();
    for f in [
        "character.toml",
        "topology.obj",
        "landmarks.json",
        "walk.pc2",
        "run.pc2",
        "turn.pc2",
    ] {
        std::fs::copy(db.join(f), copy.join(f)).unwrap();
        // Times kept, as `cp -p` keeps them: a file over 1 MiB enters the
        // cache key by its length, time and samples (issue 43), so the
        // copy keeps the original's key.
        let t = std::fs::metadata(db.join(f)).unwrap().modified().unwrap();
        std::fs::File::options()
            .write(true)
            .open(copy.join(f))
            .unwrap()
            .set_modified(t)
            .unwrap();
    }
    std::fs::write(cache_path(&copy), &cases[2].1).unwrap();
    let r = common::cli_ok(&["inspect".as_ref(), copy.join("cache").as_os_str()], None);
    let line = r
        .stdout
        .lines()
        .find(|l| l.contains("parametric.bin"))
        .unwrap_or_default()
        .to_string();
    assert!(
        line.contains("damaged") && line.contains("frame rate") && !line.contains("up to date"),
        "{}",
        r.stdout
    );
    let (_, cached) = load_or_build(&copy, &opts, false).unwrap();
    assert!(!cached, "a cache with a corrupt frame rate was trusted");
}
