//! The deformation regions of a character: the parts in solve order,
//! their example frames, constraints and blending weights (the module
//! page, [`crate::deform`], describes the method).

use super::options::{DeformMode, DeformOptions};
use super::part_laplacian::{RegionSolver, apply};
use crate::db::Character;
use crate::embed::parts::Part;
use crate::graph::FlatFrame;
use crate::pose::pose_rotations;
use crate::rig::Canonical;
use glam::{DQuat, DVec3};

/// How a region's vertex is constrained in its solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Held {
    /// Only by the Laplacian and the deformation space.
    Free,
    /// To its LBS position.
    Lbs,
    /// To the parent region's result (a seam).
    Seam,
    /// To the target shared with an overlapping sibling region
    /// ([`DeformOptions::overlap_weight`]).
    Shared,
}

/// The joint whose rotation carries a part.
pub fn part_joint(p: Part) -> Canonical {
    use Canonical as C;
    match p {
        Part::Torso => C::Pelvis,
        Part::Head => C::Neck,
        Part::LUpperArm => C::LShoulder,
        Part::LForearm => C::LElbow,
        Part::RUpperArm => C::RShoulder,
        Part::RForearm => C::RElbow,
        Part::LThigh => C::LHip,
        Part::LShin => C::LKnee,
        Part::LFoot => C::LAnkle,
        Part::RThigh => C::RHip,
        Part::RShin => C::RKnee,
        Part::RFoot => C::RAnkle,
    }
}

/// A region to build: vertices, carrying joint, parent (index in the
/// list), joints whose rotations choose examples, vertices it owns.
pub(super) type RegionSpec = (Vec<u32>, Canonical, Option<usize>, Vec<Canonical>, Vec<u32>);

/// Where a region constraint's target comes from in a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Target {
    /// The vertex's LBS position (global id).
    Lbs(u32),
    /// Another region's own result (a seam): that region's index and the
    /// vertex's local index in it.
    Region(u32, u32),
    /// The overlap's shared target (global id): the LBS position, then the
    /// overlapping siblings' blended results
    /// ([`DeformOptions::overlap_weight`]).
    Shared(u32),
    /// The result of the last region solved that has the vertex (global
    /// id): the seams' target without [`DeformOptions::parent_seams`].
    /// Where a child's parent overlaps a sibling solved after it (the two
    /// thighs under a skirt, solved left then right), that is the
    /// sibling's result, not the parent's.
    Last(u32),
}

pub(super) struct Region {
    pub(super) joint: Canonical,
    pub(super) solver: RegionSolver,
    /// Per constraint: where its target comes from.
    pub(super) targets: Vec<Target>,
    /// Regions overlapping this one with the same parent (the other thigh
    /// under a skirt), when it holds the overlap
    /// ([`DeformOptions::overlap_weight`]).
    pub(super) siblings: Vec<usize>,
    /// Weight of this region's result at each local vertex (its part's
    /// skin weight): overlapping regions are blended by it.
    pub(super) weights: Vec<f64>,
}

pub(super) fn fps_examples(rot: &[Vec<DQuat>], want: usize) -> Vec<usize> {
    let nf = rot.len();
    if nf == 0 {
        return Vec::new();
    }
    let dist = |a: usize, b: usize| -> f64 {
        rot[a]
            .iter()
            .zip(&rot[b])
            .map(|(p, q)| p.angle_between(*q))
            .sum()
    };
    // Start from the frame closest to the rest pose.
    let start = (0..nf)
        .min_by(|&a, &b| {
            let d = |f: usize| {
                rot[f]
                    .iter()
                    .map(|q| q.angle_between(DQuat::IDENTITY))
                    .sum::<f64>()
            };
            d(a).total_cmp(&d(b))
        })
        .unwrap_or(0);
    let mut chosen = vec![start];
    let mut near: Vec<f64> = (0..nf).map(|f| dist(f, start)).collect();
    while chosen.len() < want.min(nf) {
        let (f, d) = near
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(f, d)| (f, *d))
            .unwrap_or((0, 0.0));
        if d <= 1e-9 {
            break;
        }
        chosen.push(f);
        for (g, v) in near.iter_mut().enumerate() {
            *v = v.min(dist(g, f));
        }
    }
    chosen
}

/// The deformation regions in solve order (parents before children), each
/// with its vertices, joint, parent (index in this list), the joints whose
/// rotations its examples cover, and the vertices it owns: one region for
/// the whole body (`Global`), else one per body part (its region of the
/// embedding plus the vertices labelled with it).
pub(super) fn region_specs(ch: &Character, mode: DeformMode) -> Vec<RegionSpec> {
    let n = ch.n();
    let rig = ch.rig();
    match mode {
        DeformMode::Global => vec![(
            (0..n as u32).collect(),
            Canonical::Pelvis,
            None,
            Canonical::ALL.to_vec(),
            (0..n as u32).collect(),
        )],
        _ => {
            let order = [
                Part::Torso,
                Part::Head,
                Part::LUpperArm,
                Part::RUpperArm,
                Part::LThigh,
                Part::RThigh,
                Part::LForearm,
                Part::RForearm,
                Part::LShin,
                Part::RShin,
                Part::LFoot,
                Part::RFoot,
            ];
            order
                .iter()
                .map(|&p| {
                    let mut verts = rig.regions[p.index()].clone();
                    let owns: Vec<u32> = (0..n as u32)
                        .filter(|&v| rig.labels[v as usize] as usize == p.index())
                        .collect();
                    verts.extend(&owns);
                    verts.sort_unstable();
                    verts.dedup();
                    let parent = p.parent().and_then(|q| order.iter().position(|&o| o == q));
                    (verts, part_joint(p), parent, vec![part_joint(p)], owns)
                })
                .collect()
        }
    }
}

/// Per region of `specs` ([`region_specs`]), which of the `n` vertices
/// it shares with a sibling region (another child of the same parent: the
/// two thighs' regions under a skirt).
pub(super) fn sibling_overlaps(specs: &[RegionSpec], n: usize) -> Vec<Vec<bool>> {
    specs
        .iter()
        .enumerate()
        .map(|(i, (verts, _, parent, _, _))| {
            let mut count = vec![0u8; n];
            for (j, (other, _, p, _, _)) in specs.iter().enumerate() {
                if j != i && parent.is_some() && p == parent {
                    for &v in other {
                        count[v as usize] = 1;
                    }
                }
            }
            let mut shared = vec![false; n];
            for &v in verts {
                shared[v as usize] = count[v as usize] > 0;
            }
            shared
        })
        .collect()
}

/// The example frames of a region (database ids: the override, else the
/// frames farthest apart in the rotations of `example_joints`, plus
/// `opts.include`) and their differential coordinates `L x` on the region
/// (`lap`), turned into the joint's frame when `opts.local_frames`. `buf`
/// is scratch of one frame.
pub(super) fn region_examples(
    ch: &Character,
    verts: &[u32],
    lap: &[Vec<(u32, f64)>],
    joint: Canonical,
    example_joints: &[Canonical],
    opts: &DeformOptions,
    buf: &mut [[f64; 3]],
) -> (Vec<FlatFrame>, Vec<Vec<[f64; 3]>>) {
    let nf = ch.frame_count();
    // Examples covering the region's rotations, chosen once per database
    // (kept in its cache: `db::examples`).
    let mut chosen = match ch.example_override() {
        Some(e) => e.to_vec(),
        None => ch.examples().chosen(example_joints, opts.examples, || {
            let rots: Vec<Vec<DQuat>> = (0..nf)
                .map(|f| {
                    let g = pose_rotations(ch.rest_pose(), &ch.poses()[f]);
                    example_joints.iter().map(|j| g[j.index()]).collect()
                })
                .collect();
            fps_examples(&rots, opts.examples)
                .into_iter()
                .map(FlatFrame::from_index)
                .collect()
        }),
    };
    if let Some(f) = opts
        .include
        .filter(|&f| f.index() < nf && !chosen.contains(&f))
    {
        chosen.push(f);
    }
    ch.prefetch_frames(&chosen);
    let mut examples = Vec::with_capacity(chosen.len());
    for &f in &chosen {
        ch.frame_metres(f, buf);
        let x: Vec<[f64; 3]> = verts.iter().map(|&v| buf[v as usize]).collect();
        let mut d = vec![[0.0; 3]; x.len()];
        apply(lap, &x, &mut d);
        let r = if opts.local_frames {
            pose_rotations(ch.rest_pose(), ch.pose(f))[joint.index()].inverse()
        } else {
            DQuat::IDENTITY
        };
        for v in d.iter_mut() {
            *v = (r * DVec3::from_array(*v)).to_array();
        }
        examples.push(d);
    }
    (chosen, examples)
}

/// Where a region constraint's target comes from: the global vertex and
/// how it is held ([`Held::Lbs`], [`Held::Seam`]: the parent's result, or
/// [`Held::Shared`]: the overlap's shared target).
pub(super) type RegionSource = (u32, Held);

/// Per local vertex of a region, the factor of its seam weight and of its
/// held-joint weight ([`DeformOptions::seam_by_weight`],
/// [`DeformOptions::hold_by_weight`]); empty: 1 everywhere.
#[derive(Debug, Default)]
pub(super) struct ConstraintScale {
    pub(super) seam: Vec<f64>,
    pub(super) hold: Vec<f64>,
}

/// The factors of [`ConstraintScale`] for a region with `verts` and
/// blending `weights`, whose parent region has `parent_verts` and
/// `parent_weights`: a seam by the parent's share `w_p / (w_p + w)`, a
/// held vertex by the region's share of its weight and the skin weight
/// of the part the vertex is labelled with, `w / (w + w_c)` (1 where both
/// are 0).
pub(super) fn constraint_scale(
    ch: &Character,
    opts: &DeformOptions,
    verts: &[u32],
    weights: &[f64],
    parent: Option<(&[u32], &[f64])>,
) -> ConstraintScale {
    let share = |a: f64, b: f64| if a + b > 0.0 { a / (a + b) } else { 1.0 };
    let seam = match parent {
        Some((pv, pw)) if opts.seam_by_weight => verts
            .iter()
            .zip(weights)
            .map(|(v, &w)| match pv.binary_search(v) {
                Ok(j) => share(pw[j], w),
                Err(_) => 1.0,
            })
            .collect(),
        _ => Vec::new(),
    };
    let hold = if opts.hold_by_weight {
        let rig = ch.rig();
        verts
            .iter()
            .zip(weights)
            .map(|(&v, &w)| {
                let label = rig.labels[v as usize] as usize;
                let (js, ws) = &rig.skin[v as usize];
                let wc: f64 = js
                    .iter()
                    .zip(ws)
                    .filter(|(j, _)| Part::of_joint(Canonical::ALL[**j as usize]).index() == label)
                    .map(|(_, w)| *w)
                    .sum();
                share(w, wc)
            })
            .collect()
    } else {
        Vec::new()
    };
    ConstraintScale { seam, hold }
}

/// The soft constraints of a region, `(local index, weight)`, with their
/// sources `(global vertex, from the parent's result)`: seams with the
/// parent region first, then the LBS constraint vertices (and, with
/// `hold_joints`, a spread of the child parts' vertices, those `soft` does
/// not exclude); a region with none of those constrains a spread of its
/// own vertices. With `overlap_weight` above 0, the vertices `shared`
/// marks (in a sibling region too) that are not seams are held with it
/// at the overlap's shared target.
#[allow(clippy::too_many_arguments)]
pub(super) fn region_constraints(
    ch: &Character,
    mode: DeformMode,
    opts: &DeformOptions,
    verts: &[u32],
    joint: Canonical,
    parent_verts: Option<&[u32]>,
    is_constraint: &[bool],
    soft: &[bool],
    shared: &[bool],
    scale: &ConstraintScale,
) -> (Vec<(u32, f64)>, Vec<RegionSource>) {
    let rig = ch.rig();
    let mut constraints = Vec::new();
    let mut sources = Vec::new();
    for (i, &v) in verts.iter().enumerate() {
        let seam = parent_verts.is_some_and(|pv| pv.binary_search(&v).is_ok());
        if seam {
            let s = scale.seam.get(i).copied().unwrap_or(1.0);
            constraints.push((i as u32, opts.seam_weight * s));
            sources.push((v, Held::Seam));
        } else if opts.overlap_weight > 0.0 && shared.get(v as usize) == Some(&true) {
            constraints.push((i as u32, opts.overlap_weight));
            sources.push((v, Held::Shared));
        } else if is_constraint[v as usize] {
            constraints.push((i as u32, opts.constraint_weight));
            sources.push((v, Held::Lbs));
        } else if opts.hold_joints
            && mode == DeformMode::Part
            && (opts.hold_spread || i % opts.stride.max(1) == 0)
            && !soft[v as usize]
            && Part::ALL
                .get(rig.labels[v as usize] as usize)
                .is_some_and(|c| c.parent() == Some(Part::of_joint(joint)))
        {
            let mut s = scale.hold.get(i).copied().unwrap_or(1.0);
            if opts.hold_spread {
                // The same total pull as every `stride`-th vertex held
                // with the full weight, spread over all of them.
                s /= (opts.stride.max(1) as f64).sqrt();
            }
            constraints.push((i as u32, opts.constraint_weight * s));
            sources.push((v, Held::Lbs));
        }
    }
    if constraints.is_empty() {
        // A region with no eligible vertex: constrain a spread of its own.
        for (i, &v) in verts.iter().enumerate().step_by(opts.stride.max(1)) {
            constraints.push((i as u32, opts.constraint_weight));
            sources.push((v, Held::Lbs));
        }
    }
    (constraints, sources)
}

/// The skin weight above which a vertex joins a part's region
/// ([`crate::embed::parts::regions`], as the embedding calls it).
const REGION_MIN: f64 = 0.1;

/// The weight of a region's result at each of its vertices: 1 for the
/// whole body, else the vertex's skin weight on the region's part (at least
/// 1e-3 for a vertex labelled with the part), so overlapping regions blend.
/// With `taper` ([`DeformOptions::blend_taper`]) a vertex not labelled
/// with the part has `(w − 0.1) / 0.9`, so the weight falls to 0 at the
/// region's edge (where the skin weight crosses the region's threshold)
/// instead of stepping from 0.1 to 0.
pub(super) fn region_weights(
    ch: &Character,
    mode: DeformMode,
    verts: &[u32],
    joint: Canonical,
    taper: bool,
) -> Vec<f64> {
    let rig = ch.rig();
    match mode {
        DeformMode::Global => vec![1.0; verts.len()],
        _ => {
            let part = Part::of_joint(joint);
            verts
                .iter()
                .map(|&v| {
                    let (js, ws) = &rig.skin[v as usize];
                    let w: f64 = js
                        .iter()
                        .zip(ws)
                        .filter(|(j, _)| Part::of_joint(Canonical::ALL[**j as usize]) == part)
                        .map(|(_, w)| *w)
                        .sum();
                    // A vertex labelled with the part always counts.
                    if rig.labels[v as usize] as usize == part.index() {
                        w.max(1e-3)
                    } else if taper {
                        ((w - REGION_MIN) / (1.0 - REGION_MIN)).max(0.0)
                    } else {
                        w
                    }
                })
                .collect()
        }
    }
}
