//! Character database manifests on the real 4D captures.

mod common;

use std::process::Command;

fn run(args: &[&str]) -> std::process::Output {
    Command::new(common::bin()).args(args).output().unwrap()
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn init_and_info_on_samba_and_crane() {
    let Some(d) = common::data_dir() else { return };
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("samba_db");
    let s = |p: &str| d.join(p).display().to_string();
    let o = run(&[
        "db",
        "init",
        db.to_str().unwrap(),
        "--mesh",
        &s("4d/samba/samba.obj"),
        "--sequence",
        &format!("dance={}", s("4d/samba/samba.pc2")),
        "--sequence",
        &format!("first20={}", s("4d/samba/frames")),
        "--sequence",
        &format!("crane={}", s("4d/crane/crane.pc2")),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // A second init without --force is refused.
    let o2 = run(&[
        "db",
        "init",
        db.to_str().unwrap(),
        "--mesh",
        &s("4d/samba/samba.obj"),
    ]);
    assert_eq!(o2.status.code(), Some(1));
    let o = run(&["db", "info", db.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["vertices"], 9971);
    assert_eq!(v["sequences"][0]["frames"], 175);
    assert_eq!(v["sequences"][1]["frames"], 20);
    let problems: Vec<String> = v["problems"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p.as_str().unwrap().to_string())
        .collect();
    assert!(
        problems
            .iter()
            .any(|p| p.contains("'crane'") && p.contains("10002")),
        "{problems:?}"
    );
    assert!(
        problems.iter().any(|p| p.contains("no rig")),
        "{problems:?}"
    );
    assert!(
        !problems
            .iter()
            .any(|p| p.contains("'dance'") || p.contains("'first20'")),
        "{problems:?}"
    );
    // A broken manifest is one clear line naming the file.
    std::fs::write(
        db.join("character.toml"),
        "name = \"x\"\nfps = -3\ntopology = \"t.obj\"\n",
    )
    .unwrap();
    let o = run(&["db", "info", db.to_str().unwrap()]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1));
    assert!(e.contains("character.toml") && e.contains("fps"), "{e}");
}

/// `db init --up auto` (the default) reads the up axis off the landmarks'
/// groin→chin direction in the file's coordinates, and `--input-units auto`
/// the unit off the rest frame's height along it (m, cm or mm): the samba mesh and its
/// landmarks turned Z-up give `up = "z"`, the original `y`; an explicit
/// axis the landmarks contradict is kept with a warning, and a body lying
/// along ±X or −Y is refused in one line (the database reads Y-up or Z-up
/// files). Without the check a Z-up capture initialised as Y-up built and
/// retargeted into a contorted character, CMU 02_02's vertices up to 2.1 m
/// from the Y-up database's.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn init_reads_the_up_axis_and_unit_off_the_capture() {
    let Some(d) = common::data_dir() else { return };
    let dir = tempfile::tempdir().unwrap();
    let obj = std::fs::read_to_string(d.join("4d/samba/samba.obj")).unwrap();
    let lm: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("tests/fixtures/samba.landmarks.json"),
        )
        .unwrap(),
    )
    .unwrap();
    // Each placement turns (x, y, z) of the Y-up capture.
    // Each placement turns (x, y, z) of the Y-up capture in metres, and
    // gives the up axis and unit `auto` must read.
    type Turn = fn([f64; 3]) -> [f64; 3];
    let placements: [(&str, Turn, Option<&str>, &str); 6] = [
        ("y_up", |p| p, Some("y"), "m"),
        ("z_up", |[x, y, z]| [x, -z, y], Some("z"), "m"),
        ("x_up", |[x, y, z]| [y, -x, z], None, ""),
        ("y_down", |[x, y, z]| [x, -y, -z], None, ""),
        (
            "z_up_mm",
            |[x, y, z]| [x * 1e3, -z * 1e3, y * 1e3],
            Some("z"),
            "mm",
        ),
        ("y_up_cm", |p| p.map(|c| c * 100.0), Some("y"), "cm"),
    ];
    for (name, turn, want, unit) in placements {
        let mesh = dir.path().join(format!("{name}.obj"));
        let text: String = obj
            .lines()
            .map(|l| match l.strip_prefix("v ") {
                Some(rest) => {
                    let v: Vec<f64> = rest
                        .split_whitespace()
                        .map(|t| t.parse().unwrap())
                        .collect();
                    let [x, y, z] = turn([v[0], v[1], v[2]]);
                    format!("v {x} {y} {z}\n")
                }
                None => format!("{l}\n"),
            })
            .collect();
        std::fs::write(&mesh, text).unwrap();
        let mut marks = lm.clone();
        for (_, v) in marks.as_object_mut().unwrap() {
            if let Some(a) = v.as_array() {
                let p: Vec<f64> = a.iter().map(|c| c.as_f64().unwrap()).collect();
                *v = serde_json::json!(turn([p[0], p[1], p[2]]));
            }
        }
        let lm_path = dir.path().join(format!("{name}.landmarks.json"));
        std::fs::write(&lm_path, marks.to_string()).unwrap();
        let init = |db: &str, up: &[&str]| {
            let db = dir.path().join(db);
            let mut args = vec![
                "db",
                "init",
                db.to_str().unwrap(),
                "--mesh",
                mesh.to_str().unwrap(),
                "--landmarks",
                lm_path.to_str().unwrap(),
            ];
            args.extend_from_slice(up);
            let o = run(&args);
            let toml = std::fs::read_to_string(db.join("character.toml")).unwrap_or_default();
            (o, toml)
        };
        let (o, toml) = init(&format!("{name}_auto"), &[]);
        let err = String::from_utf8_lossy(&o.stderr);
        match want {
            Some(axis) => {
                assert!(o.status.success(), "{name}: {err}");
                assert!(toml.contains(&format!("up = \"{axis}\"")), "{name}: {toml}");
                assert!(
                    toml.contains(&format!("units = \"{unit}\"")),
                    "{name}: {toml}"
                );
                // A unit that makes the body 1.7 km or 1.7 mm tall warns.
                if unit != "m" {
                    let (o, _) = init(&format!("{name}_in_m"), &["--input-units", "m"]);
                    let err = String::from_utf8_lossy(&o.stderr);
                    assert!(err.contains("is the unit right?"), "{name}: {err}");
                }
                // The other axis, given explicitly, is written with a warning.
                let other = if axis == "y" { "z" } else { "y" };
                let (o, toml) = init(&format!("{name}_{other}"), &["--up", other]);
                let err = String::from_utf8_lossy(&o.stderr);
                assert!(o.status.success(), "{name}: {err}");
                assert!(
                    toml.contains(&format!("up = \"{other}\"")),
                    "{name}: {toml}"
                );
                assert!(
                    err.contains(&format!("--up {other}, but the landmarks")),
                    "{name}: no warning: {err}"
                );
                let (o, _) = init(&format!("{name}_{axis}"), &["--up", axis]);
                let err = String::from_utf8_lossy(&o.stderr);
                assert!(!err.contains("WARN"), "{name}: {err}");
            }
            None => {
                assert_eq!(o.status.code(), Some(1), "{name}: {err}");
                assert_eq!(err.trim().lines().count(), 1, "{name}: {err}");
                assert!(err.contains("within 45° of neither"), "{name}: {err}");
                assert!(toml.is_empty(), "{name}: a manifest was written");
            }
        }
    }
}
