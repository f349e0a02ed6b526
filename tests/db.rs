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
