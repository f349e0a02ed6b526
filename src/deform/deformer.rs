//! The `Deformer`: a character's prefactored part-based deformation
//! (the module page, [`crate::deform`], describes the method).

use super::bend_examples::BendExamples;
use super::cloth::{ClothStitch, StitchWorkspace};
use super::dqs::{self, ConstraintSkin};
use super::levels::{Levels, RegionScratch};
use super::near_turns::{Neighbourhoods, ReadingOf, SurfaceReading};
use super::options::{DeformMode, DeformOptions, RepairBudget, RepairTurns, TurnedOver};
use super::part_laplacian::{RegionSolver, apply};
use super::regions::{
    Held, Region, Target, constraint_scale, region_constraints, region_examples, region_specs,
    region_weights, sibling_overlaps,
};
use super::resident::{Paged, Resident, page_in, page_in_grown};
use super::turned::turned_over_flagged_in;
use super::{arap, lbs, pca, unflip, untangle};
use crate::db::Character;
use crate::mesh::laplacian::uniform_region_rows;
use crate::mesh::solver::SolveError;
use crate::mesh::stray::StrayVertices;
use crate::pose::{Pose, pose_rotations};
use glam::{DQuat, DVec3};
use rayon::prelude::*;

/// A character's prefactored deformation.
pub struct Deformer {
    mode: DeformMode,
    local_frames: bool,
    /// Vertex adjacency for the turned-over repair (when on).
    adjacency: Option<unflip::Adjacency>,
    repair: unflip::RepairOptions,
    untangle: untangle::UntangleOptions,
    repair_passes: usize,
    repair_budget: RepairBudget,
    /// Rotation-aware local steps after each region's solve.
    local_steps: usize,
    /// Each vertex's weight in the local steps' and the constraint
    /// skinning's zone ([`DeformOptions::step_zone`]); `None` everywhere.
    zone: Option<Vec<f64>>,
    /// Per region, its vertices' zone weights (local order); empty when
    /// none is in the zone (no step); `None` everywhere.
    region_zone: Vec<Option<Vec<f64>>>,
    /// Solves of overlapping siblings ([`DeformOptions::overlap_passes`]).
    overlap_passes: usize,
    /// The repair's rotations ([`DeformOptions::repair_turns`]).
    repair_turns: RepairTurns,
    /// The surface's neighbourhoods (a repair with the surface's turns).
    near: Option<Neighbourhoods>,
    /// Most repairs against the surface's turns
    /// ([`DeformOptions::surface_rounds`]).
    surface_rounds: usize,
    /// Rounds without progress that end the surface repair
    /// ([`DeformOptions::surface_stall`]).
    surface_stall: usize,
    /// The cloth stitched after the blend ([`DeformOptions::cloth_stitch`]).
    cloth: Option<ClothStitch>,
    /// The repair reads the cloth with the stitch's turns
    /// ([`DeformOptions::cloth_turns`]).
    cloth_turns: bool,
    /// A frame the stitched repair leaves folded is repaired again without
    /// the stitch ([`DeformOptions::cloth_fallback`]).
    cloth_fallback: bool,
    /// The skinning of the constraints ([`DeformOptions::constraint_skin`]).
    constraint_skin: ConstraintSkin,
    /// The knees' example-based correction of the source
    /// ([`DeformOptions::bend_examples`]).
    bend: Option<BendExamples>,
    triangles: usize,
    regions: Vec<Region>,
    /// The regions' levels when they are solved level by level on several
    /// threads ([`DeformOptions::parallel_regions`]), else `None`.
    levels: Option<Levels>,
    rest_pose: Pose,
    n: usize,
    /// Vertices in no triangle: carried by their nearest referenced vertex
    /// after every mode ([`crate::mesh::stray`]).
    stray: Option<StrayVertices>,
    /// Constraint vertices (global) of the LBS.
    pub constraint_vertices: Vec<u32>,
    /// Basis sizes (components per region).
    pub components: Vec<usize>,
    /// Example frames (flat database ids) of each region.
    pub examples: Vec<Vec<crate::graph::FlatFrame>>,
}

/// One region's own result ([`Deformer::region_results`]).
#[derive(Debug, Clone)]
pub struct RegionResult {
    /// The joint carrying the region.
    pub joint: crate::rig::Canonical,
    /// Its vertices (global ids).
    pub vertices: Vec<u32>,
    /// Its solved positions, one per vertex, world coordinates.
    pub positions: Vec<[f64; 3]>,
    /// Its blending weight at each vertex.
    pub weights: Vec<f64>,
    /// How each vertex is constrained.
    pub held: Vec<Held>,
}

/// One frame's inputs to [`Deformer::deform`]: the retrieved frame's
/// vertices, the skeleton it was captured in, and the pose it must follow.
#[derive(Clone, Copy)]
struct Frame<'a> {
    source: &'a [[f64; 3]],
    source_pose: &'a Pose,
    target: &'a Pose,
}

/// Scratch of [`Deformer::deform`].
pub struct DeformWorkspace {
    /// The source with the knees' correction ([`DeformOptions::bend_examples`];
    /// empty without).
    bent: Vec<[f64; 3]>,
    lbs: Vec<[f64; 3]>,
    /// The constraint skinning's positions, blended into `lbs` by the
    /// zone's weights (a zone and a non-linear skinning; else empty).
    zone_skin: Vec<[f64; 3]>,
    turn: Vec<DQuat>,
    acc: Vec<[f64; 3]>,
    wsum: Vec<f64>,
    /// Each region's own scratch and result ([`RegionScratch`]).
    regions: Vec<RegionScratch>,
    /// The overlap's shared targets (global ids).
    shared: Vec<[f64; 3]>,
    /// The last result solved at each vertex, world coordinates
    /// ([`Target::Last`]; written by the sequential solve only).
    last: Vec<[f64; 3]>,
    /// The frame's source normals, unnormalised
    /// ([`unflip::source_normals`]).
    source_normals: Vec<DVec3>,
    /// Each triangle's turned-over flag of the last reading
    /// ([`unflip::turned_over_flagged`]).
    flags: Vec<bool>,
    /// The best repair pass's turned-over triangles
    /// ([`Deformer::repair_with`]).
    best_bad: Vec<u32>,
    /// ClipNeutral normals (computed as the untangling reads them) and
    /// source areas of the triangles.
    references: untangle::LazyReferences,
    areas: Vec<f64>,
    /// The surface repair's readings of the frame.
    reading: SurfaceReading,
    /// The best repair pass so far.
    best: Vec<[f64; 3]>,
    /// The deformed frame before its repair, then the fixed budget's
    /// repair while the adaptive one runs.
    start: Vec<[f64; 3]>,
    /// The last frame's repair work.
    work: unflip::Work,
    /// The frame's repair budget ran out ([`RepairBudget`]'s `most`: a
    /// repair it bound stopped): no further repair starts on the frame.
    budget_over: bool,
    /// The repair running is the frame's first, against the skin's turns
    /// (bounded by [`RepairBudget::skin`] too).
    skin_repair: bool,
    /// A repair pass's state after its rounds ([`unflip::Replay`]).
    replay: unflip::Replay,
    /// The surface's own rotations ([`RepairTurns`]) and one a seed.
    surface_turn: Vec<DQuat>,
    seeds: Vec<DQuat>,
    /// The surface repair's frame that faced least against its own turns.
    surface_best: Vec<[f64; 3]>,
    /// The cloth stitch's scratch (when it runs).
    cloth: Option<StitchWorkspace>,
    /// The repair's turns with the stitch's on the cloth
    /// ([`DeformOptions::cloth_turns`]; empty without).
    repair_turn: Vec<DQuat>,
    /// The blend before the stitch ([`DeformOptions::cloth_fallback`];
    /// empty without).
    blend: Vec<[f64; 3]>,
    /// Frames deformed with this workspace whose stitch was dropped
    /// ([`DeformOptions::cloth_fallback`]).
    unstitched: usize,
    /// The capacity last paged in ([`DeformWorkspace::keep_resident`]).
    paged: Paged,
    /// The repair's lists of triangles, each taken for a list the repair
    /// makes and given back when it is done with it, and the untangling's
    /// vertices: their buffers reused frame to frame (issue 45).
    lists: Vec<Vec<u32>>,
    verts: Vec<u32>,
}

impl DeformWorkspace {
    /// An empty list of triangles for the repair, a buffer given back
    /// earlier when there is one ([`DeformWorkspace::give_back`]).
    fn take_list(&mut self) -> Vec<u32> {
        self.lists.pop().unwrap_or_default()
    }

    /// Keeps `list`'s buffer for the repair's next list (none without
    /// capacity).
    fn give_back(&mut self, mut list: Vec<u32>) {
        if list.capacity() > 0 {
            list.clear();
            self.lists.push(list);
        }
    }

    /// The work the fold repair did on the last frame deformed with this
    /// workspace, all its repairs together (zero when nothing was turned
    /// over): within [`DeformOptions::repair_budget`]'s `most`.
    pub fn repair_work(&self) -> unflip::Work {
        self.work
    }

    /// Grows the fold repair's buffers to at least `other`'s capacities:
    /// the two-frame overlap's second workspace grows to the first's
    /// largest patch before a pair, on the calling thread, rather than on
    /// meeting such a patch itself in a later pair on a pool thread
    /// (the live session's two-frame overlap). The result of a
    /// deformation does not depend on it (the buffers are cleared before
    /// each use).
    pub fn reserve_as(&mut self, other: &DeformWorkspace) {
        self.replay.reserve_as(&other.replay);
        super::patch_solve::reserve_as(&mut self.verts, &other.verts);
        reserve_lists_as(&mut self.lists, &other.lists);
        self.keep_resident();
    }

    /// Makes the workspace's buffers resident (every page written once)
    /// when their capacity changed since the last call, O(buffers) when
    /// not: the repair's buffers, reserved or grown to a larger patch, and
    /// the frame-sized buffers only a repair writes, are in the resident
    /// memory from then on instead of paged in by a later frame
    /// ([`crate::deform::resident`]). Values are kept; the result of a
    /// deformation does not depend on it.
    pub fn keep_resident(&mut self) {
        let mut paged = self.paged;
        page_in_grown(self, &mut paged);
        self.paged = paged;
    }

    /// How many frames deformed with this workspace were left without the
    /// cloth stitch, their stitched repair leaving more folds
    /// ([`DeformOptions::cloth_fallback`]).
    pub fn unstitched(&self) -> usize {
        self.unstitched
    }
}

impl Resident for DeformWorkspace {
    fn resident(&mut self, t: bool) -> usize {
        let points = [
            &mut self.lbs,
            &mut self.acc,
            &mut self.shared,
            &mut self.last,
            &mut self.best,
            &mut self.start,
            &mut self.surface_best,
        ]
        .into_iter()
        .map(|v| page_in(v, t))
        .sum::<usize>();
        points
            + page_in(&mut self.turn, t)
            + page_in(&mut self.surface_turn, t)
            + page_in(&mut self.wsum, t)
            + page_in(&mut self.areas, t)
            + page_in(&mut self.source_normals, t)
            + page_in(&mut self.flags, t)
            + page_in(&mut self.best_bad, t)
            + page_in(&mut self.verts, t)
            + self.lists.iter_mut().map(|l| page_in(l, t)).sum::<usize>()
            + self.replay.resident(t)
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
        let opts =
            &super::options::with_repair_env(&super::hold::with_env(&super::cloth::with_env(opts)));
        let mut out = Deformer::options_of(ch, mode, opts);
        if matches!(mode, DeformMode::Lbs | DeformMode::None) {
            return Ok(out);
        }
        if opts.repair_turns != RepairTurns::Skin {
            out.near = out
                .adjacency
                .as_ref()
                .map(|a| Neighbourhoods::new(a, super::near_turns::RINGS));
        }
        if mode == DeformMode::Part && opts.cloth_stitch > 0.0 {
            let cloth: Vec<bool> = super::soft::softness(ch.topology(), ch.rig())
                .iter()
                .map(|&s| s > 0.0)
                .collect();
            let tris = ch.topology().triangles();
            let joints = super::cloth_reach::joint_zones(ch.rig(), opts.stitch_joints);
            let near = super::cloth_reach::grown(tris, &cloth, opts.stitch_apart);
            let cloth: Vec<bool> = (cloth.iter().zip(&joints).zip(&near))
                .map(|((c, j), a)| *c || (*j && (opts.stitch_apart == 0 || !*a)))
                .collect();
            let cloth = super::cloth_reach::grown(tris, &cloth, opts.cloth_rings);
            out.cloth = ClothStitch::new(
                ch.topology().triangles(),
                &cloth,
                opts.cloth_stitch,
                opts.cloth_steps,
            )?;
        }
        let parent_of = out.add_regions(ch, opts)?;
        out.link_siblings(&parent_of);
        out.zone = super::step_zone::zone_weights(
            ch.topology_metres().positions(),
            ch.rest_pose(),
            opts.step_zone,
            opts.step_reach,
        );
        out.region_zone = out
            .regions
            .iter()
            .map(|r| {
                out.zone.as_ref().map(|z| {
                    let w: Vec<f64> = r.solver.vertices.iter().map(|&v| z[v as usize]).collect();
                    if w.iter().any(|&x| x > 0.0) {
                        w
                    } else {
                        Vec::new()
                    }
                })
            })
            .collect();
        if opts.parallel_regions {
            out.levels = Levels::new(&out.regions, out.overlap_passes);
        }
        if opts.bend_examples > 0.0 {
            out.bend = BendExamples::new(ch, opts.step_reach, opts.bend_examples);
        }
        Ok(out)
    }

    /// The deformer of `ch` with its options and the LBS constraint
    /// vertices, nothing prefactored (what `Lbs` and `None` need).
    fn options_of(ch: &Character, mode: DeformMode, opts: &DeformOptions) -> Deformer {
        let n = ch.n();
        let constraint_vertices = match ch.constraint_override() {
            Some(c) => c.to_vec(),
            None => lbs::constraint_vertices(ch, opts.stride),
        };
        Deformer {
            mode,
            local_frames: opts.local_frames,
            adjacency: (opts.repair.rounds > 0
                && matches!(mode, DeformMode::Part | DeformMode::Global))
            .then(|| unflip::Adjacency::new(n, ch.topology().triangles())),
            repair: opts.repair,
            untangle: opts.untangle,
            repair_passes: opts.repair_passes,
            repair_budget: opts.repair_budget,
            local_steps: opts.local_steps,
            zone: None,
            region_zone: Vec::new(),
            overlap_passes: opts.overlap_passes.max(1),
            repair_turns: opts.repair_turns,
            near: None,
            surface_rounds: opts.surface_rounds,
            surface_stall: opts.surface_stall,
            cloth: None,
            cloth_turns: opts.cloth_turns,
            cloth_fallback: opts.cloth_fallback,
            constraint_skin: opts.constraint_skin,
            bend: None,
            triangles: ch.topology().triangle_count(),
            regions: Vec::new(),
            levels: None,
            rest_pose: *ch.rest_pose(),
            n,
            stray: StrayVertices::of(ch.topology().positions(), ch.topology().triangles()),
            constraint_vertices,
            components: Vec::new(),
            examples: Vec::new(),
        }
    }

    /// Builds and prefactors the regions of `region_specs` in solve order
    /// (parents first): per region its uniform Laplacian,
    /// `region_examples`, the PCA basis, `region_weights`,
    /// `region_constraints` (seams with the parent, then LBS vertices),
    /// their targets and the Eq. 32 solver. Returns each region's parent.
    fn add_regions(
        &mut self,
        ch: &Character,
        opts: &DeformOptions,
    ) -> Result<Vec<Option<usize>>, SolveError> {
        let (n, mode) = (self.n, self.mode);
        let tris = ch.topology().triangles();
        let mut is_constraint = vec![false; n];
        for &v in &self.constraint_vertices {
            is_constraint[v as usize] = true;
        }
        // Vertices the held joints leave free: the soft ones (a skirt), when
        // `hold_soft` is off.
        let soft: Vec<bool> = if opts.hold_soft {
            vec![false; n]
        } else {
            super::soft::softness(ch.topology(), ch.rig())
                .iter()
                .map(|&s| s > 0.0)
                .collect()
        };
        let mut buf = vec![[0.0; 3]; n];
        let mut index_of: Vec<Option<usize>> = Vec::new();
        // The parent of each region built (`sibling_seams`).
        let mut parent_of: Vec<Option<usize>> = Vec::new();
        let specs = region_specs(ch, mode);
        let overlaps = (opts.overlap_weight > 0.0 && mode == DeformMode::Part)
            .then(|| sibling_overlaps(&specs, n));
        for (i, (verts, joint, parent, example_joints, _owns)) in specs.into_iter().enumerate() {
            if verts.is_empty() {
                index_of.push(None);
                continue;
            }
            index_of.push(Some(self.regions.len()));
            let parent = parent.and_then(|p| index_of.get(p).copied().flatten());
            let mut local = vec![u32::MAX; n];
            for (i, &v) in verts.iter().enumerate() {
                local[v as usize] = i as u32;
            }
            let lap = uniform_region_rows(tris, &local, verts.len());
            let (chosen, examples) =
                region_examples(ch, &verts, &lap, joint, &example_joints, opts, &mut buf);
            let basis = pca::pca(&examples, opts.keep);
            let parent_verts: Option<&Vec<u32>> = parent.map(|p| &self.regions[p].solver.vertices);
            // With `sibling_seams`, the vertices shared with the last sibling
            // built (the left thigh for the right one) are seams too.
            let sibling = parent
                .filter(|_| opts.sibling_seams)
                .and_then(|p| parent_of.iter().rposition(|&q| q == Some(p)));
            let seams: Option<Vec<u32>> = sibling.map(|k| {
                let mut all = self.regions[k].solver.vertices.clone();
                all.extend(parent_verts.into_iter().flatten());
                all.sort_unstable();
                all.dedup();
                all
            });
            let weights = region_weights(ch, mode, &verts, joint, opts.blend_taper);
            let scale = constraint_scale(
                ch,
                opts,
                &verts,
                &weights,
                parent.map(|p| {
                    let r = &self.regions[p];
                    (r.solver.vertices.as_slice(), r.weights.as_slice())
                }),
            );
            let (constraints, sources) = region_constraints(
                ch,
                mode,
                opts,
                &verts,
                joint,
                seams.as_deref().or(parent_verts.map(Vec::as_slice)),
                &is_constraint,
                &soft,
                overlaps.as_ref().map_or(&[][..], |o| o[i].as_slice()),
                &scale,
            );
            let targets = self.targets_of(&sources, sibling, parent, opts.parent_seams);
            parent_of.push(parent);
            self.components.push(basis.components.len());
            self.examples.push(chosen);
            let solver = RegionSolver::new(tris, n, verts, constraints, &basis)?;
            self.regions.push(Region {
                joint,
                solver,
                targets,
                siblings: Vec::new(),
                weights,
            });
        }
        Ok(parent_of)
    }

    /// The targets of a region's constraints `sources` (vertex and how
    /// it is held): a seam takes the result of the region `sibling`
    /// (`sibling_seams`) where it has the vertex, else the `parent`'s own
    /// (else the LBS), or the last result solved there without
    /// `parent_seams`; an overlap vertex the shared target; the rest the
    /// LBS.
    fn targets_of(
        &self,
        sources: &[(u32, Held)],
        sibling: Option<usize>,
        parent: Option<usize>,
        parent_seams: bool,
    ) -> Vec<Target> {
        let from = |k: usize, v: u32| {
            self.regions[k]
                .solver
                .vertices
                .binary_search(&v)
                .ok()
                .map(|j| Target::Region(k as u32, j as u32))
        };
        sources
            .iter()
            .map(|&(v, held)| match held {
                Held::Seam if !parent_seams => Target::Last(v),
                Held::Seam => sibling
                    .and_then(|k| from(k, v))
                    .or_else(|| parent.and_then(|k| from(k, v)))
                    .unwrap_or(Target::Lbs(v)),
                Held::Shared => Target::Shared(v),
                _ => Target::Lbs(v),
            })
            .collect()
    }

    /// Fills each region's `siblings`: the regions with the same parent
    /// that share a held overlap vertex with it.
    fn link_siblings(&mut self, parent_of: &[Option<usize>]) {
        let held: Vec<Vec<u32>> = self
            .regions
            .iter()
            .map(|r| {
                let mut h: Vec<u32> = r
                    .targets
                    .iter()
                    .filter_map(|t| match t {
                        Target::Shared(v) => Some(*v),
                        _ => None,
                    })
                    .collect();
                h.sort_unstable();
                h
            })
            .collect();
        for k in 0..self.regions.len() {
            self.regions[k].siblings = (0..self.regions.len())
                .filter(|&j| {
                    j != k
                        && parent_of[j].is_some()
                        && parent_of[j] == parent_of[k]
                        && held[k].iter().any(|v| held[j].binary_search(v).is_ok())
                })
                .collect();
        }
    }

    /// Each region's own result on the last frame deformed with `ws`
    /// (before the blend and the repair), in world coordinates, with its
    /// blending weights and which of its vertices are held (an LBS target)
    /// or seamed to the parent: a diagnostic of where regions disagree
    /// (issue 42). `target` is the pose that frame was deformed to.
    pub fn region_results(&self, target: &Pose, ws: &DeformWorkspace) -> Vec<RegionResult> {
        let _ = target;
        self.regions
            .iter()
            .zip(&ws.regions)
            .map(|(r, s)| {
                let world = &s.world;
                let mut held = vec![Held::Free; r.solver.vertices.len()];
                for (&(c, _), t) in r.solver.constraints.iter().zip(&r.targets) {
                    held[c as usize] = match t {
                        Target::Lbs(_) => Held::Lbs,
                        Target::Region(..) | Target::Last(_) => Held::Seam,
                        Target::Shared(_) => Held::Shared,
                    };
                }
                RegionResult {
                    joint: r.joint,
                    vertices: r.solver.vertices.clone(),
                    positions: world.clone(),
                    weights: r.weights.clone(),
                    held,
                }
            })
            .collect()
    }

    /// How many levels the regions are solved in, one level's regions at
    /// once on several threads ([`DeformOptions::parallel_regions`]), or
    /// `None` when they are solved one after another.
    pub fn levels(&self) -> Option<usize> {
        self.levels.as_ref().map(Levels::count)
    }

    /// The mode.
    pub fn mode(&self) -> DeformMode {
        self.mode
    }

    /// Scratch space.
    pub fn workspace(&self) -> DeformWorkspace {
        DeformWorkspace {
            bent: match &self.bend {
                Some(_) => vec![[0.0; 3]; self.n],
                None => Vec::new(),
            },
            lbs: vec![[0.0; 3]; self.n],
            zone_skin: match (&self.zone, self.constraint_skin) {
                (Some(_), ConstraintSkin::DualQuaternion | ConstraintSkin::Rigid) => {
                    vec![[0.0; 3]; self.n]
                }
                _ => Vec::new(),
            },
            turn: vec![DQuat::IDENTITY; self.n],
            acc: vec![[0.0; 3]; self.n],
            wsum: vec![0.0; self.n],
            regions: self
                .regions
                .iter()
                .map(|r| RegionScratch::new(&r.solver, r.targets.len()))
                .collect(),
            shared: vec![[0.0; 3]; self.n],
            last: vec![[0.0; 3]; self.n],
            source_normals: vec![DVec3::ZERO; self.triangles],
            flags: vec![false; self.triangles],
            best_bad: Vec::new(),
            references: untangle::LazyReferences::new(self.triangles),
            areas: vec![0.0; self.triangles],
            reading: SurfaceReading::default(),
            best: vec![[0.0; 3]; self.n],
            start: vec![[0.0; 3]; self.n],
            work: unflip::Work::default(),
            budget_over: false,
            skin_repair: false,
            replay: unflip::Replay::default(),
            surface_turn: vec![DQuat::IDENTITY; self.n],
            seeds: Vec::new(),
            surface_best: vec![[0.0; 3]; self.n],
            cloth: self.cloth.as_ref().map(ClothStitch::workspace),
            repair_turn: match (&self.cloth, self.cloth_turns) {
                (Some(_), true) => vec![DQuat::IDENTITY; self.n],
                _ => Vec::new(),
            },
            blend: match (&self.cloth, self.cloth_fallback) {
                (Some(_), true) => vec![[0.0; 3]; self.n],
                _ => Vec::new(),
            },
            unstitched: 0,
            paged: Paged::default(),
            lists: Vec::new(),
            verts: Vec::new(),
        }
    }

    /// Deforms `source` (a retrieved frame whose skeleton is `source_pose`)
    /// to follow `target`, into `out`. Returns the triangles turned over
    /// before and after the repair (zero for modes without one). With
    /// [`DeformOptions::bend_examples`] the source's knees are first given
    /// the capture's shape at the target's knee angles
    /// ([`super::bend_examples`]).
    pub fn deform(
        &self,
        ch: &Character,
        source: &[[f64; 3]],
        source_pose: &Pose,
        target: &Pose,
        out: &mut [[f64; 3]],
        ws: &mut DeformWorkspace,
    ) -> TurnedOver {
        let bent = self.bend.as_ref().map(|b| {
            let mut bent = std::mem::take(&mut ws.bent);
            b.bend(
                source,
                source_pose,
                target,
                &self.rest_pose,
                ch.rig(),
                &mut bent,
            );
            bent
        });
        let frame = Frame {
            source: bent.as_deref().unwrap_or(source),
            source_pose,
            target,
        };
        let c = self.deform_source(ch, frame, out, ws);
        // A stray vertex keeps its offset from its carrier, turned by the
        // carrier's skinning (`None` returns the source as it is).
        if let Some(s) = &self.stray {
            match self.mode {
                DeformMode::None => {}
                DeformMode::Lbs => s.carry(&ws.lbs, out),
                _ => s.carry_turned(frame.source, &ws.turn, out),
            }
        }
        if let Some(bent) = bent {
            ws.bent = bent;
        }
        c
    }

    /// [`Deformer::deform`] of the source as given.
    fn deform_source(
        &self,
        ch: &Character,
        frame: Frame<'_>,
        out: &mut [[f64; 3]],
        ws: &mut DeformWorkspace,
    ) -> TurnedOver {
        let Frame {
            source,
            source_pose,
            target,
        } = frame;
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
        let skinned = if self.zone.is_some() {
            &mut ws.zone_skin
        } else {
            &mut ws.lbs
        };
        match self.constraint_skin {
            ConstraintSkin::Linear => {}
            ConstraintSkin::DualQuaternion => {
                dqs::skin_into(source, ch.rig(), source_pose, target, &g, skinned)
            }
            ConstraintSkin::Rigid => {
                dqs::rigid_into(source, ch.rig(), source_pose, target, &g, skinned)
            }
        }
        if let Some(z) = &self.zone {
            // The zone's vertices by the constraint skinning, the rest linear.
            for ((p, q), &w) in ws.lbs.iter_mut().zip(&ws.zone_skin).zip(z) {
                if w > 0.0 {
                    *p = std::array::from_fn(|d| p[d] + w * (q[d] - p[d]));
                }
            }
        }
        let rot = pose_rotations(&self.rest_pose, target);
        // Each vertex's rotation from source to target: its bones' turns,
        // blended by skin weight.
        unflip::skin_turns(&ch.rig().skin, &g, &mut ws.turn);
        ws.shared.copy_from_slice(&ws.lbs);
        match &self.levels {
            Some(levels) => self.solve_by_level(levels, &rot, source, ws),
            None => self.solve_in_order(&rot, source, ws),
        }
        ws.acc.fill([0.0; 3]);
        ws.wsum.fill(0.0);
        for (r, s) in self.regions.iter().zip(&ws.regions) {
            for ((x, &v), &w) in s.world.iter().zip(&r.solver.vertices).zip(&r.weights) {
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
        let stitched = self.stitch(source, out, ws);
        let Some(adj) = &self.adjacency else {
            return TurnedOver::default();
        };
        let f = RepairOf {
            tris: ch.topology().triangles(),
            adj,
            source,
        };
        // The frame's repairs add their work here, against the budget.
        ws.work = unflip::Work::default();
        ws.budget_over = false;
        let counts = self.repair(f, out, ws, stitched && self.cloth_turns);
        // A frame whose budget ran out is left as its repair left it.
        if stitched && self.cloth_fallback && counts.after > 0 && !ws.budget_over {
            return self.unstitched(f, out, ws, counts);
        }
        counts
    }

    /// The cloth stitch of the blend `out` ([`super::cloth`]), when it
    /// runs: keeps the blend for the fallback and the stitch's turns for
    /// the repair (when those options are on). Whether it ran.
    fn stitch(&self, source: &[[f64; 3]], out: &mut [[f64; 3]], ws: &mut DeformWorkspace) -> bool {
        let (Some(c), Some(cw)) = (&self.cloth, ws.cloth.as_mut()) else {
            return false;
        };
        if self.cloth_fallback {
            ws.blend.copy_from_slice(out);
        }
        c.stitch(source, &ws.turn, out, cw);
        if self.cloth_turns {
            ws.repair_turn.copy_from_slice(&ws.turn);
            c.fitted_turns(cw, &mut ws.repair_turn);
        }
        true
    }

    /// The frame's repair again from the blend without the stitch
    /// ([`DeformOptions::cloth_fallback`]), after the stitched repair left
    /// `stitched.after` triangles facing against their neighbourhoods: the
    /// result that leaves fewer is kept (the stitched one on a tie), and
    /// its counts returned.
    fn unstitched(
        &self,
        f: RepairOf,
        out: &mut [[f64; 3]],
        ws: &mut DeformWorkspace,
        stitched: TurnedOver,
    ) -> TurnedOver {
        // The blend into `out`, the stitched result into `frame`.
        let mut frame = std::mem::take(&mut ws.blend);
        out.swap_with_slice(&mut frame);
        let plain = self.repair(f, out, ws, false);
        // `before` stays the stitched solve's (the deformation's count).
        let kept = if plain.after < stitched.after {
            ws.unstitched += 1;
            TurnedOver {
                before: stitched.before,
                after: plain.after,
            }
        } else {
            out.copy_from_slice(&frame);
            stitched
        };
        ws.blend = frame;
        kept
    }

    /// The rotation of region `k`'s frame (its joint's, with
    /// `local_frames`) in the target pose, `rot` the target's rotations
    /// from the rest pose.
    fn frame_of(&self, k: usize, rot: &[DQuat]) -> DQuat {
        if self.local_frames {
            rot[self.regions[k].joint.index()]
        } else {
            DQuat::IDENTITY
        }
    }

    /// The regions solved one after another in solve order, each with its
    /// overlap passes ([`DeformOptions::overlap_passes`]).
    fn solve_in_order(&self, rot: &[DQuat], source: &[[f64; 3]], ws: &mut DeformWorkspace) {
        for k in 0..self.regions.len() {
            let q = self.frame_of(k, rot);
            self.source_delta(k, q, source, &ws.turn, &mut ws.regions[k]);
            self.solve_region(k, q, ws);
            let r = &self.regions[k];
            if self.overlap_passes > 1
                && !r.siblings.is_empty()
                && r.siblings.iter().all(|&j| j < k)
            {
                for _ in 1..self.overlap_passes {
                    self.blend_shared(k, ws);
                    for j in r.siblings.iter().copied().chain([k]) {
                        self.solve_region(j, self.frame_of(j, rot), ws);
                    }
                }
            }
        }
    }

    /// The regions solved level by level ([`super::levels`]): every
    /// region's `δ₀` at once, then per level its regions' targets read
    /// (one thread) and the level's regions solved at once, each into its
    /// own scratch; the same bits as [`Deformer::solve_in_order`].
    fn solve_by_level(
        &self,
        levels: &Levels,
        rot: &[DQuat],
        source: &[[f64; 3]],
        ws: &mut DeformWorkspace,
    ) {
        let turn = &ws.turn;
        ws.regions
            .par_iter_mut()
            .enumerate()
            .with_max_len(1)
            .for_each(|(k, s)| self.source_delta(k, self.frame_of(k, rot), source, turn, s));
        for l in 0..levels.count() {
            let members = levels.members(l);
            for &k in members {
                self.gather_targets(k, self.frame_of(k, rot), ws);
            }
            if let &[k] = members {
                self.solve_own(k, self.frame_of(k, rot), &mut ws.regions[k]);
                continue;
            }
            ws.regions
                .par_iter_mut()
                .enumerate()
                .with_max_len(1)
                .filter(|(k, _)| levels.of[*k] as usize == l)
                .for_each(|(k, s)| self.solve_own(k, self.frame_of(k, rot), s));
        }
    }

    /// Region `k`'s `δ₀` into `s.delta`: the source's Laplacian
    /// coordinates, each turned by its vertex's skin-blended rotation
    /// (`turn`) from the source skeleton to the target, in the part's
    /// frame `q` (a skirt vertex shared by both thighs turns the same way
    /// in both solves).
    fn source_delta(
        &self,
        k: usize,
        q: DQuat,
        source: &[[f64; 3]],
        turn: &[DQuat],
        s: &mut RegionScratch,
    ) {
        let r = &self.regions[k];
        let qi = q.inverse();
        for (x, &v) in s.xs.iter_mut().zip(&r.solver.vertices) {
            *x = source[v as usize];
        }
        apply(r.solver.laplacian(), &s.xs, &mut s.delta);
        if self.local_steps > 0 {
            s.lsrc.copy_from_slice(&s.delta);
        }
        let zoned = self.local_steps > 0 && self.zone.is_some();
        for ((dv, &v), rq) in s
            .delta
            .iter_mut()
            .zip(&r.solver.vertices)
            .zip(s.rots.iter_mut())
        {
            let turn = if self.local_frames {
                qi * turn[v as usize]
            } else {
                DQuat::IDENTITY
            };
            *rq = turn;
            *dv = (turn * DVec3::from_array(*dv)).to_array();
        }
        if zoned {
            s.skin.copy_from_slice(&s.rots);
        }
    }

    /// Solves region `k` in its frame `q` (Eq. 32, then the local steps)
    /// with its constraints' targets read now (LBS, another region's
    /// result, the overlap's shared target), into its `world`, and
    /// records it as the last result at its vertices.
    fn solve_region(&self, k: usize, q: DQuat, ws: &mut DeformWorkspace) {
        self.gather_targets(k, q, ws);
        let s = &mut ws.regions[k];
        self.solve_own(k, q, s);
        for (x, &v) in s.world.iter().zip(&self.regions[k].solver.vertices) {
            ws.last[v as usize] = *x;
        }
    }

    /// Region `k`'s constraint targets in its frame `q`, read now (LBS,
    /// the result of a region solved before it, the overlap's shared
    /// target, the last result solved at the vertex).
    fn gather_targets(&self, k: usize, q: DQuat, ws: &mut DeformWorkspace) {
        let r = &self.regions[k];
        let qi = q.inverse();
        let (done, rest) = ws.regions.split_at_mut(k);
        for (t, out) in r.targets.iter().zip(rest[0].targets.iter_mut()) {
            let p = match *t {
                Target::Lbs(v) => ws.lbs[v as usize],
                Target::Shared(v) => ws.shared[v as usize],
                Target::Region(j, l) => done[j as usize].world[l as usize],
                Target::Last(v) => ws.last[v as usize],
            };
            *out = (qi * DVec3::from_array(p)).to_array();
        }
    }

    /// Solves region `k` in its frame `q` (Eq. 32, then the local steps)
    /// from its scratch's `δ₀` and targets, into `s.world`: reads nothing
    /// but its own scratch.
    fn solve_own(&self, k: usize, q: DQuat, s: &mut RegionScratch) {
        let r = &self.regions[k];
        r.solver
            .solve(&s.delta, &s.targets, &mut s.local, &mut s.ws);
        let zone = self.region_zone.get(k).and_then(Option::as_deref);
        let steps = match zone {
            Some([]) => 0,
            _ => self.local_steps,
        };
        for _ in 0..steps {
            arap::local_step(
                r.solver.laplacian(),
                &s.xs,
                &s.local,
                &s.lsrc,
                &mut s.rots,
                &mut s.delta,
                zone.map(|w| (w, s.skin.as_slice())),
            );
            r.solver
                .solve(&s.delta, &s.targets, &mut s.local, &mut s.ws);
        }
        for (x, y) in s.world.iter_mut().zip(&s.local) {
            *x = (q * DVec3::from_array(*y)).to_array();
        }
    }

    /// The overlap's shared targets of region `k` and its siblings: each
    /// held vertex's results in those regions blended by their weights.
    fn blend_shared(&self, k: usize, ws: &mut DeformWorkspace) {
        let group = || self.regions[k].siblings.iter().copied().chain([k]);
        for j in group() {
            for t in &self.regions[j].targets {
                if let Target::Shared(v) = *t {
                    ws.acc[v as usize] = [0.0; 3];
                    ws.wsum[v as usize] = 0.0;
                }
            }
        }
        for j in group() {
            let r = &self.regions[j];
            for (&(c, _), t) in r.solver.constraints.iter().zip(&r.targets) {
                if let Target::Shared(v) = *t {
                    let (x, w) = (ws.regions[j].world[c as usize], r.weights[c as usize]);
                    let a = &mut ws.acc[v as usize];
                    for d in 0..3 {
                        a[d] += w * x[d];
                    }
                    ws.wsum[v as usize] += w;
                }
            }
        }
        for j in group() {
            let r = &self.regions[j];
            for t in &r.targets {
                if let Target::Shared(v) = *t {
                    let (a, w) = (ws.acc[v as usize], ws.wsum[v as usize]);
                    if w > 0.0 {
                        ws.shared[v as usize] = [a[0] / w, a[1] / w, a[2] / w];
                    }
                }
            }
        }
    }

    /// The fold repair with the rotations of [`DeformOptions::repair_turns`]:
    /// [`Deformer::repair_against`] the skin's turns, then (or only) the
    /// surface's own ([`super::near_turns`], read off the deformed frame).
    /// `before` counts against the skin's turns; `after` against the
    /// surface's own turns of the frame as left, where the surface repair
    /// runs ([`Deformer::repair_surface`]: a triangle that faces with its
    /// neighbourhood is not left folded, though it may face against the
    /// skin's blend of two thighs' turns), else against the skin's.
    fn repair(
        &self,
        f: RepairOf,
        out: &mut [[f64; 3]],
        ws: &mut DeformWorkspace,
        cloth_turns: bool,
    ) -> TurnedOver {
        let RepairOf { tris, source, .. } = f;
        // The source's normals and areas once per frame; each reading
        // below only turns them.
        unflip::source_normals(tris, source, &mut ws.source_normals);
        untangle::source_areas(&ws.source_normals, &mut ws.areas);
        let skin = std::mem::take(&mut ws.turn);
        let list = ws.take_list();
        let bad = turned_over_flagged_in(tris, &ws.source_normals, out, &skin, &mut ws.flags, list);
        ws.skin_repair = true;
        let mut counts = match self.repair_turns {
            RepairTurns::Skin | RepairTurns::SkinThenSurface if cloth_turns => {
                // Counted against the skin's turns, repaired against the
                // stitch's on the cloth.
                let turn = std::mem::take(&mut ws.repair_turn);
                let list = ws.take_list();
                let sn = &ws.source_normals;
                let own = turned_over_flagged_in(tris, sn, out, &turn, &mut ws.flags, list);
                let c = self.repair_skin(f, out, ws, &turn, own);
                ws.repair_turn = turn;
                let before = bad.len();
                ws.give_back(bad);
                TurnedOver {
                    before,
                    after: c.after,
                }
            }
            RepairTurns::Skin | RepairTurns::SkinThenSurface => {
                self.repair_skin(f, out, ws, &skin, bad)
            }
            RepairTurns::Surface => {
                let before = bad.len();
                ws.give_back(bad);
                TurnedOver { before, after: 0 }
            }
        };
        ws.skin_repair = false;
        if let (Some(near), RepairTurns::SkinThenSurface | RepairTurns::Surface) =
            (&self.near, self.repair_turns)
        {
            let skin = ws.work.patches;
            counts.after = self.repair_surface(near, f, out, ws);
            ws.work.surface_patches += ws.work.patches - skin;
        }
        ws.turn = skin;
        counts
    }

    /// The frame's first repair, against the skin's turns `turn` (or the
    /// stitch's on the cloth): [`Deformer::repair_against`], or where the
    /// budget gives it no work ([`RepairBudget::skips_skin`]) the umbrella
    /// smoothing that ends a patch repair alone ([`unflip::unflip_within`]
    /// with no rounds), kept when it leaves fewer turned over. Smoothing
    /// projects nothing and solves no patch, so the budget's `most` is
    /// left whole to the surface's repair.
    fn repair_skin(
        &self,
        f: RepairOf,
        out: &mut [[f64; 3]],
        ws: &mut DeformWorkspace,
        turn: &[DQuat],
        bad: Vec<u32>,
    ) -> TurnedOver {
        if !self.repair_budget.skips_skin() {
            return self.repair_against(f, out, ws, turn, bad, 0);
        }
        let before = bad.len();
        if before == 0 {
            ws.give_back(bad);
            return TurnedOver::default();
        }
        ws.best.copy_from_slice(out);
        let smooth = unflip::RepairOptions {
            rounds: 0,
            replay: false,
            ..self.repair
        };
        let mut nothing = unflip::Budget::new(unflip::WorkLimit::NONE);
        let RepairOf { tris, adj, source } = f;
        let replay = Some((&mut ws.replay, false));
        let left = unflip::unflip_within(
            tris,
            adj,
            source,
            out,
            turn,
            bad,
            &smooth,
            &mut nothing,
            replay,
        );
        let after = left.len();
        ws.give_back(left);
        if after >= before {
            out.copy_from_slice(&ws.best);
        }
        TurnedOver {
            before,
            after: after.min(before),
        }
    }

    /// The repair against the surface's own turns: rounds of reading each
    /// neighbourhood's turn off the frame as it now is and repairing what
    /// faces against it, until nothing does,
    /// [`DeformOptions::surface_rounds`] repairs have run or the frame's
    /// repair budget ran out ([`RepairBudget`]). A repair moves
    /// vertices, and with them the turns it was read against, so a round
    /// can leave triangles that the next reading flags; each round after
    /// the first lets the patch solve reach one doubling of rings further
    /// around what is still flagged ([`Deformer::repair_against`]'s
    /// `grow`). The frame left is the round's that faces least against its
    /// own turns; returns that count
    /// ([`super::near_turns::turned_over_near`], what the tests count).
    fn repair_surface(
        &self,
        near: &Neighbourhoods,
        f: RepairOf,
        out: &mut [[f64; 3]],
        ws: &mut DeformWorkspace,
    ) -> usize {
        let mut turn = std::mem::take(&mut ws.surface_turn);
        let (mut least, mut last) = (usize::MAX, 0);
        // Rounds in a row that did not lower the count.
        let mut stalled = 0;
        for round in 0..=self.surface_rounds {
            let r = ReadingOf {
                near,
                adj: f.adj,
                tris: f.tris,
                source: f.source,
                source_normals: &ws.source_normals,
            };
            let list = ws.lists.pop().unwrap_or_default();
            let bad = if round == 0 {
                let turns = (&mut ws.seeds, &mut turn[..]);
                ws.reading.read_all_in(&r, out, turns, list)
            } else {
                let turns = (&mut ws.seeds[..], &mut turn[..]);
                ws.reading.read_again_in(&r, out, turns, list)
            };
            last = bad.len();
            if last == 0 {
                least = 0;
                ws.give_back(bad);
                break;
            }
            if last < least {
                least = last;
                stalled = 0;
                ws.surface_best.copy_from_slice(out);
            } else {
                stalled += 1;
            }
            let over = ws.budget_over;
            if round == self.surface_rounds || stalled >= self.surface_stall || over {
                ws.give_back(bad);
                break;
            }
            self.repair_against(f, out, ws, &turn, bad, round);
        }
        if last > least {
            out.copy_from_slice(&ws.surface_best);
        }
        ws.surface_turn = turn;
        least
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
    ///
    /// `bad`: the triangles of `out` turned over under `turn` (sorted, as
    /// [`unflip::turned_over_from`] gives them; the caller has counted
    /// them). `grow`: doublings of the patch's rings added to every pass
    /// ([`Deformer::repair_surface`]'s later rounds; 0 for the skin's).
    /// The source normals and areas in `ws` are the frame's
    /// ([`Deformer::repair`]).
    fn repair_against(
        &self,
        f: RepairOf,
        out: &mut [[f64; 3]],
        ws: &mut DeformWorkspace,
        turn: &[DQuat],
        bad: Vec<u32>,
        grow: usize,
    ) -> TurnedOver {
        let before = bad.len();
        if before == 0 {
            ws.give_back(bad);
            return TurnedOver::default();
        }
        // Within the triangles' share and what the frame's earlier repairs
        // left of its most ([`RepairBudget::limit_after`]).
        let base = ws.work;
        let plain = self.repair_budget.limit_after(before, &base);
        // The frame's remainder, not this repair's share (nor the skin's
        // limit, [`RepairBudget::skin`]), bounds it: a stop then ends the
        // frame's repair (`budget_over`).
        let limit = match ws.skin_repair {
            true => self.repair_budget.skin_limit_after(before, &base),
            false => plain,
        };
        let frame_bound = self.repair_budget.frame_bound(before, &plain) && limit == plain;
        let mut budget = unflip::Budget::new(limit);
        ws.references.restart();
        let fixed = untangle::UntangleOptions {
            max_steps: self.untangle.steps,
            ..self.untangle
        };
        let adaptive = self.untangle.max_steps > self.untangle.steps;
        if adaptive {
            ws.start.copy_from_slice(out);
        }
        // The list is kept for the last resort only when it may run.
        let (bad, kept) = match adaptive {
            true => {
                let mut copy = ws.take_list();
                copy.extend_from_slice(&bad);
                (copy, bad)
            }
            false => (bad, Vec::new()),
        };
        let first = self.repair_with(f, out, ws, turn, bad, &fixed, &mut budget, grow);
        ws.work = add_work(base, budget.done);
        let before_retry = budget.done.patches;
        ws.budget_over |= frame_bound && budget.done.stopped > 0;
        // The last resort is not tried on a repair the budget stopped.
        if first == 0 || !adaptive || budget.done.stopped > 0 {
            ws.give_back(kept);
            return TurnedOver {
                before,
                after: first,
            };
        }
        let bad = kept;
        // The last resort, from the deformed frame again; `ws.start` keeps
        // the first result.
        out.swap_with_slice(&mut ws.start);
        let second = self.repair_with(f, out, ws, turn, bad, &self.untangle, &mut budget, grow);
        budget.done.retry_patches += budget.done.patches - before_retry;
        ws.work = add_work(base, budget.done);
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
    /// turned over there. The work is counted in `budget` and stays
    /// within it.
    #[allow(clippy::too_many_arguments)]
    fn repair_with(
        &self,
        f: RepairOf,
        out: &mut [[f64; 3]],
        ws: &mut DeformWorkspace,
        turn: &[DQuat],
        mut bad: Vec<u32>,
        opts: &untangle::UntangleOptions,
        budget: &mut unflip::Budget,
        grow: usize,
    ) -> usize {
        let RepairOf { tris, adj, source } = f;
        let mut best = bad.len();
        let mut best_bad = std::mem::take(&mut ws.best_bad);
        best_bad.clone_from(&bad);
        ws.best.copy_from_slice(out);
        // Untangling first: it is local and cheap, and fixes most frames
        // without a patch factorisation (measured: 12.4 → 8.6 ms a frame on
        // the real samba capture, still none left).
        let mut refs = untangle::OnDemand {
            lazy: &mut ws.references,
            source_normals: &ws.source_normals,
            turn,
        };
        let lists = (bad, &mut ws.verts);
        bad = untangle::untangle_kept(tris, adj, &mut refs, &ws.areas, out, lists, opts, budget);
        // Whether `out` and `bad` are the best state (`ws.best`,
        // `best_bad`), and whether the last pass started there and went
        // back to it: then the next pass's first rounds are the last
        // pass's ([`unflip::Replay`]).
        let mut at_best = false;
        let mut resume = false;
        ws.replay.clear();
        if bad.len() < best {
            best = bad.len();
            best_bad.clone_from(&bad);
            ws.best.copy_from_slice(out);
            at_best = true;
        }
        if best == 0 {
            ws.best_bad = best_bad;
            ws.give_back(bad);
            return 0;
        }
        for pass in 0..self.repair_passes.max(1) {
            // Each pass reaches one ring doubling further than the last, so
            // a pass that starts again from the best state differs from it;
            // `grow` doublings further still.
            let repair = unflip::RepairOptions {
                rounds: self.repair.rounds + grow + pass,
                ..self.repair
            };
            let started_at_best = at_best;
            let patches = budget.done.patches;
            bad = unflip::unflip_within(
                tris,
                adj,
                source,
                out,
                turn,
                bad,
                &repair,
                budget,
                Some((&mut ws.replay, resume)),
            );
            if pass > 0 {
                budget.done.later_pass_patches += budget.done.patches - patches;
            }
            if !bad.is_empty() {
                let mut refs = untangle::OnDemand {
                    lazy: &mut ws.references,
                    source_normals: &ws.source_normals,
                    turn,
                };
                let lists = (bad, &mut ws.verts);
                bad = untangle::untangle_kept(
                    tris, adj, &mut refs, &ws.areas, out, lists, opts, budget,
                );
            }
            if bad.len() < best {
                best = bad.len();
                best_bad.clone_from(&bad);
                ws.best.copy_from_slice(out);
                resume = false;
            } else {
                // A pass that did not help: back to the best so far,
                // where it started if `started_at_best`.
                out.copy_from_slice(&ws.best);
                bad.clone_from(&best_bad);
                resume = started_at_best;
            }
            at_best = true;
            // No pass after one the budget stopped: its refused steps
            // would be built again and refused again.
            if best == 0 || budget.done.stopped > 0 {
                break;
            }
        }
        ws.best_bad = best_bad;
        ws.give_back(bad);
        best
    }
}

/// What a frame's fold repair reads: the mesh's triangles and adjacency
/// and the retrieved frame (one argument for the repair's steps).
#[derive(Clone, Copy)]
struct RepairOf<'a> {
    tris: &'a [[u32; 3]],
    adj: &'a unflip::Adjacency,
    source: &'a [[f64; 3]],
}

/// Two repairs' work added.
fn add_work(a: unflip::Work, b: unflip::Work) -> unflip::Work {
    unflip::Work {
        projections: a.projections + b.projections,
        patch_vertices: a.patch_vertices + b.patch_vertices,
        patches: a.patches + b.patches,
        surface_patches: a.surface_patches + b.surface_patches,
        retry_patches: a.retry_patches + b.retry_patches,
        later_pass_patches: a.later_pass_patches + b.later_pass_patches,
        replayed_rounds: a.replayed_rounds + b.replayed_rounds,
        stopped: a.stopped + b.stopped,
    }
}

/// Grows the repair's kept `lists` to as many as `other`'s, each holding
/// at least `other`'s longest ([`DeformWorkspace::reserve_as`]), exactly:
/// `Vec::reserve`'s amortised doubling here let two slots' lists double
/// each other at every evening out once one list was within a factor two
/// of the other slot's longest (session 44: `live::long`'s child killed
/// at 19.8 GB; the pages are written as they grow, `keep_resident`).
fn reserve_lists_as(lists: &mut Vec<Vec<u32>>, other: &[Vec<u32>]) {
    let most = other.iter().map(Vec::capacity).max().unwrap_or(0);
    let count = lists.len().max(other.len());
    lists.resize_with(count, Vec::new);
    for l in lists {
        if l.capacity() < most {
            l.reserve_exact(most - l.len());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The live session's two slots even their repair lists out after
    /// every deformation (each grown to the other's, then the other to
    /// it): the capacities settle at the largest either held, however
    /// often they are evened out, never past it — not doubled by each call (session 44:
    /// `Vec::reserve`'s amortised growth made two lists within a factor
    /// two of the other slot's longest double each other every frame,
    /// and `live::long`'s child was killed at 19.8 GB).
    #[test]
    fn evening_out_two_slots_lists_settles_at_the_largest() {
        let with = |caps: &[usize]| -> Vec<Vec<u32>> {
            caps.iter().map(|&c| Vec::with_capacity(c)).collect()
        };
        for (a, b) in [
            (&[100, 60][..], &[150][..]),
            (&[100, 80][..], &[100][..]),
            (&[7][..], &[5, 6, 4][..]),
            (&[][..], &[30][..]),
        ] {
            let (mut a, mut b) = (with(a), with(b));
            let largest = a.iter().chain(&b).map(Vec::capacity).max().unwrap();
            for round in 0..20 {
                reserve_lists_as(&mut a, &b);
                reserve_lists_as(&mut b, &a);
                // Each grows to the other's longest: all of them to the
                // largest from the second round on, none past it.
                for l in a.iter().chain(&b) {
                    let c = l.capacity();
                    assert!(c <= largest, "round {round}: {c} held, largest {largest}");
                    assert!(round == 0 || c == largest, "round {round}: {c} held");
                }
                assert_eq!(a.len(), b.len(), "round {round}");
            }
        }
    }
}
