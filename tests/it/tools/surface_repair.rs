//! The fold repair on the real samba capture (issues 42 and 45): where the
//! part-based solve turns triangles over before any repair, and the
//! repair's work per frame.

use crate::common;

use surfmotion::db::Character;
use surfmotion::deform::{DeformMode, DeformOptions, Deformer, unflip};
use surfmotion::drive::query::load_mocap;
use surfmotion::drive::{Output, RetargetOptions, synthesise};
use surfmotion::embed::parts::Part;

/// The retrieved, interpolated frames of `clip` on `ch` (no deformation):
/// the deformation's sources, with the query it follows.
fn sources(ch: &Character, d: &std::path::Path, clip: &str) -> Output {
    let m = load_mocap(&d.join("mocap").join(clip), &Default::default(), 30.0).unwrap();
    let opts = RetargetOptions {
        deform: DeformMode::None,
        ..Default::default()
    };
    synthesise(ch, &m.poses, &m.reference, 30.0, &opts).unwrap()
}

/// Per frame: the triangles the solve turned over before the repair, the
/// triangles left after it and the repair's work.
struct Frames {
    before: Vec<Vec<u32>>,
    after: Vec<usize>,
    work: Vec<unflip::Work>,
}

/// Deforms every frame of `raw` with `opts`, frame by frame.
fn deform_frames(ch: &Character, raw: &Output, opts: &DeformOptions) -> Frames {
    let n = ch.n();
    let tris = ch.topology().triangles();
    let def = Deformer::new(ch, DeformMode::Part, opts).unwrap();
    let bare = Deformer::new(
        ch,
        DeformMode::Part,
        &DeformOptions {
            repair: unflip::RepairOptions {
                rounds: 0,
                ..opts.repair
            },
            ..*opts
        },
    )
    .unwrap();
    let (mut ws, mut wb) = (def.workspace(), bare.workspace());
    let mut out = vec![[0.0; 3]; n];
    let mut turn = vec![glam::DQuat::IDENTITY; n];
    let mut f = Frames {
        before: Vec::new(),
        after: Vec::new(),
        work: Vec::new(),
    };
    for k in 0..raw.report.frames {
        let src = &raw.positions[k * n..(k + 1) * n];
        let sp = ch.rig().frame_joints(src);
        let target = &raw.query[k];
        bare.deform(ch, src, &sp, target, &mut out, &mut wb);
        let g = surfmotion::pose::pose_rotations(&sp, target);
        unflip::skin_turns(&ch.rig().skin, &g, &mut turn);
        f.before.push(unflip::turned_over(tris, src, &out, &turn));
        let c = def.deform(ch, src, &sp, target, &mut out, &mut ws);
        assert_eq!(c.before, f.before[k].len(), "frame {k}");
        f.after
            .push(unflip::turned_over(tris, src, &out, &turn).len());
        f.work.push(ws.repair_work());
    }
    f
}

/// Where the solve folds 02_02 on the real capture before any repair:
/// triangle-frames per part (the part of the triangle's first vertex),
/// on soft (skirt) vertices or not. A measurement: prints, asserts only
/// that it has something to show.
#[test]
#[ignore = "measurement: prints where the pre-repair folds are"]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn where_the_solve_folds_the_real_capture() {
    let Some(d) = common::data_dir() else { return };
    let ch = Character::load(&crate::deform::samba_capture_db(&d), &surfmotion::db::Quiet).unwrap();
    let tris = ch.topology().triangles();
    let soft = surfmotion::deform::soft::softness(ch.topology(), ch.rig());
    let in_regions: Vec<usize> = {
        let mut c = vec![0usize; ch.n()];
        for r in &ch.rig().regions {
            for &v in r {
                c[v as usize] += 1;
            }
        }
        c
    };
    let only = std::env::var("SURFACE_REPAIR_CLIPS").unwrap_or_default();
    let variants = [
        ("default", DeformOptions::default()),
        (
            "soft vertices not held",
            DeformOptions {
                hold_soft: false,
                ..Default::default()
            },
        ),
    ];
    for clip in ["cmu-amc/02/02_02.amc", "cmu-bvh/131_01.bvh"] {
        if !only.is_empty() && !clip.contains(&only) {
            continue;
        }
        let raw = sources(&ch, &d, clip);
        for (name, opts) in &variants {
            eprintln!("{clip}, {name}:");
            let f = deform_frames(&ch, &raw, opts);
            let mut per = [[0usize; 3]; Part::COUNT];
            for bad in &f.before {
                for &t in bad {
                    let tri = tris[t as usize];
                    let p = ch.rig().labels[tri[0] as usize] as usize;
                    let s = tri.iter().any(|&v| soft[v as usize] > 0.0);
                    let o = tri.iter().any(|&v| in_regions[v as usize] > 1);
                    per[p][0] += 1;
                    per[p][1] += s as usize;
                    per[p][2] += o as usize;
                }
            }
            let total: usize = f.before.iter().map(Vec::len).sum();
            eprintln!(
                "{clip}: {total} triangle-frames turned over before the repair, {} after; frames with any {}",
                f.after.iter().sum::<usize>(),
                f.before.iter().filter(|b| !b.is_empty()).count()
            );
            for (p, c) in Part::ALL.iter().zip(&per) {
                if c[0] > 0 {
                    eprintln!(
                        "  {:<12} {:>6} (soft {:>6}, in two regions {:>6})",
                        p.name(),
                        c[0],
                        c[1],
                        c[2]
                    );
                }
            }
            for (what, mut w) in [
                (
                    "projections",
                    f.work.iter().map(|w| w.projections).collect::<Vec<_>>(),
                ),
                (
                    "patch unknowns",
                    f.work.iter().map(|w| w.patch_vertices).collect(),
                ),
                (
                    "per triangle, projections",
                    f.work
                        .iter()
                        .zip(&f.before)
                        .filter(|(_, b)| !b.is_empty())
                        .map(|(w, b)| w.projections / b.len())
                        .collect(),
                ),
                (
                    "per triangle, patch",
                    f.work
                        .iter()
                        .zip(&f.before)
                        .filter(|(_, b)| !b.is_empty())
                        .map(|(w, b)| w.patch_vertices / b.len())
                        .collect(),
                ),
            ] {
                w.sort_unstable();
                eprintln!(
                    "  repair {what} per frame: median {}, p90 {}, max {}",
                    w[w.len() / 2],
                    w[w.len() * 9 / 10],
                    w[w.len() - 1]
                );
            }
            for (k, (b, w)) in f.before.iter().zip(&f.work).enumerate() {
                eprintln!(
                    "  frame {k}: {} turned over, {} left, {w:?}",
                    b.len(),
                    f.after[k]
                );
            }
            assert!(total > 0);
        }
    }
}
