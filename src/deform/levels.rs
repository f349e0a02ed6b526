//! The regions' solve order as levels, so the regions of one level are
//! solved at once on several threads ([`super::DeformOptions::parallel_regions`]).
//!
//! A region's constraints read the LBS positions, the overlap's shared
//! targets and, at its seams, the results of regions solved before it
//! ([`Target::Region`]: its parent, with `sibling_seams` also a sibling).
//! A region's level is one more than the highest level it reads (0 when it
//! reads none): the torso alone, then the head, upper arms and thighs,
//! then the forearms and shins, then the feet. Within a level no region
//! reads another, so solving them in any order on any thread gives each
//! the same inputs and, with its own scratch ([`RegionScratch`]) and the
//! same arithmetic in the same order, the same bits as the sequential
//! solve.
//!
//! Two configurations read results in solve order and keep the sequential
//! solve: seams held to the last result solved at the vertex
//! ([`Target::Last`], `parent_seams` off) and more than one overlap pass
//! (each re-solves a region's siblings after blending them).
//!
//! Cost: building the levels is one pass over the constraints, once per
//! character.

use super::part_laplacian::{RegionSolver, RegionWorkspace};
use super::regions::{Region, Target};
use glam::DQuat;

/// Each region's level, and the regions of each level in solve order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct Levels {
    /// Level of each region.
    pub(super) of: Vec<u32>,
    /// The regions of level `l`: `members[start[l]..start[l + 1]]`.
    members: Vec<usize>,
    start: Vec<usize>,
}

impl Levels {
    /// The levels of `regions` (in solve order), or `None` when a region
    /// reads a result in solve order ([`Target::Last`], or `overlap_passes`
    /// above 1 with siblings to re-solve) or a seam of a region not solved
    /// before it.
    pub(super) fn new(regions: &[Region], overlap_passes: usize) -> Option<Levels> {
        let mut of: Vec<u32> = Vec::with_capacity(regions.len());
        for (k, r) in regions.iter().enumerate() {
            if overlap_passes > 1 && !r.siblings.is_empty() {
                return None;
            }
            let mut level = 0;
            for t in &r.targets {
                match *t {
                    Target::Last(_) => return None,
                    Target::Region(j, _) if j as usize >= k => return None,
                    Target::Region(j, _) => level = level.max(of[j as usize] + 1),
                    Target::Lbs(_) | Target::Shared(_) => {}
                }
            }
            of.push(level);
        }
        let count = of.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
        let mut start = vec![0; count + 1];
        let mut members = Vec::with_capacity(regions.len());
        for l in 0..count {
            members.extend((0..regions.len()).filter(|&k| of[k] as usize == l));
            start[l + 1] = members.len();
        }
        Some(Levels { of, members, start })
    }

    /// Number of levels.
    pub(super) fn count(&self) -> usize {
        self.start.len() - 1
    }

    /// The regions of level `l`, in solve order.
    pub(super) fn members(&self, l: usize) -> &[usize] {
        &self.members[self.start[l]..self.start[l + 1]]
    }
}

/// One region's scratch of a frame's deformation (all in the region's
/// local vertex order): what a thread solving it writes, and nothing
/// another region's solve reads while it runs.
pub struct RegionScratch {
    /// The source frame's positions.
    pub(super) xs: Vec<[f64; 3]>,
    /// The turned source Laplacian coordinates `δ₀` (Eq. 32).
    pub(super) delta: Vec<[f64; 3]>,
    /// The solved positions, world coordinates.
    pub(super) world: Vec<[f64; 3]>,
    /// The constraints' targets in the region's frame.
    pub(super) targets: Vec<[f64; 3]>,
    /// The solved positions in the region's frame.
    pub(super) local: Vec<[f64; 3]>,
    /// The solver's scratch.
    pub(super) ws: RegionWorkspace,
    /// The source's Laplacian coordinates, unturned (local steps).
    pub(super) lsrc: Vec<[f64; 3]>,
    /// Each vertex's rotation of the local steps.
    pub(super) rots: Vec<DQuat>,
    /// Each vertex's skin-blended turn (the local steps in a zone,
    /// [`super::step_zone`]).
    pub(super) skin: Vec<DQuat>,
}

impl RegionScratch {
    /// Scratch of a region with `solver` and `constraints` constraints.
    pub(super) fn new(solver: &RegionSolver, constraints: usize) -> RegionScratch {
        let n = solver.vertices.len();
        RegionScratch {
            xs: vec![[0.0; 3]; n],
            delta: vec![[0.0; 3]; n],
            world: vec![[0.0; 3]; n],
            targets: vec![[0.0; 3]; constraints],
            local: vec![[0.0; 3]; n],
            ws: solver.workspace(),
            lsrc: vec![[0.0; 3]; n],
            rots: vec![DQuat::IDENTITY; n],
            skin: vec![DQuat::IDENTITY; n],
        }
    }

    /// The solved positions (world coordinates, local order).
    pub fn world(&self) -> &[[f64; 3]] {
        &self.world
    }
}
