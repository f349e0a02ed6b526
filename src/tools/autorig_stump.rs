//! Where the automatic rig puts a headless body's head and neck joints
//! (issue 41, partial bodies; `autorig_eval … headless`): the head joint
//! against the centre of the cut's rim (the kept vertices next to a
//! removed one), the neck joint against the skeleton that drove each
//! frame, and the heights along up of the rim's centre, the necks and the
//! shoulders (the rig's and the fixture rig's, on the rest positions).

use super::autorig_cut::{CutRig, Outcome};
use crate::embed::Embedding;
use crate::rig::Canonical;
use glam::DVec3;

/// One row's head and neck figures.
pub struct NeckAndHead {
    /// The head joint's distance from the rim's centre (% of the cut
    /// body's height, [`Embedding::height`], as `embed::auto_headless`
    /// bounds it); `None` for a whole body.
    pub head_to_rim: Option<f64>,
    /// The neck joint's mean distance over the frames from the driving
    /// skeleton's (% of the whole body's height).
    pub neck_error: f64,
    /// The heights, for the details.
    pub depths: String,
}

/// [`NeckAndHead`] of `case` rigged as `mine` (the whole body's rest
/// positions `rest`, neighbours `nb`).
pub fn neck_and_head(
    case: &CutRig,
    mine: &Embedding,
    rest: &[[f64; 3]],
    nb: &[Vec<u32>],
) -> NeckAndHead {
    let neck = Canonical::Neck.index();
    let s: f64 = case
        .frames
        .iter()
        .zip(case.poses)
        .map(|(f, pose)| mine.frame_joints(f)[neck].distance(pose[neck]))
        .sum();
    let k = case.frames.len().min(case.poses.len());
    let h = case.rig.height();
    let neck_error = 100.0 * s / k.max(1) as f64 / h;
    let up = DVec3::from_array(mine.up());
    let at = |e: &Embedding, c: Canonical| DVec3::from_array(e.joints()[c.index()]);
    let shoulders =
        |e: &Embedding| (at(e, Canonical::LShoulder) + at(e, Canonical::RShoulder)) * 0.5;
    let pc = |x: f64| 100.0 * x / h;
    let mut depths = format!(
        "neck above the shoulders: rig {:.2}, truth {:.2} (% height)",
        pc((at(mine, Canonical::Neck) - shoulders(mine)).dot(up)),
        pc((at(case.rig, Canonical::Neck) - shoulders(case.rig)).dot(up)),
    );
    let rim = case.rim(rest, nb);
    let head_to_rim = (!rim.is_empty()).then(|| {
        let c = rim.iter().sum::<DVec3>() / rim.len() as f64;
        depths += &format!(
            "; the rim's centre above the neck: rig {:.2}, truth {:.2}; above the shoulders: rig {:.2}, truth {:.2}",
            pc((c - at(mine, Canonical::Neck)).dot(up)),
            pc((c - at(case.rig, Canonical::Neck)).dot(up)),
            pc((c - shoulders(mine)).dot(up)),
            pc((c - shoulders(case.rig)).dot(up)),
        );
        if let Some(m) = &case.mesh {
            depths += &format!("; radii below the rim's centre: {}", radii(m.positions(), c, up, h));
            depths += &rim_loops(case, m);
        }
        100.0 * at(mine, Canonical::Head).distance(c) / mine.height()
    });
    NeckAndHead {
        head_to_rim,
        neck_error,
        depths,
    }
}

/// How far across `up` the body reaches from the vertical through `c`
/// (within 15 % of the height of it) in sections 1 % of the height `h`
/// apart going down from `c`, % of the height: a neck's half width, then
/// the shoulders'.
fn radii(p: &[[f64; 3]], c: DVec3, up: DVec3, h: f64) -> String {
    let mut out = [0.0f64; 10];
    for q in p {
        let d = DVec3::from_array(*q) - c;
        let (below, across) = (-d.dot(up) / h, (d - up * d.dot(up)).length() / h);
        let k = (100.0 * below).round();
        if (0.0..10.0).contains(&k) && across < 0.15 {
            out[k as usize] = out[k as usize].max(100.0 * across);
        }
    }
    out.iter()
        .map(|r| format!("{r:.1}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The cut body's boundary loops as the embedding reads them for its
/// stump's top (`embed::stump::rim_loops` on the rest frame the rig chose,
/// the automatic landmarks moved to it), the highest four: centroid off
/// the axis, vertices' reach, below the top, from the arms (% height),
/// and whether each passes at the default reach; empty unless rigged
/// headless.
fn rim_loops(case: &CutRig, m: &crate::mesh::Mesh) -> String {
    use crate::embed::stump;
    let Outcome::Rigged(b) = &case.outcome else {
        return String::new();
    };
    let auto = &b.0;
    if !auto.headless {
        return String::new();
    }
    let (p, lm) = match auto.rest_frame.and_then(|r| case.frames.get(r)) {
        Some(f) => (
            f.as_slice(),
            auto.landmarks.moved(m.positions(), f, m.triangles()),
        ),
        None => (m.positions(), auto.landmarks.clone()),
    };
    let mut loops = stump::rim_loops(&lm, p, m.triangles());
    loops.sort_by(|a, b| a.below_top.total_cmp(&b.below_top));
    let each: Vec<String> = loops
        .iter()
        .take(4)
        .map(|l| {
            format!(
                "{} v, off {:.1}, reach {:.1}, below {:.1}, arms {:.1}{}",
                l.vertices,
                100.0 * l.off_axis,
                100.0 * l.reach,
                100.0 * l.below_top,
                100.0 * l.from_arms,
                if l.passes(stump::RIM_REACH) {
                    " (passes)"
                } else {
                    ""
                }
            )
        })
        .collect();
    format!(
        "; boundary loops ({} in all, the highest first): {}",
        loops.len(),
        each.join("; ")
    )
}
