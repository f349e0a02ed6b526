//! The `Deformer`: a character's prefactored part-based deformation
//! (the module page, [`crate::deform`], describes the method).

use super::part_laplacian::{RegionSolver, RegionWorkspace, apply};
use super::{lbs, pca, unflip, untangle};
use crate::db::Character;
use crate::embed::parts::Part;
use crate::mesh::laplacian::uniform_region_rows;
use crate::mesh::solver::SolveError;
use crate::pose::{Pose, pose_rotations};
use crate::rig::Canonical;
use glam::{DQuat, DVec3};
use rayon::prelude::*;

/// How retrieved frames are made to follow the query skeleton.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DeformMode {
    /// Part-based PCA Laplacian deformation (the paper's method).
    #[default]
    Part,
    /// One PCA Laplacian deformation space for the whole body.
    Global,
    /// Plain linear blend skinning of the retrieved frame.
    Lbs,
    /// No deformation: the interpolated retrieval.
    None,
}

impl std::fmt::Display for DeformMode {
    /// The words a report uses for the mode.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Part => "part-based PCA Laplacian",
            Self::Global => "whole-body PCA Laplacian",
            Self::Lbs => "linear blend skinning",
            Self::None => "none (the interpolated retrieval)",
        })
    }
}

/// Triangles turned over relative to the source frame (see [`unflip`]),
/// before and after the repair.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct TurnedOver {
    /// After the deformation's solve.
    pub before: usize,
    /// After the repair and untangling.
    pub after: usize,
}

/// Options of the deformation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeformOptions {
    /// Share of the examples' variance the basis keeps. Default: 0.95.
    pub keep: f64,
    /// Example frames per part (or for the whole body). Default: 40.
    pub examples: usize,
    /// Weight of an LBS constraint. Default: 1.
    pub constraint_weight: f64,
    /// Weight of a vertex shared with the parent part. Default: 10.
    pub seam_weight: f64,
    /// Keep every `stride`-th eligible constraint vertex. Default: 4.
    pub stride: usize,
    /// A database frame (flat id, [`crate::graph::SurfaceMotionGraph::flat_id`])
    /// every region uses as an example (besides those chosen
    /// automatically). Default: none.
    pub include: Option<u32>,
    /// Learn and solve each part in its own rotating frame (true) or in
    /// world coordinates as the paper does (false). Default: true.
    pub local_frames: bool,
    /// Repair of triangles the solve turned over ([`unflip`]); `rounds: 0`
    /// turns it (and the untangling) off.
    pub repair: unflip::RepairOptions,
    /// Local untangling after each repair pass ([`untangle`]).
    pub untangle: untangle::UntangleOptions,
    /// Repair + untangle passes while triangles stay turned over; the
    /// best pass is kept. Default 3 (measured on the samba database: one
    /// pass leaves a few on the hardest queries, e.g. 1 on CMU 131_01, three
    /// leave none on the nine retarget queries).
    pub repair_passes: usize,
    /// Hold the part of a region that lies in a child part (the thigh's
    /// region below the knee, the torso's inside the thighs and upper arms)
    /// at its LBS positions, every `stride`-th vertex, with
    /// `constraint_weight`. Default true. Without it that end of the
    /// region is extrapolated from the mid-bone constraints along the
    /// retrieved frame's differential coordinates, and the child, seamed to
    /// it, inherits the error at the joint: on the samba database the knees
    /// crumpled and were pushed back (hyper-extension p95 18.8° on CMU
    /// 02_02, 0.0° with it; joint-velocity error 0.34 → 0.16 cm/frame).
    pub hold_joints: bool,
}

impl Default for DeformOptions {
    fn default() -> Self {
        DeformOptions {
            keep: 0.95,
            examples: 40,
            constraint_weight: 1.0,
            seam_weight: 10.0,
            stride: 4,
            include: None,
            local_frames: true,
            repair: unflip::RepairOptions::default(),
            untangle: untangle::UntangleOptions::default(),
            repair_passes: 3,
            hold_joints: true,
        }
    }
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
type RegionSpec = (Vec<u32>, Canonical, Option<usize>, Vec<Canonical>, Vec<u32>);

struct Region {
    joint: Canonical,
    solver: RegionSolver,
    /// Per constraint: global vertex and whether it is a seam (parent's result).
    sources: Vec<(u32, bool)>,
    /// Weight of this region's result at each local vertex (its part's
    /// skin weight): overlapping regions are blended by it.
    weights: Vec<f64>,
}

/// A character's prefactored deformation.
pub struct Deformer {
    mode: DeformMode,
    local_frames: bool,
    /// Vertex adjacency for the turned-over repair (when on).
    adjacency: Option<unflip::Adjacency>,
    repair: unflip::RepairOptions,
    untangle: untangle::UntangleOptions,
    repair_passes: usize,
    triangles: usize,
    regions: Vec<Region>,
    rest_pose: Pose,
    n: usize,
    /// Constraint vertices (global) of the LBS.
    pub constraint_vertices: Vec<u32>,
    /// Basis sizes (components per region).
    pub components: Vec<usize>,
    /// Example frames (flat database ids) of each region.
    pub examples: Vec<Vec<u32>>,
}

/// Scratch of [`Deformer::deform`].
pub struct DeformWorkspace {
    lbs: Vec<[f64; 3]>,
    turn: Vec<DQuat>,
    xs: Vec<Vec<[f64; 3]>>,
    delta: Vec<Vec<[f64; 3]>>,
    acc: Vec<[f64; 3]>,
    wsum: Vec<f64>,
    solved: Vec<[f64; 3]>,
    targets: Vec<Vec<[f64; 3]>>,
    local: Vec<Vec<[f64; 3]>>,
    ws: Vec<RegionWorkspace>,
    /// Reference normals and source areas of the triangles (untangling).
    normals: Vec<DVec3>,
    areas: Vec<f64>,
    /// The best repair pass so far.
    best: Vec<[f64; 3]>,
    /// The deformed frame before its repair, then the fixed budget's
    /// repair while the adaptive one runs.
    start: Vec<[f64; 3]>,
}

fn fps_examples(rot: &[Vec<DQuat>], want: usize) -> Vec<usize> {
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
fn region_specs(ch: &Character, mode: DeformMode) -> Vec<RegionSpec> {
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

/// The example frames of a region (database ids: the override, else the
/// frames farthest apart in the rotations of `example_joints`, plus
/// `opts.include`) and their differential coordinates `L x` on the region
/// (`lap`), turned into the joint's frame when `opts.local_frames`. `buf`
/// is scratch of one frame.
fn region_examples(
    ch: &Character,
    verts: &[u32],
    lap: &[Vec<(u32, f64)>],
    joint: Canonical,
    example_joints: &[Canonical],
    opts: &DeformOptions,
    buf: &mut [[f64; 3]],
) -> (Vec<u32>, Vec<Vec<[f64; 3]>>) {
    let nf = ch.frame_count();
    // Examples covering the region's rotations.
    let rots: Vec<Vec<DQuat>> = (0..nf)
        .map(|f| {
            let g = pose_rotations(ch.rest_pose(), &ch.poses()[f]);
            example_joints.iter().map(|j| g[j.index()]).collect()
        })
        .collect();
    let mut chosen = match ch.example_override() {
        Some(e) => e.to_vec(),
        None => fps_examples(&rots, opts.examples)
            .into_iter()
            .map(|f| f as u32)
            .collect(),
    };
    if let Some(f) = opts
        .include
        .filter(|&f| (f as usize) < nf && !chosen.contains(&f))
    {
        chosen.push(f);
    }
    let mut examples = Vec::with_capacity(chosen.len());
    for &f in &chosen {
        ch.frame_metres(f, buf);
        let x: Vec<[f64; 3]> = verts.iter().map(|&v| buf[v as usize]).collect();
        let mut d = vec![[0.0; 3]; x.len()];
        apply(lap, &x, &mut d);
        let r = if opts.local_frames {
            pose_rotations(ch.rest_pose(), &ch.poses()[f as usize])[joint.index()].inverse()
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

/// Where a region constraint's target comes from: `(global vertex, from
/// the parent region's result)`.
type RegionSource = (u32, bool);

/// The soft constraints of a region, `(local index, weight)`, with their
/// sources `(global vertex, from the parent's result)`: seams with the
/// parent region first, then the LBS constraint vertices (and, with
/// `hold_joints`, a spread of the child parts' vertices); a region with
/// none of those constrains a spread of its own vertices.
fn region_constraints(
    ch: &Character,
    mode: DeformMode,
    opts: &DeformOptions,
    verts: &[u32],
    joint: Canonical,
    parent_verts: Option<&[u32]>,
    is_constraint: &[bool],
) -> (Vec<(u32, f64)>, Vec<RegionSource>) {
    let rig = ch.rig();
    let mut constraints = Vec::new();
    let mut sources = Vec::new();
    for (i, &v) in verts.iter().enumerate() {
        let seam = parent_verts.is_some_and(|pv| pv.binary_search(&v).is_ok());
        if seam {
            constraints.push((i as u32, opts.seam_weight));
            sources.push((v, true));
        } else if is_constraint[v as usize]
            || (opts.hold_joints
                && mode == DeformMode::Part
                && i % opts.stride.max(1) == 0
                && Part::ALL
                    .get(rig.labels[v as usize] as usize)
                    .is_some_and(|c| c.parent() == Some(Part::of_joint(joint))))
        {
            constraints.push((i as u32, opts.constraint_weight));
            sources.push((v, false));
        }
    }
    if constraints.is_empty() {
        // A region with no eligible vertex: constrain a spread of its own.
        for (i, &v) in verts.iter().enumerate().step_by(opts.stride.max(1)) {
            constraints.push((i as u32, opts.constraint_weight));
            sources.push((v, false));
        }
    }
    (constraints, sources)
}

/// The weight of a region's result at each of its vertices: 1 for the
/// whole body, else the vertex's skin weight on the region's part (at least
/// 1e-3 for a vertex labelled with the part), so overlapping regions blend.
fn region_weights(ch: &Character, mode: DeformMode, verts: &[u32], joint: Canonical) -> Vec<f64> {
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
                    } else {
                        w
                    }
                })
                .collect()
        }
    }
}

impl Deformer {
    /// Prefactors the deformation of a character (nothing for `Lbs`/`None`).
    ///
    /// The steps: the LBS constraint vertices, `region_specs` (the regions
    /// in solve order, parents first), then per region its uniform
    /// Laplacian, `region_examples` (the frames spanning its rotations and
    /// their differential coordinates, Huang et al. 2015 Sec. 5.2.3),
    /// the PCA basis, `region_constraints` (seams with the parent, then
    /// LBS vertices), `region_weights` and the prefactored Eq. 32 solver.
    pub fn new(
        ch: &Character,
        mode: DeformMode,
        opts: &DeformOptions,
    ) -> Result<Deformer, SolveError> {
        let n = ch.n();
        let constraint_vertices = match ch.constraint_override() {
            Some(c) => c.to_vec(),
            None => lbs::constraint_vertices(ch, opts.stride),
        };
        let mut out = Deformer {
            mode,
            local_frames: opts.local_frames,
            adjacency: (opts.repair.rounds > 0
                && matches!(mode, DeformMode::Part | DeformMode::Global))
            .then(|| unflip::Adjacency::new(n, ch.topology().triangles())),
            repair: opts.repair,
            untangle: opts.untangle,
            repair_passes: opts.repair_passes,
            triangles: ch.topology().triangle_count(),
            regions: Vec::new(),
            rest_pose: *ch.rest_pose(),
            n,
            constraint_vertices: constraint_vertices.clone(),
            components: Vec::new(),
            examples: Vec::new(),
        };
        if matches!(mode, DeformMode::Lbs | DeformMode::None) {
            return Ok(out);
        }
        let tris = ch.topology().triangles();
        let is_constraint = {
            let mut m = vec![false; n];
            for &v in &constraint_vertices {
                m[v as usize] = true;
            }
            m
        };
        let mut buf = vec![[0.0; 3]; n];
        let mut index_of: Vec<Option<usize>> = Vec::new();
        for (verts, joint, parent, example_joints, _owns) in region_specs(ch, mode) {
            if verts.is_empty() {
                index_of.push(None);
                continue;
            }
            index_of.push(Some(out.regions.len()));
            let parent = parent.and_then(|p| index_of.get(p).copied().flatten());
            let mut local = vec![u32::MAX; n];
            for (i, &v) in verts.iter().enumerate() {
                local[v as usize] = i as u32;
            }
            let lap = uniform_region_rows(tris, &local, verts.len());
            let (chosen, examples) =
                region_examples(ch, &verts, &lap, joint, &example_joints, opts, &mut buf);
            let basis = pca::pca(&examples, opts.keep);
            let parent_verts: Option<&Vec<u32>> = parent.map(|p| &out.regions[p].solver.vertices);
            let (constraints, sources) = region_constraints(
                ch,
                mode,
                opts,
                &verts,
                joint,
                parent_verts.map(Vec::as_slice),
                &is_constraint,
            );
            let weights = region_weights(ch, mode, &verts, joint);
            out.components.push(basis.components.len());
            out.examples.push(chosen);
            let solver = RegionSolver::new(tris, n, verts, constraints, &basis)?;
            out.regions.push(Region {
                joint,
                solver,
                sources,
                weights,
            });
        }
        Ok(out)
    }

    /// The mode.
    pub fn mode(&self) -> DeformMode {
        self.mode
    }

    /// Scratch space.
    pub fn workspace(&self) -> DeformWorkspace {
        DeformWorkspace {
            lbs: vec![[0.0; 3]; self.n],
            turn: vec![DQuat::IDENTITY; self.n],
            xs: self
                .regions
                .iter()
                .map(|r| vec![[0.0; 3]; r.solver.vertices.len()])
                .collect(),
            delta: self
                .regions
                .iter()
                .map(|r| vec![[0.0; 3]; r.solver.vertices.len()])
                .collect(),
            acc: vec![[0.0; 3]; self.n],
            wsum: vec![0.0; self.n],
            solved: vec![[0.0; 3]; self.n],
            targets: self
                .regions
                .iter()
                .map(|r| vec![[0.0; 3]; r.sources.len()])
                .collect(),
            local: self
                .regions
                .iter()
                .map(|r| vec![[0.0; 3]; r.solver.vertices.len()])
                .collect(),
            ws: self.regions.iter().map(|r| r.solver.workspace()).collect(),
            normals: vec![DVec3::ZERO; self.triangles],
            areas: vec![0.0; self.triangles],
            best: vec![[0.0; 3]; self.n],
            start: vec![[0.0; 3]; self.n],
        }
    }

    /// Deforms `source` (a retrieved frame whose skeleton is `source_pose`)
    /// to follow `target`, into `out`. Returns the triangles turned over
    /// before and after the repair (zero for modes without one).
    pub fn deform(
        &self,
        ch: &Character,
        source: &[[f64; 3]],
        source_pose: &Pose,
        target: &Pose,
        out: &mut [[f64; 3]],
        ws: &mut DeformWorkspace,
    ) -> TurnedOver {
        if self.mode == DeformMode::None {
            out.copy_from_slice(source);
            return TurnedOver::default();
        }
        let g = pose_rotations(source_pose, target);
        lbs::skin_into(source, ch.rig(), source_pose, target, &g, &mut ws.lbs);
        out.copy_from_slice(&ws.lbs);
        if self.mode == DeformMode::Lbs {
            return TurnedOver::default();
        }
        let rot = pose_rotations(&self.rest_pose, target);
        // Each vertex's rotation from source to target: its bones' turns,
        // blended by skin weight.
        unflip::skin_turns(&ch.rig().skin, &g, &mut ws.turn);
        ws.acc.fill([0.0; 3]);
        ws.wsum.fill(0.0);
        for (k, r) in self.regions.iter().enumerate() {
            let q = if self.local_frames {
                rot[r.joint.index()]
            } else {
                DQuat::IDENTITY
            };
            let qi = q.inverse();
            // δ₀: the source's Laplacian coordinates, each turned by its
            // vertex's skin-blended rotation from the source skeleton to the
            // target, in the part's frame. (A skirt vertex shared by both
            // thighs turns the same way in both solves.)
            for (x, &v) in ws.xs[k].iter_mut().zip(&r.solver.vertices) {
                *x = source[v as usize];
            }
            apply(r.solver.laplacian(), &ws.xs[k], &mut ws.delta[k]);
            for (dv, &v) in ws.delta[k].iter_mut().zip(&r.solver.vertices) {
                let turn = if self.local_frames {
                    qi * ws.turn[v as usize]
                } else {
                    DQuat::IDENTITY
                };
                *dv = (turn * DVec3::from_array(*dv)).to_array();
            }
            for (t, &(v, seam)) in ws.targets[k].iter_mut().zip(&r.sources) {
                let p = if seam {
                    ws.solved[v as usize]
                } else {
                    ws.lbs[v as usize]
                };
                *t = (qi * DVec3::from_array(p)).to_array();
            }
            r.solver.solve(
                &ws.delta[k],
                &ws.targets[k],
                &mut ws.local[k],
                &mut ws.ws[k],
            );
            for ((y, &v), &w) in ws.local[k].iter().zip(&r.solver.vertices).zip(&r.weights) {
                let x = (q * DVec3::from_array(*y)).to_array();
                ws.solved[v as usize] = x;
                let a = &mut ws.acc[v as usize];
                for d in 0..3 {
                    a[d] += w * x[d];
                }
                ws.wsum[v as usize] += w;
            }
        }
        for ((o, a), &w) in out.iter_mut().zip(&ws.acc).zip(&ws.wsum) {
            if w > 0.0 {
                *o = [a[0] / w, a[1] / w, a[2] / w];
            }
        }
        match &self.adjacency {
            Some(adj) => self.repair(ch.topology().triangles(), adj, source, out, ws),
            None => TurnedOver::default(),
        }
    }

    /// [`untangle::untangle`], then passes of [`unflip::unflip`] and
    /// untangling while triangles stay turned over, keeping the best pass,
    /// all with the fixed projection budget; then, if any are left, the
    /// same again from the start with the adaptive budget
    /// ([`untangle::UntangleOptions::max_steps`]), kept if it leaves fewer.
    ///
    /// The adaptive budget is only the last resort: a frame the fixed
    /// budget and the patch repair bring wholly the right way round is
    /// left as they leave it. Run on every frame, the doubling also moved
    /// vertices the fixed budget and the repair would have fixed anyway,
    /// further into their fans' thin feasible sets; those turn the right
    /// way against the reference normals but not against the rest frame's
    /// neighbourhoods (`crate::tools::eval::triangles`): CMU 03_02 on samba, where
    /// nothing is left turned over either way, read 110 → 121 triangles
    /// turned over against the rest frame in its worst frame (s12-blocks3).
    fn repair(
        &self,
        tris: &[[u32; 3]],
        adj: &unflip::Adjacency,
        source: &[[f64; 3]],
        out: &mut [[f64; 3]],
        ws: &mut DeformWorkspace,
    ) -> TurnedOver {
        let bad = unflip::turned_over(tris, source, out, &ws.turn);
        let before = bad.len();
        if before == 0 {
            return TurnedOver::default();
        }
        untangle::references(tris, source, &ws.turn, &mut ws.normals, &mut ws.areas);
        let fixed = untangle::UntangleOptions {
            max_steps: self.untangle.steps,
            ..self.untangle
        };
        let adaptive = self.untangle.max_steps > self.untangle.steps;
        if adaptive {
            ws.start.copy_from_slice(out);
        }
        let first = self.repair_with(tris, adj, source, out, ws, bad.clone(), &fixed);
        if first == 0 || !adaptive {
            return TurnedOver {
                before,
                after: first,
            };
        }
        // The last resort, from the deformed frame again; `ws.start` keeps
        // the first result.
        out.swap_with_slice(&mut ws.start);
        let second = self.repair_with(tris, adj, source, out, ws, bad, &self.untangle);
        if second >= first {
            out.copy_from_slice(&ws.start);
        }
        TurnedOver {
            before,
            after: first.min(second),
        }
    }

    /// The repair of [`Deformer::repair`] with untangling options `opts`,
    /// from the turned-over triangles `bad` (reference normals in `ws`):
    /// leaves `out` at its best pass and returns the triangles still
    /// turned over there.
    #[allow(clippy::too_many_arguments)]
    fn repair_with(
        &self,
        tris: &[[u32; 3]],
        adj: &unflip::Adjacency,
        source: &[[f64; 3]],
        out: &mut [[f64; 3]],
        ws: &mut DeformWorkspace,
        mut bad: Vec<u32>,
        opts: &untangle::UntangleOptions,
    ) -> usize {
        let mut best = bad.len();
        let mut best_bad = bad.clone();
        ws.best.copy_from_slice(out);
        // Untangling first: it is local and cheap, and fixes most frames
        // without a patch factorisation (measured: 12.4 → 8.6 ms a frame on
        // the real samba capture, still none left).
        bad = untangle::untangle(tris, adj, &ws.normals, &ws.areas, out, bad, opts);
        if bad.len() < best {
            best = bad.len();
            best_bad.clone_from(&bad);
            ws.best.copy_from_slice(out);
        }
        if best == 0 {
            return 0;
        }
        for pass in 0..self.repair_passes.max(1) {
            // Each pass reaches one ring doubling further than the last, so
            // a pass that starts again from the best state differs from it.
            let repair = unflip::RepairOptions {
                rounds: self.repair.rounds + pass,
                ..self.repair
            };
            bad = unflip::unflip(tris, adj, source, out, &ws.turn, bad, &repair);
            if !bad.is_empty() {
                bad = untangle::untangle(tris, adj, &ws.normals, &ws.areas, out, bad, opts);
            }
            if bad.len() < best {
                best = bad.len();
                best_bad.clone_from(&bad);
                ws.best.copy_from_slice(out);
            } else {
                // A pass that did not help: back to the best so far.
                out.copy_from_slice(&ws.best);
                bad.clone_from(&best_bad);
            }
            if best == 0 {
                break;
            }
        }
        best
    }

    /// Deforms every frame of a sequence (frame-major) in parallel;
    /// returns the turned-over triangle counts summed over the frames.
    pub fn deform_all(
        &self,
        ch: &Character,
        frames: &mut [[f64; 3]],
        targets: &[Pose],
    ) -> TurnedOver {
        let n = self.n;
        frames
            .par_chunks_mut(n.max(1))
            .zip(targets.par_iter())
            .map_init(
                || (self.workspace(), vec![[0.0; 3]; n]),
                |(ws, src), (f, t)| {
                    src.copy_from_slice(f);
                    let sp = ch.rig().frame_joints(src);
                    self.deform(ch, src, &sp, t, f, ws)
                },
            )
            .reduce(TurnedOver::default, |a, b| TurnedOver {
                before: a.before + b.before,
                after: a.after + b.after,
            })
    }
}
