//! The creases at the back of the knee (issue 42, session 36): per stage
//! of the deformation, how many of the surface measure's crease edges lie
//! within 8 cm of a knee, on a CMU walk retargeted onto the real samba
//! capture.

use crate::common;

use surfmotion::db::Character;
use surfmotion::deform::dqs::ConstraintSkin;
use surfmotion::deform::{DeformMode, DeformOptions, Deformer, unflip};
use surfmotion::drive::query::load_mocap;
use surfmotion::drive::{DriveOptions, synthesise};
use surfmotion::rig::Canonical;
use surfmotion::tools::eval::surface::{SurfaceOptions, SurfaceReference, captured_of, frame_ids};

/// Knee-zone crease edge-frames of one stage, and all crease edge-frames.
#[derive(Default, Debug, Clone, Copy)]
struct Count {
    knee: usize,
    all: usize,
}

/// Per stage the knee-zone and total creases of `clip` onto the real samba
/// capture with `opts`: the skinning (linear, dual-quaternion), each
/// thigh's and shin's own solve (its vertices put into the frame the
/// blend gives, only the region's edges counted), the blend with the
/// cloth stitch (no repair) and the output after the repair. A
/// measurement: prints (`SURFACE_KNEE_CLIP`, default CMU 02_02;
/// `SURFACE_KNEE_STEPS`: [`DeformOptions::local_steps`], default 0).
#[test]
#[ignore = "measurement: prints the knee-zone creases per stage"]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn where_the_knee_creases_come_from() {
    let Some(d) = common::data_dir() else { return };
    let ch = Character::load(&crate::deform::samba_capture_db(&d), &surfmotion::db::Quiet).unwrap();
    let clip = std::env::var("SURFACE_KNEE_CLIP").unwrap_or("cmu-amc/02/02_02.amc".into());
    let m = load_mocap(&d.join("mocap").join(&clip), &Default::default(), 30.0).unwrap();
    let none = DriveOptions {
        deform: DeformMode::None,
        ..Default::default()
    };
    let raw = synthesise(&ch, &m.poses, &m.reference, 30.0, &none).unwrap();
    let rest = ch.topology_metres();
    let ids = frame_ids(&ch);
    let reference = SurfaceReference::new(
        captured_of(&ch, rest.positions(), &ids),
        SurfaceOptions::default(),
    )
    .unwrap();
    let joints = ch.rig().frame_joints(rest.positions());
    let near_knee: Vec<bool> = rest
        .positions()
        .iter()
        .map(|p| {
            let p = glam::DVec3::from_array(*p);
            [Canonical::LKnee, Canonical::RKnee]
                .iter()
                .any(|k| (p - joints[k.index()]).length() < 0.08)
        })
        .collect();
    // Rotation-aware local steps after each region's solve.
    let steps: usize = std::env::var("SURFACE_KNEE_STEPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let knee_edge = |e: &[u32; 2]| near_knee[e[0] as usize] && near_knee[e[1] as usize];
    for skin in [
        ConstraintSkin::Linear,
        ConstraintSkin::DualQuaternion,
        ConstraintSkin::Rigid,
    ] {
        let opts = DeformOptions {
            constraint_skin: skin,
            local_steps: steps,
            ..Default::default()
        };
        let bare_opts = DeformOptions {
            repair: unflip::RepairOptions {
                rounds: 0,
                ..opts.repair
            },
            ..opts
        };
        let (def, bare) = (
            Deformer::new(&ch, DeformMode::Part, &opts).unwrap(),
            Deformer::new(&ch, DeformMode::Part, &bare_opts).unwrap(),
        );
        let (mut ws, mut wb) = (def.workspace(), bare.workspace());
        let n = ch.n();
        let names = [
            "skin", "l_thigh", "r_thigh", "l_shin", "r_shin", "blend", "repair", "source",
        ];
        let mut c = [Count::default(); 8];
        let mut out = vec![[0.0; 3]; n];
        let mut skinned = vec![[0.0; 3]; n];
        let add = |c: &mut Count, frame: &[[f64; 3]], only: Option<&[u32]>| {
            for e in reference.crease_edges(frame) {
                let inside = |v: u32| only.is_none_or(|o| o.binary_search(&v).is_ok());
                if inside(e[0]) && inside(e[1]) {
                    c.all += 1;
                    c.knee += knee_edge(&e) as usize;
                }
            }
        };
        for k in 0..raw.report.frames {
            let src = &raw.positions[k * n..(k + 1) * n];
            let sp = ch.rig().frame_joints(src);
            let target = &raw.query[k];
            let g = surfmotion::pose::pose_rotations(&sp, target);
            match skin {
                ConstraintSkin::Linear => {
                    surfmotion::deform::lbs::skin_into(src, ch.rig(), &sp, target, &g, &mut skinned)
                }
                ConstraintSkin::DualQuaternion => {
                    surfmotion::deform::dqs::skin_into(src, ch.rig(), &sp, target, &g, &mut skinned)
                }
                ConstraintSkin::Rigid => surfmotion::deform::dqs::rigid_into(
                    src,
                    ch.rig(),
                    &sp,
                    target,
                    &g,
                    &mut skinned,
                ),
            }
            add(&mut c[0], &skinned, None);
            add(&mut c[7], src, None);
            bare.deform(&ch, src, &sp, target, &mut out, &mut wb);
            add(&mut c[5], &out, None);
            let res = bare.region_results(target, &wb);
            for (i, j) in [
                Canonical::LHip,
                Canonical::RHip,
                Canonical::LKnee,
                Canonical::RKnee,
            ]
            .iter()
            .enumerate()
            {
                let r = res.iter().find(|r| r.joint == *j).unwrap();
                let mut frame = out.clone();
                for (&v, x) in r.vertices.iter().zip(&r.positions) {
                    frame[v as usize] = *x;
                }
                add(&mut c[1 + i], &frame, Some(&r.vertices));
            }
            def.deform(&ch, src, &sp, target, &mut out, &mut ws);
            add(&mut c[6], &out, None);
        }
        eprintln!(
            "{clip} onto samba, {} frames, constraints by {skin:?} skinning, {steps} local steps: crease edge-frames within 8 cm of a knee / all (region stages: the region's edges only)",
            raw.report.frames
        );
        for (name, c) in names.iter().zip(&c) {
            eprintln!("  {name:>8}: {:>6} / {:>6}", c.knee, c.all);
        }
        assert!(c[0].all > 0, "the skinning creases somewhere");
    }
}
