//! Forward kinematics against peer libraries (bvhio, AMCParser) on every clip
//! in ../shared/data/mocap, and BVH write/read round trips.

use crate::common;

use serde_json::Value;
use surfmotion::mocap::bvh;
use surfmotion::rig::{LoadOptions, load_clip};

fn reference(name: &str) -> Option<(std::path::PathBuf, Value)> {
    let d = common::data_dir()?;
    let text = std::fs::read_to_string(d.join("reference").join(name)).unwrap();
    Some((d, serde_json::from_str(&text).unwrap()))
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn bvh_fk_matches_bvhio_on_every_clip() {
    let Some((d, r)) = reference("bvh_fk.json") else {
        return;
    };
    let clips = r["clips"].as_object().unwrap();
    assert!(clips.len() >= 27);
    for (rel, c) in clips {
        let clip = load_clip(&d.join(rel), &LoadOptions::default()).unwrap();
        let names: Vec<String> = c["joint_names"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap().to_string())
            .collect();
        assert_eq!(clip.point_names(), names, "{rel}");
        let mut worst = 0.0f64;
        for (f, pts) in c["positions"].as_object().unwrap() {
            let f: usize = f.parse().unwrap();
            let ours = clip.points_at(f);
            for (j, p) in pts.as_array().unwrap().iter().enumerate() {
                for k in 0..3 {
                    let e = (ours[j][k] - p[k].as_f64().unwrap()).abs();
                    worst = worst.max(e);
                    assert!(
                        e < 1e-3,
                        "{rel} frame {f} joint {} axis {k}: ours {} ref {}",
                        names[j],
                        ours[j][k],
                        p[k]
                    );
                }
            }
        }
        eprintln!("{rel}: max |Δ| = {worst:.2e}");
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn amc_fk_matches_amcparser_on_every_clip() {
    let Some((d, r)) = reference("amc_fk.json") else {
        return;
    };
    let clips = r["clips"].as_object().unwrap();
    assert!(clips.len() >= 13);
    for (rel, c) in clips {
        let clip = load_clip(
            &d.join(rel),
            &LoadOptions {
                asf: Some(d.join(c["asf"].as_str().unwrap())),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(
            clip.frame_count() as u64,
            c["frames_in_file"].as_u64().unwrap(),
            "{rel}"
        );
        let names = clip.point_names();
        let mut worst = 0.0f64;
        for (f, pts) in c["positions"].as_object().unwrap() {
            let f: usize = f.parse().unwrap();
            let ours = clip.points_at(f);
            let pts = pts.as_object().unwrap();
            assert_eq!(pts.len(), names.len(), "{rel}: bone count");
            for (name, p) in pts {
                let j = names
                    .iter()
                    .position(|n| n == name)
                    .unwrap_or_else(|| panic!("{rel}: no bone {name}"));
                for k in 0..3 {
                    let e = (ours[j][k] - p[k].as_f64().unwrap()).abs();
                    worst = worst.max(e);
                    assert!(
                        e < 1e-3,
                        "{rel} frame {f} bone {name} axis {k}: ours {} ref {}",
                        ours[j][k],
                        p[k]
                    );
                }
            }
        }
        eprintln!("{rel}: max |Δ| = {worst:.2e}");
    }
}

/// The AMC and the cgspeed BVH of CMU 01_01 describe the same motion; the BVH
/// has an extra T-pose frame first. A BVH leg or spine joint sits at the end
/// of the ASF bone before it, which pins the ASF unit and axis handling. (The
/// cgspeed conversion rebuilt the neck and arms, so those do not coincide.)
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn amc_and_cgspeed_bvh_of_01_01_agree() {
    let Some(d) = common::data_dir() else { return };
    let amc = load_clip(
        &d.join("mocap/cmu-amc/01/01_01.amc"),
        &LoadOptions::default(),
    )
    .unwrap();
    let bvh = load_clip(&d.join("mocap/cmu-bvh/01_01.bvh"), &LoadOptions::default()).unwrap();
    assert_eq!(bvh.frame_count(), amc.frame_count() + 1);
    let pairs = [
        ("LeftUpLeg", "lhipjoint"),
        ("LeftLeg", "lfemur"),
        ("LeftFoot", "ltibia"),
        ("RightLeg", "rfemur"),
        ("RightFoot", "rtibia"),
        ("LeftToeBase", "lfoot"),
        ("RightUpLeg", "rhipjoint"),
        ("RightToeBase", "rfoot"),
        ("Spine", "lowerback"),
        ("Spine1", "upperback"),
    ];
    let an = amc.point_names();
    for k in [0, 1, 500, 1375, amc.frame_count() - 1] {
        let a = amc.points_at(k);
        let b = bvh.points_at(k + 1);
        for (bj, aj) in pairs {
            let ia = an.iter().position(|n| n == aj).unwrap();
            let ib = bvh.joint(bj).unwrap().idx();
            let e = (a[ia] - b[ib]).abs().max_element();
            assert!(
                e < 1e-3,
                "frame {k}: BVH {bj} {:?} vs ASF {aj} end {:?}",
                b[ib],
                a[ia]
            );
        }
    }
    // Same units: both CMU 1/0.45 inch.
    assert!((amc.units.metres_per_unit - bvh.units.metres_per_unit).abs() < 1e-12);
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn bvh_write_read_round_trip_is_exact_on_every_clip() {
    let Some(d) = common::data_dir() else { return };
    let mut files = common::files_with_ext(&d.join("mocap"), "bvh");
    files.extend(common::files_with_ext(&d.join("mocap"), "amc"));
    for f in files {
        let a = load_clip(&f, &LoadOptions::default()).unwrap();
        let text = bvh::format_bvh(&a);
        let b = bvh::parse_bvh(
            &text,
            std::path::Path::new("roundtrip.bvh"),
            &bvh::BvhOptions::default(),
        )
        .unwrap();
        assert_eq!(a.frame_count(), b.frame_count(), "{}", f.display());
        assert!((a.frame_time - b.frame_time).abs() < 1e-12);
        // The writer emits joints depth-first; compare by name.
        let map: Vec<usize> = a
            .joints
            .iter()
            .map(|j| b.joint(&j.name).unwrap().idx())
            .collect();
        let mut worst = 0.0f64;
        for fr in 0..a.frame_count() {
            let pa = a.world_positions(fr);
            let pb = b.world_positions(fr);
            for (i, &m) in map.iter().enumerate() {
                worst = worst.max((pa[i] - pb[m]).abs().max_element());
            }
        }
        assert!(
            worst < 1e-6,
            "{}: round trip moved a joint by {worst}",
            f.display()
        );
    }
}
