//! Repair of turned-over triangles after the part-based deformation.
//!
//! Where the part solutions meet under strong compression (a skirt between
//! the legs, a hem pushed by a knee) a few triangles of the deformed surface
//! can face the wrong way. A triangle is *turned over* when its normal
//! opposes the source triangle's normal turned by the triangle's
//! skin-blended rotation from the source skeleton to the target (a triangle
//! that simply rotates with its limb, however far, is not).
//!
//! Each patch of such triangles (their vertices grown by a few rings) is
//! rebuilt by a local Poisson solve with its surrounding ring fixed. A
//! triangle that is turned over or nearly so (its normal within
//! [`RepairOptions::healthy_cos`] of edge-on to the turned source normal)
//! asks for its source edges turned by its rotation, weighted up
//! ([`RepairOptions::weight`]); every other triangle of the patch asks for
//! its current edges, so the deformation's shape is kept and only the fold
//! is worked out (asking every triangle for its turned source shape, as an
//! earlier version did, undid the deformation over large patches and moved
//! the joints). If triangles are still turned over the patch is doubled and
//! the solve repeated, up to [`RepairOptions::rounds`]; the vertices of any
//! left then move to the mean of their neighbours (a few Jacobi steps of
//! umbrella smoothing), which unfolds small folds the solve keeps.
//! [`super::untangle`] finishes the job. Frames with nothing turned over
//! cost one pass over the triangles.

pub use super::repair_options::{Budget, RepairOptions, Work, WorkLimit};
use super::resident::{Resident, page_in};
pub use super::turned::{
    Adjacency, skin_turns, source_normals, turned_over, turned_over_flagged, turned_over_from,
};
pub(crate) use super::turned::{CHUNK, faces_against, triangle_turn};
use super::unflip_patch::{RepairScratch, RoundOf};
use glam::{DQuat, DVec3};

/// The state after a pass's Poisson rounds (before its smoothing), kept
/// so the next pass, when it starts from the same state with the same
/// triangles (the pass did not help and the repair went back to where it
/// started), takes its first rounds from here instead of solving them
/// again: the rounds are deterministic, so the next pass's first rounds
/// would give this state bit for bit, and it only solves the rounds it
/// adds (one more doubling). Allocated once per workspace, with the
/// repair's buffers.
#[derive(Debug, Clone, Default)]
pub struct Replay {
    /// The frame after the rounds.
    out: Vec<[f64; 3]>,
    /// The triangles still turned over there.
    bad: Vec<u32>,
    /// Rounds solved and the rings of the next round.
    rounds: usize,
    rings: usize,
    /// Whether the state above is one a next pass can take.
    valid: bool,
    /// The repair's buffers, reused by every call given this state
    /// ([`RepairScratch`]; not part of the state: a clone starts empty).
    scratch: RepairScratch,
}

impl Replay {
    /// Forgets the kept state.
    pub fn clear(&mut self) {
        self.valid = false;
    }

    /// Grows the kept frame's and the repair's buffers to at least
    /// `other`'s capacities ([`RepairScratch::reserve_as`]); the kept
    /// state is not touched.
    pub(crate) fn reserve_as(&mut self, other: &Replay) {
        super::patch_solve::reserve_as(&mut self.out, &other.out);
        super::patch_solve::reserve_as(&mut self.bad, &other.bad);
        self.scratch.reserve_as(&other.scratch);
    }
}

impl Resident for Replay {
    fn resident(&mut self, touch: bool) -> usize {
        page_in(&mut self.out, touch) + page_in(&mut self.bad, touch) + self.scratch.resident(touch)
    }
}

/// Rebuilds the patches around the turned-over triangles `bad` (sorted,
/// as [`turned_over`] gives them) of `out` in place (see the module docs);
/// returns the triangles still turned over.
pub fn unflip(
    tris: &[[u32; 3]],
    adj: &Adjacency,
    source: &[[f64; 3]],
    out: &mut [[f64; 3]],
    turn: &[DQuat],
    bad: Vec<u32>,
    opts: &RepairOptions,
) -> Vec<u32> {
    let mut budget = Budget::new(WorkLimit::NONE);
    unflip_within(tris, adj, source, out, turn, bad, opts, &mut budget, None)
}

/// [`unflip`] within `budget`: a round whose patch (free and fixed
/// vertices) would go past the patch unknowns left is not solved (the
/// smoothing still runs); the patch unknowns solved are added to it.
///
/// `replay`: `(kept, resume)`. With `resume` the call starts from the
/// state `kept` holds (when it holds one: the caller asks only when `out`
/// and `bad` are the state the last call that kept it started from, with
/// the same options but `rounds`) and solves only the rounds after it;
/// every call that runs all its rounds keeps its state in `kept`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn unflip_within(
    tris: &[[u32; 3]],
    adj: &Adjacency,
    source: &[[f64; 3]],
    out: &mut [[f64; 3]],
    turn: &[DQuat],
    mut bad: Vec<u32>,
    opts: &RepairOptions,
    budget: &mut Budget,
    mut replay: Option<(&mut Replay, bool)>,
) -> Vec<u32> {
    let n = out.len();
    let most_rings = opts.most_rings.max(1);
    let mut rings = most_rings.min(2);
    let mut first = 0;
    if let Some((kept, resume)) = replay.as_mut() {
        if *resume && kept.valid && kept.rounds <= opts.rounds && kept.out.len() == n {
            out.copy_from_slice(&kept.out);
            bad.clone_from(&kept.bad);
            rings = kept.rings;
            first = kept.rounds;
            budget.done.replayed_rounds += kept.rounds;
        }
        kept.valid = false;
    }
    // The repair's memory: the workspace's (reused frame to frame), or
    // this call's own.
    let mut scratch = replay
        .as_mut()
        .map(|(kept, _)| std::mem::take(&mut kept.scratch))
        .unwrap_or_default();
    scratch.fit(n, tris.len());
    let f = RoundOf {
        tris,
        adj,
        source,
        turn,
        opts,
    };
    // Whether every round ran (none stopped by the budget or a failed
    // solve): only then is the state one a next pass can take.
    let mut complete = true;
    for _ in first..opts.rounds {
        if bad.is_empty() {
            break;
        }
        if !scratch.round(&f, out, &mut bad, rings, budget) {
            complete = false;
            break;
        }
        rings = rings.saturating_mul(2).min(most_rings);
    }
    if let Some((kept, _)) = replay.as_mut() {
        if complete && opts.replay {
            kept.out.resize(n, [0.0; 3]);
            kept.out.copy_from_slice(out);
            kept.bad.clone_from(&bad);
            kept.rounds = opts.rounds;
            kept.rings = rings;
            kept.valid = true;
        }
    }
    smooth(&f, out, &mut bad, &mut scratch);
    if let Some((kept, _)) = replay {
        kept.scratch = scratch;
    }
    bad
}

/// Up to [`RepairOptions::smooth`] Jacobi steps of umbrella smoothing on
/// the vertices of the turned-over triangles `bad` (kept sorted and up to
/// date), in `scratch`'s buffers.
fn smooth(f: &RoundOf, out: &mut [[f64; 3]], bad: &mut Vec<u32>, scratch: &mut RepairScratch) {
    let RoundOf {
        tris,
        adj,
        source,
        turn,
        ..
    } = *f;
    for _ in 0..f.opts.smooth {
        if bad.is_empty() {
            break;
        }
        let vs = &mut scratch.vs;
        vs.clear();
        vs.extend(bad.iter().flat_map(|&t| tris[t as usize]));
        vs.sort_unstable();
        vs.dedup();
        scratch.moved.clear();
        scratch.moved.extend(vs.iter().map(|&v| {
            let nb = &adj.vertices[v as usize];
            let s: DVec3 = nb.iter().map(|&u| DVec3::from_array(out[u as usize])).sum();
            (s / nb.len().max(1) as f64).to_array()
        }));
        for (&v, p) in scratch.vs.iter().zip(&scratch.moved) {
            out[v as usize] = *p;
        }
        scratch.recount_around(tris, adj, source, out, turn, bad);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::subdivide::{icosahedron, midpoint};

    #[test]
    fn a_pushed_in_vertex_is_pulled_back_out() {
        let m = midpoint(&midpoint(&icosahedron()));
        let src = m.positions().to_vec();
        let mut out = src.clone();
        // Push one vertex through the opposite side: its fan turns over.
        out[0] = (DVec3::from_array(src[0]) * -0.5).to_array();
        let turn = vec![DQuat::IDENTITY; src.len()];
        let adj = Adjacency::new(src.len(), m.triangles());
        assert!(!turned_over(m.triangles(), &src, &out, &turn).is_empty());
        let opts = RepairOptions {
            rounds: 4,
            ..Default::default()
        };
        let bad = turned_over(m.triangles(), &src, &out, &turn);
        let before = bad.len();
        let after = unflip(m.triangles(), &adj, &src, &mut out, &turn, bad, &opts).len();
        assert!(before > 0 && after == 0, "{before} -> {after}");
        assert!(DVec3::from_array(out[0]).distance(DVec3::from_array(src[0])) < 1e-6);
    }

    /// With the rings bounded ([`RepairOptions::most_rings`]) no round's
    /// patch reaches past that many rings (plus its fixed ring) around the
    /// triangles turned over when it starts, every round's factorisation
    /// is counted, and generated folds (one to three vertices pushed
    /// through a sphere, at several depths) are still all turned back;
    /// without the bound the same rounds grow bigger patches.
    #[test]
    fn bounded_rings_keep_patches_small_and_still_unfold() {
        let m = midpoint(&midpoint(&midpoint(&icosahedron())));
        let (tris, src) = (m.triangles(), m.positions().to_vec());
        let adj = Adjacency::new(src.len(), tris);
        let turn = vec![DQuat::IDENTITY; src.len()];
        // Vertices within `r` rings of `seeds`.
        let within = |seeds: &[u32], r: usize| {
            let mut seen = vec![false; src.len()];
            let mut front: Vec<u32> = seeds.to_vec();
            for &v in seeds {
                seen[v as usize] = true;
            }
            for _ in 0..r {
                let mut next = Vec::new();
                for &v in &front {
                    for &u in &adj.vertices[v as usize] {
                        if !seen[u as usize] {
                            seen[u as usize] = true;
                            next.push(u);
                        }
                    }
                }
                front = next;
            }
            seen.iter().filter(|&&s| s).count()
        };
        let mut cases = 0;
        for pushed in [&[0u32][..], &[0, 7], &[0, 7, 40]] {
            for depth in [-0.2, -0.5, 0.3] {
                let mut out = src.clone();
                for &v in pushed {
                    out[v as usize] = (DVec3::from_array(src[v as usize]) * depth).to_array();
                }
                let bad = turned_over(tris, &src, &out, &turn);
                if bad.is_empty() {
                    continue;
                }
                cases += 1;
                let seeds: Vec<u32> = {
                    let mut s: Vec<u32> = bad.iter().flat_map(|&t| tris[t as usize]).collect();
                    s.sort_unstable();
                    s.dedup();
                    s
                };
                let run = |most_rings: usize, rounds: usize| {
                    let opts = RepairOptions {
                        rounds,
                        most_rings,
                        ..Default::default()
                    };
                    let mut o = out.clone();
                    let mut budget = Budget::new(WorkLimit::NONE);
                    let left = unflip_within(
                        tris,
                        &adj,
                        &src,
                        &mut o,
                        &turn,
                        bad.clone(),
                        &opts,
                        &mut budget,
                        None,
                    );
                    (left.len(), budget.done)
                };
                // One round: its patch is the seeds' 2 rings plus the fixed ring.
                let (_, one) = run(2, 1);
                assert_eq!(one.patches, 1);
                assert_eq!(one.patch_vertices, within(&seeds, 3), "{pushed:?} {depth}");
                let (left, capped) = run(2, 4);
                assert_eq!(left, 0, "{pushed:?} {depth}: left turned over");
                assert!(capped.patches >= 1 && capped.patches <= 4);
                // Each round's patch is within 3 rings of what it started
                // from, which the first round's seeds bound from above
                // only while the folds stay where they were: bound by the
                // whole mesh, and by the unbounded run's work.
                assert!(capped.patch_vertices <= capped.patches * src.len());
                let (left_all, all) = run(usize::MAX, 4);
                assert_eq!(left_all, 0);
                if all.patches == capped.patches && all.patches > 2 {
                    assert!(
                        capped.patch_vertices < all.patch_vertices,
                        "{pushed:?} {depth}: {capped:?} vs {all:?}"
                    );
                }
            }
        }
        assert!(cases >= 6, "only {cases} generated folds turned over");
    }

    /// A pass resumed from the kept state of a pass with one round fewer
    /// that started where it starts ([`Replay`]) gives the fresh pass's
    /// frame and triangles bit for bit, solving only the round it adds;
    /// over generated folds (one to three vertices pushed through a
    /// sphere at several depths), rings bounded and not, 1-4 rounds.
    #[test]
    fn a_replayed_pass_is_the_fresh_pass() {
        let m = midpoint(&midpoint(&midpoint(&icosahedron())));
        let (tris, src) = (m.triangles(), m.positions().to_vec());
        let adj = Adjacency::new(src.len(), tris);
        let turn = vec![DQuat::IDENTITY; src.len()];
        let (mut cases, mut moved) = (0, 0);
        for pushed in [&[0u32][..], &[0, 7], &[0, 7, 40], &[3, 90, 200]] {
            for depth in [-0.2, -0.5, 0.3, 0.6] {
                let mut start = src.clone();
                for &v in pushed {
                    start[v as usize] = (DVec3::from_array(src[v as usize]) * depth).to_array();
                }
                let bad = turned_over(tris, &src, &start, &turn);
                if bad.is_empty() {
                    continue;
                }
                for most_rings in [2, usize::MAX] {
                    for rounds in 1..4 {
                        cases += 1;
                        let opts = |rounds| RepairOptions {
                            rounds,
                            most_rings,
                            ..Default::default()
                        };
                        let run = |rounds, replay: Option<(&mut Replay, bool)>| {
                            let mut out = start.clone();
                            let mut budget = Budget::new(WorkLimit::NONE);
                            let left = unflip_within(
                                tris,
                                &adj,
                                &src,
                                &mut out,
                                &turn,
                                bad.clone(),
                                &opts(rounds),
                                &mut budget,
                                replay,
                            );
                            (out, left, budget.done)
                        };
                        let (fresh, fresh_left, fresh_work) = run(rounds + 1, None);
                        let mut kept = Replay::default();
                        let (first, _, first_work) = run(rounds, Some((&mut kept, false)));
                        moved += usize::from(first != start);
                        let (again, again_left, again_work) =
                            run(rounds + 1, Some((&mut kept, true)));
                        let bits = |p: &[[f64; 3]]| -> Vec<u64> {
                            p.iter().flatten().map(|c| c.to_bits()).collect()
                        };
                        assert_eq!(bits(&again), bits(&fresh), "{pushed:?} {depth} {rounds}");
                        assert_eq!(again_left, fresh_left, "{pushed:?} {depth} {rounds}");
                        assert_eq!(again_work.replayed_rounds, rounds);
                        // Only the added round is solved, when it runs.
                        assert!(again_work.patches <= 1);
                        assert_eq!(
                            again_work.patches + first_work.patches,
                            fresh_work.patches,
                            "{pushed:?} {depth} {rounds}"
                        );
                    }
                }
            }
        }
        assert!(cases >= 30 && moved > 0, "{cases} cases, {moved} moved");
    }

    /// A second pass over the same frames makes no allocation call in the
    /// repair but faer's symbolic analysis of each patch, a few calls a
    /// patch whatever its size (the first pass grows the workspace's
    /// buffers to the largest patch): generated folds (one to three
    /// vertices pushed through a sphere at several depths) on the sphere
    /// as made, mirrored, turned and scaled ×100, with the rings bounded
    /// and not. The patches are larger than the bound a patch, so memory
    /// taken a vertex or a row (the solver before: a row per vertex) fails.
    /// A fresh state grown to the first ([`Replay::reserve_as`]) makes no
    /// call outside faer on its first pass.
    #[test]
    fn a_second_pass_allocates_nothing_but_the_patches_orderings() {
        use super::super::patch_solve::counted::calls;
        let m = midpoint(&midpoint(&midpoint(&icosahedron())));
        let tris = m.triangles();
        let r = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 0.8);
        type Map = fn(DVec3, DQuat) -> DVec3;
        let variants: [(&str, Map); 4] = [
            ("plain", |p, _| p),
            ("mirrored", |p, _| DVec3::new(-p.x, p.y, p.z)),
            ("turned", |p, r| r * p),
            ("scaled", |p, _| p * 100.0),
        ];
        // Most allocation calls a patch may make (faer's ordering and
        // symbolic factor).
        const PER_PATCH: usize = 16;
        for (name, map) in variants {
            let src: Vec<[f64; 3]> = m
                .positions()
                .iter()
                .map(|p| map(DVec3::from_array(*p), r).to_array())
                .collect();
            let adj = Adjacency::new(src.len(), tris);
            let turn = vec![DQuat::IDENTITY; src.len()];
            let mut frames = Vec::new();
            for pushed in [&[0u32][..], &[0, 7], &[0, 7, 40], &[3, 90, 200]] {
                for depth in [-0.2, -0.5, 0.3] {
                    let mut start = src.clone();
                    for &v in pushed {
                        start[v as usize] = (DVec3::from_array(src[v as usize]) * depth).to_array();
                    }
                    let bad = turned_over(tris, &src, &start, &turn);
                    if !bad.is_empty() {
                        frames.push((start, bad));
                    }
                }
            }
            assert!(frames.len() >= 8, "{name}: {} folds", frames.len());
            for most_rings in [2, usize::MAX] {
                let opts = RepairOptions {
                    most_rings,
                    ..Default::default()
                };
                let mut kept = Replay::default();
                let mut out = src.clone();
                let mut bad = Vec::with_capacity(tris.len());
                let mut pass = |kept: &mut Replay| {
                    let (before, mut work) = (calls(), Work::default());
                    for (start, b) in &frames {
                        out.copy_from_slice(start);
                        bad.clear();
                        bad.extend_from_slice(b);
                        let mut budget = Budget::new(WorkLimit::NONE);
                        bad = unflip_within(
                            tris,
                            &adj,
                            &src,
                            &mut out,
                            &turn,
                            std::mem::take(&mut bad),
                            &opts,
                            &mut budget,
                            Some((kept, false)),
                        );
                        work.patches += budget.done.patches;
                        work.patch_vertices += budget.done.patch_vertices;
                    }
                    let after = calls();
                    ([after[0] - before[0], after[1] - before[1]], work)
                };
                let (first, _) = pass(&mut kept);
                let ([outside, faer], work) = pass(&mut kept);
                let case = format!("{name}, rings {most_rings}: first pass {first:?}, {work:?}");
                assert!(work.patches >= frames.len(), "{case}");
                assert_eq!(outside, 0, "{case}: {outside} calls outside faer");
                assert!(faer <= PER_PATCH * work.patches, "{case}: {faer} in faer");
                assert!(
                    work.patch_vertices > PER_PATCH * work.patches,
                    "{case}: patches too small to tell"
                );
                // A second workspace grown to the first (the live overlap's
                // second slot) allocates nothing on its first pass either.
                let mut grown = Replay::default();
                grown.reserve_as(&kept);
                let ([outside, _], _) = pass(&mut grown);
                assert_eq!(outside, 0, "{case}: grown to the first, {outside} calls");
            }
        }
    }

    /// The frame's source normals, turned per reading, flag the same
    /// triangles as [`turned_over`] and give [`super::super::untangle::references`]'
    /// normals and areas bit for bit (a deformed, partly folded sphere under
    /// generated per-vertex turns).
    #[test]
    fn normals_once_per_frame_are_the_readings_own() {
        use super::super::untangle::{references, source_areas, turned_references};
        let m = midpoint(&midpoint(&midpoint(&icosahedron())));
        let (tris, src) = (m.triangles(), m.positions().to_vec());
        let nt = tris.len();
        let out: Vec<[f64; 3]> = src
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let v = DVec3::from_array(*p);
                (v * (1.0 + 0.3 * (i as f64 * 0.7).sin()) - DVec3::X * (0.4 * v.y).sin()).to_array()
            })
            .collect();
        let mut sn = vec![DVec3::ZERO; nt];
        source_normals(tris, &src, &mut sn);
        let mut seen = 0;
        // One flag buffer for every reading, as a workspace keeps it.
        let mut flags = Vec::new();
        for k in 0..4 {
            let turn: Vec<DQuat> = (0..src.len())
                .map(|i| DQuat::from_rotation_y(k as f64 * 0.9 + (i % 7) as f64 * 0.2))
                .collect();
            let bad = turned_over(tris, &src, &out, &turn);
            assert_eq!(turned_over_from(tris, &sn, &out, &turn), bad, "turns {k}");
            let flagged = turned_over_flagged(tris, &sn, &out, &turn, &mut flags);
            assert_eq!(flagged, bad, "turns {k}, flagged");
            assert_eq!(
                flagged.capacity(),
                bad.len(),
                "allocated once, to its length"
            );
            seen += bad.len();
            let (mut n0, mut a0) = (vec![DVec3::ZERO; nt], vec![0.0; nt]);
            references(tris, &src, &turn, &mut n0, &mut a0);
            let (mut n1, mut a1) = (vec![DVec3::ONE; nt], vec![1.0; nt]);
            turned_references(tris, &sn, &turn, &mut n1);
            source_areas(&sn, &mut a1);
            for t in 0..nt {
                assert_eq!(
                    n0[t].to_array().map(f64::to_bits),
                    n1[t].to_array().map(f64::to_bits)
                );
                assert_eq!(a0[t].to_bits(), a1[t].to_bits());
            }
        }
        assert!(
            seen > 0,
            "nothing turned over: the check has nothing to catch"
        );
    }

    #[test]
    fn rotated_triangles_are_not_turned_over() {
        let m = icosahedron();
        let src = m.positions().to_vec();
        let r = DQuat::from_rotation_x(2.5);
        let out: Vec<[f64; 3]> = src
            .iter()
            .map(|p| (r * DVec3::from_array(*p)).to_array())
            .collect();
        let turn = vec![r; src.len()];
        assert!(turned_over(m.triangles(), &src, &out, &turn).is_empty());
        let none = vec![DQuat::IDENTITY; src.len()];
        assert!(!turned_over(m.triangles(), &src, &out, &none).is_empty());
    }
}
