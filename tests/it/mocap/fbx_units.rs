//! The FBX unit judged from the body (issue 44): `UnitScaleFactor` stands
//! when it gives a human stature; missing, or contradicting the body (a
//! 1.7 m actor stored in cm and declared as m reads 170 m), the stature
//! rule BVH files get (`mocap::units::units_from_stature`) decides.
//! Variants are made from real files by rewriting the factor in place.

use crate::common;
use std::path::Path;
use surfmotion::mocap::Units;
use surfmotion::mocap::fbx::units_with_stature;
use surfmotion::rig::{LoadOptions, load_clip};

/// The bytes of a binary FBX 7.x with its `UnitScaleFactor` property set
/// to `value`, or renamed away (`None`: the file has no factor). The
/// property record is `S"UnitScaleFactor" S"double" S"Number" S"" D<f64>`.
fn with_unit_scale(bytes: &[u8], value: Option<f64>) -> Vec<u8> {
    let name = b"S\x0f\x00\x00\x00UnitScaleFactor";
    let at = bytes
        .windows(name.len())
        .position(|w| w == name)
        .expect("a UnitScaleFactor property");
    let mut out = bytes.to_vec();
    match value {
        None => out[at + name.len() - 1] = b'X',
        Some(v) => {
            // Skip the name and the three type strings to the 'D' value.
            let mut k = at + name.len();
            for _ in 0..3 {
                assert_eq!(out[k], b'S');
                let len = u32::from_le_bytes(out[k + 1..k + 5].try_into().unwrap()) as usize;
                k += 5 + len;
            }
            assert_eq!(out[k], b'D', "a double value");
            out[k + 1..k + 9].copy_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// Loads `bytes` as `name` (an FBX) through the clip loader: units,
/// stature check and all; returns the clip in metres.
fn load(dir: &Path, name: &str, bytes: &[u8]) -> surfmotion::mocap::Clip {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    load_clip(&p, &LoadOptions::default()).unwrap()
}

/// The height (m) of a clip's frame: vertical span of its joints.
fn height(c: &surfmotion::mocap::Clip, frame: usize) -> f64 {
    let mut c = c.clone();
    c.to_metres_y_up();
    let ys: Vec<f64> = c.world_positions(frame).iter().map(|p| p.y).collect();
    ys.iter().cloned().fold(f64::MIN, f64::max) - ys.iter().cloned().fold(f64::MAX, f64::min)
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_missing_or_wrong_unit_scale_factor_is_judged_from_the_stature() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    // Mixamo's dancer: centimetres, UnitScaleFactor 1, a human body.
    let real = std::fs::read(d.join("fbx/threejs/Samba Dancing.fbx")).unwrap();
    let file = load(tmp.path(), "as_is.fbx", &real);
    assert_eq!(file.units().metres_per_unit, 0.01);
    assert!(
        file.units().reason.contains("the body agrees"),
        "{}",
        file.units().reason
    );
    let h = height(&file, 0);
    assert!((1.2..2.0).contains(&h), "height {h}");
    // Declared as metres (100): a 170 m dancer, so the body decides: cm.
    let wrong = load(
        tmp.path(),
        "wrong.fbx",
        &with_unit_scale(&real, Some(100.0)),
    );
    assert_eq!(
        wrong.units().metres_per_unit,
        0.01,
        "{}",
        wrong.units().reason
    );
    assert!(
        wrong.units().reason.contains("UnitScaleFactor 100")
            && wrong.units().reason.contains("the body decides"),
        "{}",
        wrong.units().reason
    );
    // Declared as millimetres (0.1): a 17 cm dancer, likewise.
    let small = load(tmp.path(), "small.fbx", &with_unit_scale(&real, Some(0.1)));
    assert_eq!(
        small.units().metres_per_unit,
        0.01,
        "{}",
        small.units().reason
    );
    // No factor at all: the body decides, and says so.
    let none = load(tmp.path(), "none.fbx", &with_unit_scale(&real, None));
    assert_eq!(none.units().metres_per_unit, 0.01);
    assert!(
        none.units().reason.contains("no UnitScaleFactor"),
        "{}",
        none.units().reason
    );
    // The same motion either way, to the bit.
    for c in [&wrong, &small, &none] {
        assert_eq!(c.translations(), file.translations());
        assert_eq!(height(c, 100), height(&file, 100));
    }
    // `inspect` says what the file declares and what was read.
    let p = tmp.path().join("wrong.fbx");
    let o = common::run_ok(
        std::process::Command::new(common::bin())
            .arg("inspect")
            .arg(&p),
    );
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(s.contains("UnitScaleFactor 100 (1 m per unit)"), "{s}");
    assert!(s.contains("units       cm = 0.01 m per unit"), "{s}");
    assert!(s.contains("the body decides"), "{s}");
    let p = tmp.path().join("none.fbx");
    let o = common::run_ok(
        std::process::Command::new(common::bin())
            .arg("inspect")
            .arg(&p),
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("no UnitScaleFactor"));
}

/// CMU 01_01 as Blender exported it (IsaacGymEnvs): CMU units taken for
/// metres, written in cm with UnitScaleFactor 1, a body about 30 m tall.
/// No unit the suites write makes it human, so it is scaled to the
/// nominal adult, as a BVH in an unknown unit is.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn cmu_01_01_fbx_declared_in_cm_but_30_m_tall_is_scaled_to_an_adult() {
    let Some(d) = common::data_dir() else { return };
    let c = load_clip(
        &d.join("fbx/isaacgymenvs/01_01_cmu.fbx"),
        &LoadOptions::default(),
    )
    .unwrap();
    assert!(
        c.units().reason.contains("the body decides") && c.units().reason.contains("1.7 m adult"),
        "{}",
        c.units().reason
    );
    let h = height(&c, 1000);
    assert!((1.0..2.2).contains(&h), "height {h} m");
}

/// The rule alone: a factor that gives a human stature stands; one that
/// does not, or none, yields to the body; without a humanoid the file's
/// unit stays.
#[test]
fn units_with_stature_keeps_a_plausible_factor_and_replaces_the_others() {
    let cm = Units {
        metres_per_unit: 0.01,
        name: "cm".into(),
        reason: "FBX GlobalSettings UnitScaleFactor 1".into(),
    };
    let m = Units {
        metres_per_unit: 1.0,
        name: "m".into(),
        reason: "FBX GlobalSettings UnitScaleFactor 100".into(),
    };
    let basis = || "limbs".to_string();
    // 170 units: cm agrees; declared m contradicts (170 m) → cm.
    assert_eq!(
        units_with_stature(&cm, Some((170.0, basis()))).metres_per_unit,
        0.01
    );
    let u = units_with_stature(&m, Some((170.0, basis())));
    assert_eq!(u.metres_per_unit, 0.01, "{}", u.reason);
    // 1.75 units: declared m agrees; declared cm (1.75 cm) → m.
    assert_eq!(
        units_with_stature(&m, Some((1.75, basis()))).metres_per_unit,
        1.0
    );
    assert_eq!(
        units_with_stature(&cm, Some((1.75, basis()))).metres_per_unit,
        1.0
    );
    // 68 units declared cm (0.68 m, below a human) → inches (1.73 m).
    let u = units_with_stature(&cm, Some((68.0, basis())));
    assert_eq!(u.metres_per_unit, 0.0254, "{}", u.reason);
    // No humanoid: the file's unit, with the reason.
    let u = units_with_stature(&m, None);
    assert_eq!(u.metres_per_unit, 1.0);
    assert!(u.reason.contains("no humanoid"), "{}", u.reason);
}
