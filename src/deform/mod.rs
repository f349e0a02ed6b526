//! Skeleton-driven editing of retrieved frames (Huang et al. 2015,
//! Sec. 5.2.3): linear blend skinning gives positional constraints
//! ([`lbs`]), and a part-based PCA Laplacian deformation
//! ([`part_laplacian`], [`pca`]) makes the surface meet them while keeping
//! the captured surface detail and dynamics.
//!
//! The deformation space of a frame is centred on that frame's own
//! Laplacian coordinates (the paper centres it on the examples' mean; see
//! [`part_laplacian`]), so the captured surface detail and dynamics of the
//! retrieved frame are kept and the learnt modes say how it may bend.
//!
//! Per body part (the rig embedding's overlapping regions, so a skirt
//! belongs to both legs) the deformation space is learnt from example
//! frames of the database chosen to cover the part's range of rotation
//! (farthest-point sampling of the part's rotation relative to the rest
//! pose), with their Laplacian coordinates expressed in the part's own
//! frame. Because a rotation commutes with the Laplacian, a part rotated by
//! `R` in the target pose is solved in its own frame (`y = Rᵀx`, constraints
//! rotated by `Rᵀ`) and turned back, so one factorisation per part serves
//! every pose. Parts are solved from the torso outwards; a vertex a child
//! shares with its parent is constrained (strongly) to the parent's own
//! result ([`DeformOptions::parent_seams`], the default since session 27;
//! off, to the last result solved there, which under a skirt is the other
//! thigh's), the
//! others to their LBS positions; the end of a region that reaches
//! into a child part is held at LBS positions too
//! ([`DeformOptions::hold_joints`]), so the joint is where the skeleton
//! puts it before the child is solved ([`DeformOptions::constraint_skin`]
//! places those targets by dual-quaternion skinning, [`dqs`], instead:
//! off by default, measured in its doc). Where regions overlap (siblings such
//! as the two thighs under a skirt, or a parent and child near a joint) the
//! results are blended by the parts' skin weights, so parts join without
//! seams ([`DeformOptions::overlap_weight`] holds the two thighs' shared
//! vertices at one target in both solves first, and
//! [`DeformOptions::blend_taper`] takes the weights to 0 at a region's
//! edge; both off by default).
//!
//! Constraint vertices are chosen once per character, away from joints
//! where LBS collapses: vertices bound (≥ 95 %) to one bone whose rest
//! position projects into the middle 60 % of that bone, every `stride`-th.
//! The manifest's `[deform]` section can give the constraint vertices and
//! the example frames instead.
//!
//! With [`DeformOptions::cloth_stitch`] (on by default since session 30),
//! after the blend the cloth (a skirt: [`soft::softness`] above 0) is
//! solved once more as one piece ([`cloth`]):
//! its captured Laplacian coordinates turned by rotations fitted to the
//! blended surface, pulled towards the blend. Each part's solve turns the
//! cloth's coordinates by the skin's blend of its bones' turns, which is
//! not how a skirt between two thighs turns, and crumples it (README,
//! issue 42, measured per stage). The repair then reads and rebuilds the
//! cloth with the stitch's rotations ([`DeformOptions::cloth_turns`]), and
//! a frame it cannot leave unfolded is repaired from the unstitched blend
//! instead ([`DeformOptions::cloth_fallback`]).
//!
//! Where the solve turns triangles over (under the skirt, at the knees) a
//! repair ([`unflip`], [`untangle`]) rebuilds them, first against the
//! skin's turns, then against the surface's own ([`near_turns`],
//! [`DeformOptions::repair_turns`]); Huang et al.'s method has no such
//! step, and the part-based PCA Laplacian cannot do without it here: on
//! the real samba capture the solve alone turns 4,845 (CMU 02_02) to
//! 68,743 (131_01) triangle-frames over (README, issue 42).

pub mod arap;
pub mod bend_examples;
pub mod cloth;
pub mod cloth_reach;
pub mod deformer;
pub mod dqs;
pub mod hold;
pub mod lbs;
pub mod levels;
pub mod near_turns;
pub mod options;
pub(crate) mod overrides;
pub mod part_laplacian;
mod patch_solve;
pub mod pca;
pub mod regions;
pub mod repair_budget;
mod repair_options;
pub(crate) mod resident;
pub mod soft;
pub mod step_zone;
mod turned;
pub mod unflip;
mod unflip_patch;
pub mod untangle;

pub use deformer::{DeformWorkspace, Deformer, RegionResult};
pub use options::{DeformMode, DeformOptions, RepairTurns, TurnedOver};
pub use regions::{Held, part_joint};
pub use repair_budget::{RepairBudget, RepairBudgetError};

/// This thread's allocation calls so far in the library's tests (outside
/// faer's symbolic analysis; [`patch_solve::counted`]): other modules'
/// tests of what allocates per frame read it too (issue 45).
#[cfg(test)]
pub(crate) fn allocation_calls() -> usize {
    patch_solve::counted::calls()[0]
}
