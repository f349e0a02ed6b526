//! The fold repair on the real samba capture (issues 42 and 45): where the
//! part-based solve turns triangles over before any repair, and the
//! repair's work per frame.

use crate::common;

use surfmotion::db::Character;
use surfmotion::deform::{DeformMode, DeformOptions, Deformer, RepairBudget, RepairTurns, unflip};
use surfmotion::drive::query::load_mocap;
use surfmotion::drive::{DriveOptions, Output, synthesise};
use surfmotion::embed::parts::Part;

/// The retrieved, interpolated frames of `clip` on `ch` (no deformation):
/// the deformation's sources, with the query it follows.
fn sources(ch: &Character, d: &std::path::Path, clip: &str) -> Output {
    let m = load_mocap(&d.join("mocap").join(clip), &Default::default(), 30.0).unwrap();
    let opts = DriveOptions {
        deform: DeformMode::None,
        ..Default::default()
    };
    synthesise(ch, &m.poses, &m.reference, 30.0, &opts).unwrap()
}

/// The real samba capture and `clip` retargeted onto it (the
/// [`sources`] of its deformation), or `None` without the shared data.
fn samba_clip(clip: &str) -> Option<(Character, Output)> {
    let d = common::data_dir()?;
    let ch = Character::load(&crate::deform::samba_capture_db(&d), &surfmotion::db::Quiet).unwrap();
    let raw = sources(&ch, &d, clip);
    Some((ch, raw))
}

/// Per frame: the triangles the solve turned over before the repair, the
/// triangles left after it and the repair's work.
struct Frames {
    before: Vec<Vec<u32>>,
    after: Vec<usize>,
    work: Vec<unflip::Work>,
    /// Wall seconds of each frame's deformation with its repair (printed
    /// only: the machine is shared).
    seconds: Vec<f64>,
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
        seconds: Vec::new(),
    };
    for k in 0..raw.report.frames {
        let src = &raw.positions[k * n..(k + 1) * n];
        let sp = ch.rig().frame_joints(src);
        let target = &raw.query[k];
        bare.deform(ch, src, &sp, target, &mut out, &mut wb);
        let g = surfmotion::pose::pose_rotations(&sp, target);
        unflip::skin_turns(ch.rig().skin(), &g, &mut turn);
        f.before.push(unflip::turned_over(tris, src, &out, &turn));
        let t = std::time::Instant::now();
        let c = def.deform(ch, src, &sp, target, &mut out, &mut ws);
        f.seconds.push(t.elapsed().as_secs_f64());
        assert_eq!(c.before, f.before[k].len(), "frame {k}");
        f.after
            .push(unflip::turned_over(tris, src, &out, &turn).len());
        f.work.push(ws.repair_work());
    }
    f
}

/// A repair budget of `projections` and `patch` unknowns a frame at
/// most, 1,000 projections and 60 patch unknowns per triangle turned over.
fn budget(projections: usize, patch: usize) -> RepairBudget {
    RepairBudget {
        per_triangle: unflip::WorkLimit {
            projections: 1_000,
            patch_vertices: 60,
        },
        most: unflip::WorkLimit {
            projections,
            patch_vertices: patch,
        },
        skin: unflip::WorkLimit::NONE,
    }
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
    let mask: Vec<u32> = {
        let mut m = vec![0u32; ch.n()];
        for (p, r) in ch.rig().regions().iter().enumerate() {
            for &v in r {
                m[v as usize] |= 1 << p;
            }
        }
        m
    };
    let in_regions: Vec<usize> = {
        let mut c = vec![0usize; ch.n()];
        for r in ch.rig().regions() {
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
        (
            "seams by weight, held joints spread",
            DeformOptions {
                seam_by_weight: true,
                hold_spread: true,
                ..Default::default()
            },
        ),
        (
            "seams by weight only",
            DeformOptions {
                seam_by_weight: true,
                ..Default::default()
            },
        ),
        (
            "held joints spread and by weight",
            DeformOptions {
                seam_by_weight: true,
                hold_spread: true,
                hold_by_weight: true,
                ..Default::default()
            },
        ),
        (
            "sibling seams",
            DeformOptions {
                sibling_seams: true,
                ..Default::default()
            },
        ),
        (
            "budget 30k / 4k",
            DeformOptions {
                repair_budget: budget(30_000, 4_000),
                ..Default::default()
            },
        ),
        (
            "budget 15k / 2k",
            DeformOptions {
                repair_budget: budget(15_000, 2_000),
                ..Default::default()
            },
        ),
        (
            "budget 60k / 8k",
            DeformOptions {
                repair_budget: budget(60_000, 8_000),
                ..Default::default()
            },
        ),
    ];
    for clip in [
        "cmu-amc/02/02_02.amc",
        "cmu-bvh/131_01.bvh",
        "cmu-bvh/131_02.bvh",
    ] {
        if !only.is_empty() && !clip.contains(&only) {
            continue;
        }
        let raw = sources(&ch, &d, clip);
        let pick = std::env::var("SURFACE_REPAIR_VARIANTS").unwrap_or_default();
        for (name, opts) in &variants {
            if !pick.is_empty() && !pick.split(',').any(|p| name.contains(p)) {
                continue;
            }
            eprintln!("{clip}, {name}:");
            let f = deform_frames(&ch, &raw, opts);
            let mut per = [[0usize; 3]; Part::COUNT];
            let mut sets = std::collections::BTreeMap::<u32, usize>::new();
            for bad in &f.before {
                for &t in bad {
                    let tri = tris[t as usize];
                    let p = ch.rig().labels()[tri[0] as usize] as usize;
                    let s = tri.iter().any(|&v| soft[v as usize] > 0.0);
                    let o = tri.iter().any(|&v| in_regions[v as usize] > 1);
                    per[p][0] += 1;
                    *sets.entry(mask[tri[0] as usize]).or_default() += 1;
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
            let mut sets: Vec<(u32, usize)> = sets.into_iter().collect();
            sets.sort_by_key(|&(_, c)| std::cmp::Reverse(c));
            for (m, c) in sets.iter().take(8) {
                let names: Vec<&str> = Part::ALL
                    .iter()
                    .filter(|p| m & (1 << p.index()) != 0)
                    .map(|p| p.name())
                    .collect();
                eprintln!("  in regions {names:?}: {c}");
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
            let mut t = f.seconds.clone();
            t.sort_by(f64::total_cmp);
            eprintln!(
                "  deformation wall ms a frame: median {:.1}, max {:.1}; frames left with any turned over {}",
                1e3 * t[t.len() / 2],
                1e3 * t[t.len() - 1],
                f.after.iter().filter(|&&a| a > 0).count()
            );
            if std::env::var_os("SURFACE_REPAIR_FRAMES").is_some() {
                for (k, (b, w)) in f.before.iter().zip(&f.work).enumerate() {
                    eprintln!(
                        "  frame {k}: {} turned over, {} left, {w:?}, {:.1} ms",
                        b.len(),
                        f.after[k],
                        1e3 * f.seconds[k]
                    );
                }
            }
            assert!(total > 0);
        }
    }
}

/// The fold repair's work can be bounded per frame (issue 45's tail): on
/// CMU 02_02 retargeted onto the real samba capture, with a budget of
/// 30,000 projections and 4,000 patch unknowns a frame, every frame's
/// repair stays within it (counted: projections and patch unknowns, not
/// time), the unbounded repair (the default) goes past it on some frame,
/// so the bound binds, and the bounded repair still turns back all but
/// 1 % of the triangle-frames the solve turned over (measured: 11 of
/// 3,599 left; the unbounded repair leaves 0).
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_fold_repair_stays_within_its_budget() {
    let Some((ch, raw)) = samba_clip("cmu-amc/02/02_02.amc") else {
        return;
    };
    let budget = budget(30_000, 4_000);
    // The budget bounds each repair; the skin's turns alone (one repair,
    // counted against them as `deform_frames` counts), on the solve
    // without the cloth stitch: with it (the default since session 30) the
    // repair reads the skirt with the stitch's turns and the unbounded
    // repair stays within this budget on every frame of 02_02, so the
    // bound would not bind.
    let skin = DeformOptions {
        repair_turns: RepairTurns::Skin,
        cloth_stitch: 0.0,
        ..Default::default()
    };
    let opts = DeformOptions {
        repair_budget: budget,
        ..skin
    };
    assert_eq!(DeformOptions::default().repair_budget, RepairBudget::NONE);
    let bounded = deform_frames(&ch, &raw, &opts);
    let unbounded = deform_frames(&ch, &raw, &skin);
    for (k, (w, b)) in bounded.work.iter().zip(&bounded.before).enumerate() {
        let limit = budget.limit(b.len());
        assert!(
            w.projections <= limit.projections && w.patch_vertices <= limit.patch_vertices,
            "frame {k}: {w:?} past {limit:?}"
        );
    }
    let over = |f: &Frames| {
        f.work
            .iter()
            .zip(&f.before)
            .filter(|(w, b)| {
                let l = budget.limit(b.len());
                w.projections > l.projections || w.patch_vertices > l.patch_vertices
            })
            .count()
    };
    assert!(
        over(&unbounded) > 0,
        "the unbounded repair stayed within the budget on every frame"
    );
    let left = |f: &Frames| f.after.iter().sum::<usize>();
    let solved: usize = bounded.before.iter().map(Vec::len).sum();
    assert_eq!(left(&unbounded), 0);
    assert!(
        100 * left(&bounded) <= solved,
        "bounded repair left {} of {solved} triangle-frames turned over",
        left(&bounded)
    );
    eprintln!(
        "02_02 on samba: unbounded repair past the budget on {} frames; left turned over: bounded {}, unbounded {}",
        over(&unbounded),
        left(&bounded),
        left(&unbounded)
    );
}

/// Live's repair budget bounds a frame's whole repair (issue 45's
/// deadline): on CMU 131_01 retargeted onto the real samba capture with
/// the default deformation (the skin's turns, then the surface's own
/// rounds, the cloth stitch and its fallback: several repairs a frame),
/// every frame's counted work, all its repairs together, stays within the
/// budget's most, and the bound binds (the repair stops at it on some
/// frame). Run with [`RepairBudget::LIVE`]'s shares and skin's limit
/// (none: its smoothing alone) and a quarter of its most: live's own most
/// no longer binds on 131_01 once the skin's repair spends nothing
/// (session 52; it stopped 114 of 249 frames before).
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_live_budget_bounds_each_frames_whole_repair() {
    let Some((ch, raw)) = samba_clip("cmu-bvh/131_01.bvh") else {
        return;
    };
    let live = RepairBudget {
        most: unflip::WorkLimit {
            projections: RepairBudget::LIVE.most.projections / 4,
            patch_vertices: RepairBudget::LIVE.most.patch_vertices / 4,
        },
        ..RepairBudget::LIVE
    };
    assert!(live.skips_skin());
    let opts = DeformOptions {
        repair_budget: live,
        ..Default::default()
    };
    let f = deform_frames(&ch, &raw, &opts);
    for (k, w) in f.work.iter().enumerate() {
        assert!(
            w.projections <= live.most.projections && w.patch_vertices <= live.most.patch_vertices,
            "frame {k}: {w:?} past {:?}",
            live.most
        );
    }
    let stopped = f.work.iter().filter(|w| w.stopped > 0).count();
    assert!(stopped > 0, "the budget never bound on 131_01");
    let most = |g: fn(&unflip::Work) -> usize| f.work.iter().map(g).max().unwrap_or(0);
    eprintln!(
        "131_01 on samba, {live}: stopped on {stopped} of {} frames; most a frame: {} projections, {} patch unknowns; left turned over (skin reading) {}",
        f.work.len(),
        most(|w| w.projections),
        most(|w| w.patch_vertices),
        f.after.iter().sum::<usize>()
    );
}

/// Why the thigh and shin regions fold where they overlap (issue 42): at
/// the frame of CMU 02_02 with the most triangles turned over before the
/// repair, what each region's solve gives a vertex of the overlap (the
/// thigh's and the shin's results, the LBS position, the blending weights,
/// how each region holds the vertex), by position along the thigh bone
/// and the shin bone, on the folded triangles and on the whole overlap.
/// A measurement: prints.
#[test]
#[ignore = "measurement: prints what the thigh and shin solves ask of the knee overlap"]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn why_the_knees_fold() {
    use surfmotion::deform::Held;
    use surfmotion::rig::Canonical as C;
    let clip = std::env::var("SURFACE_KNEE_CLIP").unwrap_or("cmu-amc/02/02_02.amc".into());
    let Some((ch, raw)) = samba_clip(&clip) else {
        return;
    };
    let opts = DeformOptions {
        repair: unflip::RepairOptions {
            rounds: 0,
            ..Default::default()
        },
        seam_by_weight: std::env::var_os("SURFACE_KNEE_NEW").is_some(),
        hold_spread: std::env::var_os("SURFACE_KNEE_NEW").is_some(),
        ..Default::default()
    };
    let f = deform_frames(
        &ch,
        &raw,
        &DeformOptions {
            repair: Default::default(),
            ..opts
        },
    );
    let (k, _) = f
        .before
        .iter()
        .enumerate()
        .max_by_key(|(_, b)| b.len())
        .unwrap();
    let n = ch.n();
    let tris = ch.topology().triangles();
    let def = Deformer::new(&ch, DeformMode::Part, &opts).unwrap();
    let mut ws = def.workspace();
    let src = &raw.positions[k * n..(k + 1) * n];
    let sp = ch.rig().frame_joints(src);
    let target = &raw.query[k];
    let mut out = vec![[0.0; 3]; n];
    def.deform(&ch, src, &sp, target, &mut out, &mut ws);
    let g = surfmotion::pose::pose_rotations(&sp, target);
    let mut lbs = vec![[0.0; 3]; n];
    surfmotion::deform::lbs::skin_into(src, ch.rig(), &sp, target, &g, &mut lbs);
    let res = def.region_results(target, &ws);
    let bad = &f.before[k];
    eprintln!(
        "{clip}: frame {k}, {} turned over before the repair",
        bad.len()
    );
    let dist = |a: [f64; 3], b: [f64; 3]| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    let rest = ch.rest_pose();
    for (thigh, shin, hip, knee, ankle) in [
        (C::LHip, C::LKnee, C::LHip, C::LKnee, C::LAnkle),
        (C::RHip, C::RKnee, C::RHip, C::RKnee, C::RAnkle),
    ] {
        let rt = res.iter().find(|r| r.joint == thigh).unwrap();
        let rs = res.iter().find(|r| r.joint == shin).unwrap();
        let at = |r: &surfmotion::deform::RegionResult, v: u32| r.vertices.binary_search(&v).ok();
        // Along the leg in the source frame: 0 at the hip, 1 at the knee, 2 at the ankle.
        let along = |v: u32| {
            let p = glam::DVec3::from_array(src[v as usize]);
            let (h, kn, an) = (sp[hip.index()], sp[knee.index()], sp[ankle.index()]);
            let s = (p - kn).dot(kn - h) / (kn - h).length_squared();
            if s < 0.0 {
                1.0 + s
            } else {
                1.0 + (p - kn).dot(an - kn) / (an - kn).length_squared()
            }
        };
        let _ = rest;
        let folded: std::collections::BTreeSet<u32> =
            bad.iter().flat_map(|&t| tris[t as usize]).collect();
        // Bins of `along`: per bin, count, mean |thigh − shin|, |thigh − LBS|,
        // |shin − LBS|, |blend − LBS|, mean weights, held kinds, folded vertices.
        let mut bins = vec![[0.0f64; 12]; 12];
        for (i, &v) in rt.vertices.iter().enumerate() {
            let Some(j) = at(rs, v) else { continue };
            let a = along(v);
            let b = ((a - 0.6) / 0.1).floor().clamp(0.0, 11.0) as usize;
            let e = &mut bins[b];
            e[0] += 1.0;
            e[1] += dist(rt.positions[i], rs.positions[j]);
            e[2] += dist(rt.positions[i], lbs[v as usize]);
            e[3] += dist(rs.positions[j], lbs[v as usize]);
            e[4] += dist(out[v as usize], lbs[v as usize]);
            e[5] += rt.weights[i];
            e[6] += rs.weights[j];
            e[7] += (rt.held[i] == Held::Lbs) as u8 as f64;
            e[8] += (rs.held[j] == Held::Seam) as u8 as f64;
            e[9] += folded.contains(&v) as u8 as f64;
            e[10] += (rs.held[j] == Held::Lbs) as u8 as f64;
            e[11] += (ch.rig().labels()[v as usize] as usize == Part::of_joint(shin).index()) as u8
                as f64;
        }
        eprintln!(
            "{thigh:?}/{shin:?} overlap by position along the leg (1 = knee, 2 = ankle): n, cm |thigh-shin| |thigh-LBS| |shin-LBS| |blend-LBS|, weight thigh shin, thigh holds at LBS, shin seams, shin holds at LBS, shin-labelled, folded"
        );
        for (b, e) in bins.iter().enumerate() {
            if e[0] == 0.0 {
                continue;
            }
            let m = |x: f64| x / e[0];
            eprintln!(
                "  {:.1}-{:.1}: {:>5} | {:>6.2} {:>6.2} {:>6.2} {:>6.2} | {:.2} {:.2} | {:>4} {:>4} {:>4} {:>4} | {:>4}",
                0.6 + 0.1 * b as f64,
                0.7 + 0.1 * b as f64,
                e[0],
                100.0 * m(e[1]),
                100.0 * m(e[2]),
                100.0 * m(e[3]),
                100.0 * m(e[4]),
                m(e[5]),
                m(e[6]),
                e[7],
                e[8],
                e[10],
                e[11],
                e[9]
            );
        }
    }
    // The folded vertices by the regions holding them.
    let mut kinds = std::collections::BTreeMap::<String, usize>::new();
    for &v in bad
        .iter()
        .flat_map(|&t| tris[t as usize])
        .collect::<std::collections::BTreeSet<u32>>()
        .iter()
    {
        let key: Vec<String> = res
            .iter()
            .filter_map(|r| {
                r.vertices.binary_search(&v).ok().map(|i| {
                    format!("{:?}:{:?}:{:.2}", r.joint, r.held[i], r.weights[i])
                        .chars()
                        .take(18)
                        .collect()
                })
            })
            .collect();
        let key: Vec<String> = key
            .iter()
            .map(|s: &String| s.split(':').take(2).collect::<Vec<_>>().join(":"))
            .collect();
        *kinds.entry(key.join(" + ")).or_default() += 1;
    }
    let mut kinds: Vec<_> = kinds.into_iter().collect();
    kinds.sort_by_key(|&(_, c)| std::cmp::Reverse(c));
    eprintln!("folded vertices by region:held");
    for (kd, c) in kinds.iter().take(12) {
        eprintln!("  {c:>5} {kd}");
    }
}

/// Triangle-frames the part-based solve turns over before any repair,
/// over every frame of `raw`, with `opts` (its repair off).
fn folds_before_repair(ch: &Character, raw: &Output, opts: &DeformOptions) -> usize {
    let n = ch.n();
    let tris = ch.topology().triangles();
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
    let mut ws = bare.workspace();
    let mut out = vec![[0.0; 3]; n];
    let mut turn = vec![glam::DQuat::IDENTITY; n];
    (0..raw.report.frames)
        .map(|k| {
            let src = &raw.positions[k * n..(k + 1) * n];
            let sp = ch.rig().frame_joints(src);
            let target = &raw.query[k];
            bare.deform(ch, src, &sp, target, &mut out, &mut ws);
            let g = surfmotion::pose::pose_rotations(&sp, target);
            unflip::skin_turns(ch.rig().skin(), &g, &mut turn);
            unflip::turned_over(tris, src, &out, &turn).len()
        })
        .sum()
}

/// Fewer folds where the thigh and shin regions overlap (issue 42): CMU
/// 02_02 retargeted onto the real samba capture, triangle-frames the
/// part-based solve turns over before any repair, with the default
/// options `seam_by_weight` and `hold_spread` (off by default) against
/// session 22's (every seam at full weight, every `stride`-th held joint
/// vertex at full weight, the default): the old options turn
/// over more than 3,000 (3,599 measured in session 22) and the default
/// fewer (measured through `retarget --json`: 3,683 → 3,521; a small
/// step, not the fix issue 42 asks for).
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_knees_fold_less_before_the_repair() {
    let Some((ch, raw)) = samba_clip("cmu-amc/02/02_02.amc") else {
        return;
    };
    let old = folds_before_repair(
        &ch,
        &raw,
        &DeformOptions {
            seam_by_weight: false,
            hold_spread: false,
            ..Default::default()
        },
    );
    let new = folds_before_repair(
        &ch,
        &raw,
        &DeformOptions {
            seam_by_weight: true,
            hold_spread: true,
            ..Default::default()
        },
    );
    eprintln!(
        "02_02 on samba, triangle-frames turned over before the repair: session 22's options {old}, default {new}"
    );
    assert!(old > 3_000, "session 22's options: {old}");
    assert!(new < old, "default {new} against {old}");
}

/// Per region with a parent, the mean and largest distance (cm) over the
/// frames of `raw` between the region's result at a seam vertex and the
/// parent region's own result there, with `opts`.
fn seam_gaps(ch: &Character, raw: &Output, opts: &DeformOptions) -> Vec<(String, f64, f64)> {
    use surfmotion::deform::Held;
    let n = ch.n();
    let def = Deformer::new(ch, DeformMode::Part, opts).unwrap();
    let mut ws = def.workspace();
    let mut out = vec![[0.0; 3]; n];
    let mut gaps = std::collections::BTreeMap::<String, (f64, usize, f64)>::new();
    for k in 0..raw.report.frames {
        let src = &raw.positions[k * n..(k + 1) * n];
        let sp = ch.rig().frame_joints(src);
        def.deform(ch, src, &sp, &raw.query[k], &mut out, &mut ws);
        let res = def.region_results(&raw.query[k], &ws);
        for r in &res {
            let Some(parent) = Part::of_joint(r.joint).parent() else {
                continue;
            };
            let pj = surfmotion::deform::part_joint(parent);
            let Some(p) = res.iter().find(|q| q.joint == pj) else {
                continue;
            };
            let e = gaps
                .entry(Part::of_joint(r.joint).name().to_string())
                .or_default();
            for (i, &v) in r.vertices.iter().enumerate() {
                if r.held[i] != Held::Seam {
                    continue;
                }
                let j = p
                    .vertices
                    .binary_search(&v)
                    .expect("a seam vertex is the parent's");
                let (a, b) = (r.positions[i], p.positions[j]);
                let d = 100.0
                    * ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2))
                        .sqrt();
                e.0 += d;
                e.1 += 1;
                e.2 = e.2.max(d);
            }
        }
    }
    gaps.into_iter()
        .filter(|(_, e)| e.1 > 0)
        .map(|(name, (s, c, m))| (name, s / c as f64, m))
        .collect()
}

/// A region meets its parent where it is seamed to it (issue 42, the left
/// shin 2-3 cm from its tie to the left thigh, the right 0.02 cm): with
/// `parent_seams` a seam vertex (weight 10) is held to the parent region's
/// own result. Without it the seams read the last region solved at the
/// vertex, so where the two thighs' regions overlap under the skirt the
/// left shin (solved after both thighs) is tied to the *right* thigh's
/// result. On the real samba capture and on the synthetic database, two
/// clips each (a walk; kicks and lunges), every frame: for every region
/// the mean gap is under 0.1 cm and the largest under 1 cm (measured on
/// 02_02, samba: left shin 0.010 / 0.124 cm); without `parent_seams` the
/// left shin's is not (1.16 / 16.4 cm: the test fails).
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_region_meets_its_parent_at_its_seams() {
    let Some(d) = common::data_dir() else { return };
    for db in [
        crate::deform::samba_capture_db(&d),
        common::synthetic_db(&d),
    ] {
        let ch = Character::load(&db, &surfmotion::db::Quiet).unwrap();
        for clip in ["cmu-amc/02/02_02.amc", "cmu-bvh/131_01.bvh"] {
            let raw = sources(&ch, &d, clip);
            let on = DeformOptions {
                parent_seams: true,
                ..Default::default()
            };
            let gaps = seam_gaps(&ch, &raw, &on);
            eprintln!(
                "{}, {clip}: seam gaps (region, mean cm, max cm) {gaps:.3?}",
                db.display()
            );
            assert!(gaps.len() >= 8, "{gaps:?}");
            for (name, mean, max) in &gaps {
                assert!(
                    *mean < 0.1 && *max < 1.0,
                    "{clip}, {name}: mean {mean:.3} cm, max {max:.3} cm"
                );
            }
        }
    }
}

/// Triangle-frames of `raw` turned over against the character's rest frame
/// (the surface measure's test, `eval`'s plausibility count) after the
/// deformation with `opts` and its repair, and those facing against their
/// own neighbourhoods' turns from the retrieved frame
/// ([`surfmotion::deform::near_turns::SurfaceFolds`], the deformation
/// tests' reading).
fn turned_over_after_repair(ch: &Character, raw: &Output, opts: &DeformOptions) -> (usize, usize) {
    use surfmotion::tools::eval::triangles::RestTriangles;
    let n = ch.n();
    let tris = ch.topology().triangles();
    let rest = ch.topology_metres();
    let rt = RestTriangles::new(rest.positions(), rest.triangles()).unwrap();
    let mut folds = surfmotion::deform::near_turns::SurfaceFolds::new(n, tris);
    let mut frames = raw.positions.clone();
    let def = Deformer::new(ch, DeformMode::Part, opts).unwrap();
    let mut ws = def.workspace();
    let mut near = 0;
    for (k, f) in frames.chunks_exact_mut(n).enumerate() {
        let src = &raw.positions[k * n..(k + 1) * n];
        let sp = ch.rig().frame_joints(src);
        def.deform(ch, src, &sp, &raw.query[k], f, &mut ws);
        near += folds.turned_over(tris, src, f).len();
    }
    (rt.per_frame(&frames).iter().sum(), near)
}

/// The parent's seams with the repair finished against the surface's own
/// turns (issue 42: `parent_seams`, `RepairTurns::SkinThenSurface`, the
/// default since session 26) leave fewer triangles turned over against the
/// rest frame after the repair than the old default (the seam read off the
/// last region solved, the repair against the skin's turns only), which
/// with `parent_seams` alone
/// left more on three of four clips (02_02 on samba: 465 → 735). On the
/// real samba capture, CMU 02_02 mirrored left to right and played
/// backwards (each retrieved anew: other sources, other folds). And the
/// default leaves no triangle facing against its own neighbourhood there
/// (session 27: the surface repair's rounds until none does; the old
/// default leaves some, so that count can fail).
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_parent_seams_and_surface_repair_leave_fewer_turned_over_after_the_repair() {
    let Some(d) = common::data_dir() else { return };
    let ch = Character::load(&crate::deform::samba_capture_db(&d), &surfmotion::db::Quiet).unwrap();
    let def = DeformOptions::default();
    assert!(def.parent_seams && def.repair_turns == RepairTurns::SkinThenSurface);
    let old = DeformOptions {
        parent_seams: false,
        repair_turns: RepairTurns::Skin,
        ..Default::default()
    };
    let m = load_mocap(
        &d.join("mocap/cmu-amc/02/02_02.amc"),
        &Default::default(),
        30.0,
    )
    .unwrap();
    let backwards: Vec<_> = m.poses.iter().rev().copied().collect();
    for (name, poses) in [
        ("mirrored", common::mirrored_clip(&m.poses)),
        ("backwards", backwards),
    ] {
        let opts = DriveOptions {
            deform: DeformMode::None,
            ..Default::default()
        };
        let raw = synthesise(&ch, &poses, &m.reference, 30.0, &opts).unwrap();
        let ((before, old_near), (now, near)) = (
            turned_over_after_repair(&ch, &raw, &old),
            turned_over_after_repair(&ch, &raw, &def),
        );
        eprintln!(
            "02_02 {name} on samba, triangle-frames turned over after the repair against the rest frame / against their own neighbourhoods: old default {before} / {old_near}, default (parent seams and surface repair) {now} / {near}"
        );
        assert!(old_near > 0, "{name}: the old default left no fold to find");
        assert_eq!(
            near, 0,
            "{name}: {near} facing against their neighbourhoods"
        );
        // Strictly fewer: the old default itself reads equal and fails here.
        assert!(
            now < before,
            "{name}: default {now} against the old default {before}"
        );
    }
}
