//! The deformation's mode, options and turned-over count.

pub use super::repair_budget::RepairBudget;
use super::unflip;
use super::untangle;

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
    pub include: Option<crate::graph::FlatFrame>,
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
    /// Hold soft vertices (a skirt, [`super::soft::softness`] above 0) too
    /// when holding the joints. Default true. Off, it barely changes the
    /// folds (session 22, CMU 02_02 on the real samba capture, triangle-
    /// frames turned over before the repair: 3,599 → 3,412; 131_01 59,914
    /// → 58,891): the folds are not on the soft vertices held (418 of
    /// 02_02's 2,078 on the left thigh are soft) but where the thigh and
    /// shin regions overlap at the knee (1,255 + 538 + 766 of 3,599) and
    /// where the two thighs overlap under the skirt (609).
    pub hold_soft: bool,
    /// Constrain a region's vertices shared with its last sibling solved
    /// before it (the right thigh's with the left's, under a skirt) to that
    /// sibling's result, as seams. Default false: measured worse (session
    /// 22, triangle-frames turned over before the repair on the real samba
    /// capture: CMU 02_02 3,599 → 4,255, 131_01 59,914 → 66,055; the
    /// folds move from the left leg to the right).
    pub sibling_seams: bool,
    /// Scale a seam (a vertex a region shares with its parent, held to the
    /// parent's result) by the parent's share of the two regions' blending
    /// weights there, `w_parent / (w_parent + w_child)`: near the joint the
    /// child follows the parent, below it (the shin's part of the thigh's
    /// region) it follows its own solve, and the blend by the same skin
    /// weights joins the two (issue 42). Off, every seam has
    /// `seam_weight` and the child copies the parent's result over the
    /// whole overlap, including the free lower end of the thigh's region.
    /// Default false: measured (session 23, `retarget --json` onto the
    /// real samba capture, with `hold_spread`), triangle-frames turned over
    /// before the repair 02_02 3,683 → 3,521, 131_01 59,945 → 58,471,
    /// 131_02 8,360 → 8,432, but turned over against the rest frame after
    /// the repair 288 → 356 (02_02) and 703 → 741 (131_02): a mixed step.
    pub seam_by_weight: bool,
    /// Scale a held joint vertex (`hold_joints`: the region's end inside a
    /// child part, held at LBS) by the region's share of the blending
    /// weights there, `w_region / (w_region + w_child)`, so the thigh's
    /// targets loosen below the knee where its result counts little in
    /// the blend (issue 42). Default false. Measured (session 36,
    /// `SURFMOTION_HOLD=by_weight=on`, CMU 02_02 / 03_02 onto the real
    /// samba capture, `eval --surface`): creases 3,026 → 2,844 / 5,908 →
    /// 5,356, crossings 6,830 → 5,496 / 2,962 → 2,507, but turned over
    /// against the rest frame 5 → 9 / 92 → 104, rough 7,070 → 8,222 on
    /// 03_02 and joint-velocity error 0.116 → 0.153 / 0.123 → 0.154
    /// cm/frame: the loosened knee drifts from the skeleton.
    pub hold_by_weight: bool,
    /// Hold every vertex of a region's end inside a child part
    /// (`hold_joints`) with `constraint_weight / √stride`, instead of
    /// every `stride`-th with `constraint_weight`: the same total pull
    /// towards the LBS positions, spread evenly, so single held vertices
    /// do not dimple the surface around them (issue 42).
    /// Default false (measured with `seam_by_weight`, above; alone,
    /// session 36, `SURFMOTION_HOLD=spread=on`, CMU 02_02 / 03_02 onto the
    /// real samba capture: creases 3,026 → 3,268 / 5,908 → 6,326, turned
    /// over against the rest frame 5 → 20 / 92 → 124).
    pub hold_spread: bool,
    /// Rotation-aware local steps after each region's solve ([`super::arap`]):
    /// each vertex's rotation re-fitted to the solved one-ring, the source's
    /// Laplacian coordinates turned by it, solved again with the same
    /// factorisation. Default 0: measured on the samba capture (issue 42),
    /// two steps leave the turned-over triangle-frames before the repair
    /// nearly as they were (CMU 02_02 3,599 → 3,066, 03_02 15,228 →
    /// 15,036) for three times the deformation's time (02_02: 6.7 →
    /// 20.7 s for 75 frames, on a loaded shared machine): the folds are in the
    /// thighs' regions (the skirt; 02_02 without repair, `eval --surface`:
    /// thighs 789 + 264 triangle-frames against the rest frame, shins
    /// 56 + 54, torso 2), where the overlapping thigh solves and their
    /// held LBS targets disagree, not in the turn of the coordinates.
    /// On the knees' creases it does act (session 36,
    /// `tools::surface_knees` with `SURFACE_KNEE_STEPS=2`, crease
    /// edge-frames within 8 cm of a knee after the repair, CMU 02_02 / 03_02
    /// onto the real samba capture): 1,517 → 865 / 1,512 → 1,055, all
    /// creases 3,027 → 2,032 / 5,908 → 5,538; through `retarget` + `eval`
    /// (`SURFMOTION_HOLD=steps=2`) turned over against the rest frame 5 →
    /// 10 / 92 → 102 and the retarget's CPU about 1.6× (README).
    pub local_steps: usize,
    /// Where the local steps (`local_steps`) and a non-linear
    /// `constraint_skin` act ([`super::step_zone`]): everywhere (the
    /// default, as measured above) or only near the knees (and elbows),
    /// the rest of the body keeping the default's solve and linear
    /// targets. Default `Everywhere`. Measured (session 37,
    /// `SURFMOTION_HOLD=skin=dq,steps=2,zone=knees`, CMU 02_02 / 03_02 onto
    /// the real samba capture, `retarget --json` then `eval --surface`,
    /// element-frames, main → this): creases 3,026 → 2,369 / 5,908 →
    /// 5,343, rough 2,885 → 2,621 / 7,070 → 6,592, crossings 6,830 →
    /// 6,121 / 2,962 → 2,616, retarget CPU 1.17-1.19× (everywhere: 1.6×);
    /// but turned over against the rest frame 5 → 7 / 92 → 91,
    /// joint-velocity error 0.116 → 0.122 / 0.123 → 0.127 cm/frame and the
    /// left shin's joint-follow p95 2.53 → 3.16 / 9.93 → 10.74 cm: not the
    /// default. Linear targets (`steps=2,zone=knees`): creases 2,414 /
    /// 5,723, turned over 15 / 82, velocity 0.116 / 0.128. The triangles
    /// the steps turn over (everywhere or in the zone) lie behind the
    /// knee, 4-6 cm behind the joint and 2-3.5 cm above it, where the bent
    /// knee compresses the skin (`tools::surface_turned`). README "The
    /// surface measure", issue 42.
    pub step_zone: super::step_zone::StepZone,
    /// The zone's reach: a vertex is fully in it within this fraction of
    /// the child bone's rest length of the joint (the shin's for a knee),
    /// half in at 1.5 times that, out from twice. Default 0.2 (8 cm on
    /// the samba capture's knees).
    pub step_reach: f64,
    /// The most work the fold repair may do on one frame
    /// ([`RepairBudget`]). Default [`RepairBudget::NONE`] (the unbounded
    /// repair, what offline `retarget` runs); live sessions use
    /// [`RepairBudget::LIVE`] (a deadline a frame).
    pub repair_budget: RepairBudget,
    /// Weight holding the vertices two sibling regions share (the two
    /// thighs' regions under a skirt) at one shared target in both solves:
    /// their LBS position, then (`overlap_passes` above 1) the two
    /// results blended by skin weight, so the solves agree there before
    /// they are blended. 0 turns it off. Default 0: measured (session 24,
    /// with `parent_seams`, weight 3, onto the real samba capture), the
    /// triangle-frames turned over before the repair drop on CMU 02_02,
    /// 131_01, 131_02, 03_02 (5,837 → 3,544, 72,465 → 65,177, 11,131 →
    /// 6,551, 20,204 → 17,062) and the joint-velocity error with them, but
    /// those turned over against the rest frame after the repair rise on
    /// three of four (465 → 567, 16,864 → 17,893, 5,706 → 6,016; 131_02
    /// 1,067 → 698) and the ground penetration too (README, issue 42).
    pub overlap_weight: f64,
    /// Solves of the overlapping siblings (at least 1); each after the
    /// first takes the last one's blend as the shared target. Default 1.
    pub overlap_passes: usize,
    /// Blending weights that fall to 0 at a region's edge
    /// ([`super::regions::region_weights`]). Default false.
    pub blend_taper: bool,
    /// Hold a seam (a vertex a region shares with its parent) to the
    /// parent region's own result. Off, a seam is held to the result of the
    /// last region solved that has the vertex, which is the parent's
    /// except where the parent overlaps a sibling solved after it: the
    /// left shin, solved after both thighs, is then tied to the *right*
    /// thigh's result under the skirt (session 23 measured the left shin
    /// 2-3 cm from its left thigh there, the right 0.02 cm).
    /// Default true (session 27; false gives the outputs of sessions up to
    /// 26). Alone (session 24) it lowered the triangle-frames turned over
    /// before the repair (CMU 02_02 on the real samba capture 5,837 →
    /// 4,845) but raised those turned over against the rest frame after it
    /// (465 → 735): the repair read "turned over" with the skin's turns,
    /// which under the skirt are not the surface's. With
    /// [`RepairTurns::SkinThenSurface`], 465 → 55 (README, issue 42).
    pub parent_seams: bool,
    /// The rotations the fold repair reads "turned over" with
    /// ([`RepairTurns`]).
    pub repair_turns: RepairTurns,
    /// Most repairs against the surface's own turns
    /// ([`RepairTurns::SkinThenSurface`], [`RepairTurns::Surface`]), each
    /// after reading the turns again off the frame as the last left it, each
    /// after the first reaching one doubling of rings further around what is
    /// still flagged; a frame stops at the first round that leaves nothing
    /// facing against its own turns, so the rounds past it cost nothing.
    /// Default 6 (session 26 ran 2 and left triangle-frames facing against
    /// their own neighbourhoods: CMU 02_02 on the real samba capture 8,
    /// 131_01 frame 96 3; README, issue 42).
    pub surface_rounds: usize,
    /// Stop the surface repair's rounds ([`DeformOptions::surface_rounds`])
    /// after this many rounds in a row that do not lower the count of
    /// triangles facing against their own turns (the frame kept is still
    /// the round's that faced least). Default `usize::MAX` (off: every
    /// round runs until none face against their turns). Measured (session
    /// 33, live `--replay` of CMU 02_02 at lag 0 onto the real samba
    /// capture): 1 leaves 2 triangle-frames facing against their turns,
    /// which the cloth fallback then repairs again, so the factorisations
    /// rise (3.41 → 3.55 a frame); on 131_01 no fewer. Not the default.
    pub surface_stall: usize,
    /// Solve the regions level by level, the regions of one level (the
    /// head, upper arms and thighs; then the forearms and shins; then the
    /// feet) on several threads at once ([`super::levels`]). The result is
    /// the sequential solve's bit for bit; configurations that read
    /// results in solve order (`parent_seams` off, `overlap_passes` above
    /// 1) are solved in order either way. Default true (session 28).
    pub parallel_regions: bool,
    /// Weight `w` of the cloth stitch ([`super::cloth`]): after the part
    /// solves are blended, the cloth vertices (a skirt:
    /// [`super::soft::softness`] above 0) are solved once more as one
    /// piece, their captured detail turned with them and pulled towards
    /// the blend with `w`, so the steps between the overlapping pelvis and
    /// thigh solves do not crumple the hem. 0 turns it off (the outputs of
    /// session 29; `SURFMOTION_CLOTH=stitch=0`, [`super::cloth::CLOTH_ENV`]).
    /// Default 0.5 (session 30, with `cloth_turns` and `cloth_fallback`;
    /// README, issue 42): the skirt's mean bend down on all eight yardstick
    /// clips onto the real samba capture (02_01 11.21° → 10.00°, 131_01
    /// 12.84° → 11.02°), nothing left facing against its own neighbourhood
    /// after the repair. Session 29 measured the stitch alone, which left
    /// CMU 131_01 frame 102 one triangle so
    /// (`deform::a_real_retarget_keeps_every_vertex_in_its_ring`).
    pub cloth_stitch: f64,
    /// Rotation fits per frame of the cloth stitch, each followed by a
    /// prefactored solve ([`super::cloth`]). Default 2.
    pub cloth_steps: usize,
    /// With the cloth stitch, the fold repair reads "turned over" on the
    /// cloth, and solves its patches there, with the rotations the stitch
    /// fitted to the cloth's one-rings instead of the skin's blend of the
    /// bones' turns ([`super::cloth`]), so a patch asks the cloth for the
    /// shape the stitch gave it. The reported `before` count is still
    /// against the skin's turns. Default true (session 30): without it the
    /// repair's patches crumple the stitched skirt again where the solve
    /// turned much over (CMU 131_01 on the real samba capture: skirt bend
    /// 11.52° without, 11.02° with; 03_02 11.27° → 10.78° and joint-velocity
    /// error 0.132 → 0.123 cm/frame).
    pub cloth_turns: bool,
    /// With the cloth stitch, a frame whose repair leaves triangles facing
    /// against their own neighbourhoods is repaired again from the blend
    /// without the stitch, and the result that leaves fewer is kept
    /// ([`super::cloth`]). Default true (session 30): with `cloth_turns`
    /// alone, 131_01's first 130 frames leave frame 117 five triangles
    /// facing against their neighbourhoods, the stitch without either
    /// frame 102 one; with the fallback, none (on the eight yardstick
    /// clips it never changes a frame).
    pub cloth_fallback: bool,
    /// Rings of vertices the cloth stitch reaches beyond the cloth
    /// ([`super::cloth_reach`]): the skirt's top, the waist and the
    /// thighs' skin under the skirt, which the overlapping pelvis and
    /// thigh solves share. Default 0 (the stitch on the cloth alone).
    /// Measured (session 35, `SURFMOTION_CLOTH=rings=4`, CMU 02_02 / 03_02
    /// onto the real samba capture, `eval --surface`): creases 3,026 →
    /// 2,779 / 5,908 → 5,232 element-frames, but turned over against the
    /// rest frame 5 → 16 on 02_02 and crossings 2,962 → 3,403 on 03_02.
    pub cloth_rings: usize,
    /// Joints whose blend zones the cloth stitch solves too
    /// ([`super::cloth_reach::StitchJoints`]). Default none. Session 35
    /// found most creases off the cloth: of CMU 02_02's 3,026 crease
    /// edge-frames onto the real samba capture, 2,625 are on edges
    /// without a cloth end and 78 % lie within 8 cm of a knee (03_02: 50 %),
    /// mostly behind it, where the thigh's and shin's solves are blended
    /// (skinning alone creases there as much). Measured (`SURFMOTION_CLOTH=
    /// joints=limbs`, 02_02 / 03_02, `eval --surface`, element-frames,
    /// default → limbs): creases 3,026 → 2,415 / 5,908 → 4,625, rough
    /// 2,885 → 1,703 / 7,070 → 3,569, stretched 1,252 → 885 / 3,981 →
    /// 2,663, joint-velocity error 0.116 → 0.112 / 0.123 → 0.097 cm/frame,
    /// the shins' joints regressed from the surface p95 (l, r) 03_02 9.93,
    /// 6.56 → 4.51, 2.74 cm; but turned over against the rest frame 5 →
    /// 31 / 92 → 164 and crossings 6,830 → 6,973 / 2,962 → 3,741, on the
    /// thighs above the knee (README, issue 42). `knees` alone: creases
    /// 2,548 / 5,550, turned over 32 / 178. Not the default.
    pub stitch_joints: super::cloth_reach::StitchJoints,
    /// With `stitch_joints`, leave out of the joints' zones every vertex
    /// within this many rings of the cloth, so a knee's zone is not
    /// stitched as one piece with the hem it touches (the samba capture's
    /// hem is joined to the legs by triangles: 260 of its knee zones'
    /// 1,013 vertices are cloth). Default 0 (nothing left out).
    pub stitch_apart: usize,
    /// The skinning that places the solve's positional constraints (the
    /// LBS targets of Eq. 32, the held joint ends of `hold_joints`):
    /// linear blend (Huang et al. 2015) or dual quaternions
    /// ([`super::dqs`], Kavan et al. 2008), which do not pull a vertex
    /// weighted between two bones towards their joint, or each vertex's
    /// heaviest bone alone. `Deformer::deform`'s `Lbs` mode stays linear.
    /// Default linear. Measured (session 36, `SURFMOTION_HOLD=skin=dq`,
    /// [`super::hold::HOLD_ENV`]; CMU 02_02 / 03_02 onto the real samba
    /// capture, `retarget --json` then `eval --surface`, element-frames,
    /// linear → dual quaternions): creases 3,026 → 3,019 / 5,908 → 5,210,
    /// rough 2,885 → 2,791 / 7,070 → 6,570, slivers 406 → 427 / 1,147 →
    /// 813, stretched 1,252 → 1,250 / 3,981 → 3,376, but turned over
    /// against the rest frame 5 → 10 / 92 → 107, crossings 6,830 → 7,086 /
    /// 2,962 → 3,174 and joint-velocity error 0.116 → 0.119 / 0.123 →
    /// 0.142 cm/frame: the knees' creases are not the held targets'
    /// collapse (02_02's barely move). `rigid`: every figure worse
    /// (creases 5,656 / 13,287). With `hold_by_weight` (`skin=dq,
    /// by_weight=on`): creases 2,839 / 4,857, turned over 6 / 79, but
    /// velocity error 0.155 / 0.157 and the shins' joint-follow p95 worse
    /// (02_02 left 2.53 → 3.23 cm). README "The surface measure", issue 42.
    pub constraint_skin: super::dqs::ConstraintSkin,
    /// Gain of the knees' example-based correction
    /// ([`super::bend_examples`]): before the solve, the retrieved frame's
    /// vertices near each knee (within twice `step_reach` of the shin's
    /// length, cloth left out) are moved by the change the capture's own
    /// frames show, against the skinned rest frame, between the retrieved
    /// frame's knee angle and the target's (pose-space deformation learnt
    /// from the database). 0 turns it off. Default 0 (off; measured in the
    /// README, issue 42).
    pub bend_examples: f64,
}

/// The rotations the fold repair ([`super::unflip`], [`super::untangle`])
/// turns the retrieved frame's triangles by before asking whether the
/// deformed ones face the other way.
///
/// The surface measure ([`crate::tools::eval::triangles`]) asks the same
/// question with each neighbourhood's own rotation; the skin's blend of
/// the bones' turns differs from it where a vertex's bones turn apart (the
/// skirt between the thighs, a limb twisted about itself), so a repair
/// that reads only the skin's turns leaves folds the measure counts, and a
/// better solve before it (`parent_seams`) did not show after it. Measured
/// (session 25, `retarget` then `eval --surface` onto the real samba
/// capture; session-24 default → `parent_seams` with this default):
/// triangle-frames turned over against the rest frame after the repair,
/// CMU 02_02 465 → 55, 131_02 1,067 → 118 (README, issue 42).
///
/// Which reading a person sees was settled by looking (session 26, README
/// issue 42): the triangles only the skin's blend flags face with their
/// surroundings on screen; those the surface's own turns flag are the
/// visible folds. The deformation's tests count with
/// [`super::near_turns::turned_over_near`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RepairTurns {
    /// The skeleton's rotations blended by skin weight (the default up to
    /// session 26): blind to folds where a vertex's bones turn apart.
    Skin,
    /// The default (session 27): the skin's, then repairs of what is left
    /// turned over against the surface's own rotations
    /// ([`super::near_turns`]: each neighbourhood's best rigid alignment
    /// from the retrieved frame onto the repaired one, read again after
    /// each repair, at most [`DeformOptions::surface_rounds`] repairs), the
    /// test the surface measure makes against the rest frame.
    #[default]
    SkinThenSurface,
    /// The surface's own rotations only.
    Surface,
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
            hold_soft: true,
            sibling_seams: false,
            seam_by_weight: false,
            hold_by_weight: false,
            hold_spread: false,
            local_steps: 0,
            step_zone: super::step_zone::StepZone::Everywhere,
            step_reach: 0.2,
            repair_budget: RepairBudget::default(),
            overlap_weight: 0.0,
            overlap_passes: 1,
            blend_taper: false,
            parent_seams: true,
            repair_turns: RepairTurns::default(),
            surface_rounds: 6,
            surface_stall: usize::MAX,
            parallel_regions: true,
            cloth_stitch: 0.5,
            cloth_steps: 2,
            cloth_turns: true,
            cloth_fallback: true,
            cloth_rings: 0,
            stitch_joints: super::cloth_reach::StitchJoints::None,
            stitch_apart: 0,
            constraint_skin: super::dqs::ConstraintSkin::Linear,
            bend_examples: 0.0,
        }
    }
}

/// The environment variable that overrides the fold repair's options for
/// measurement ([`with_repair_overrides`]), as [`super::cloth::CLOTH_ENV`]
/// does the cloth's: e.g. `SURFMOTION_REPAIR=rings=16,passes=2`.
pub const REPAIR_ENV: &str = "SURFMOTION_REPAIR";

/// `opts` with [`REPAIR_ENV`]'s overrides (a warning, and none taken, when
/// it cannot be read).
pub fn with_repair_env(opts: &DeformOptions) -> DeformOptions {
    with_env_overrides(opts, REPAIR_ENV, "repair", with_repair_overrides)
}

/// `opts` with the overrides the environment variable `var` holds, read
/// by `parse` (a warning naming the `what` options, and none taken, when
/// they cannot be read; `opts` when `var` is not set).
pub(crate) fn with_env_overrides(
    opts: &DeformOptions,
    var: &str,
    what: &str,
    parse: fn(&DeformOptions, &str) -> Result<DeformOptions, String>,
) -> DeformOptions {
    match std::env::var(var) {
        Ok(text) => parse(opts, &text).unwrap_or_else(|why| {
            tracing::warn!("{var}: {why}; the default {what} options are used");
            *opts
        }),
        Err(_) => *opts,
    }
}

/// `opts` with the comma-separated `name=value` pairs of `text`: `rings`
/// (most rings of a patch, [`unflip::RepairOptions::most_rings`]; `all`
/// for no bound), `rounds` ([`unflip::RepairOptions::rounds`]), `passes`
/// ([`DeformOptions::repair_passes`]), `surface`
/// ([`DeformOptions::surface_rounds`]), `stall`
/// ([`DeformOptions::surface_stall`]) and `replay` (0 or 1,
/// [`unflip::RepairOptions::replay`]). An error names the pair it could
/// not read and every name accepted.
pub fn with_repair_overrides(opts: &DeformOptions, text: &str) -> Result<DeformOptions, String> {
    const NAMES: &str = "rings=N|all, rounds=N, passes=N, surface=N, stall=N, replay=0|1";
    let mut o = *opts;
    for p in super::overrides::pairs(text, NAMES) {
        let p = p?;
        match p.name {
            "rings" if p.value == "all" => o.repair.most_rings = usize::MAX,
            "rings" => o.repair.most_rings = p.count()?.max(1),
            "rounds" => o.repair.rounds = p.count()?,
            "passes" => o.repair_passes = p.count()?,
            "surface" => o.surface_rounds = p.count()?,
            "stall" => o.surface_stall = p.count()?.max(1),
            "replay" => o.repair.replay = p.count()? != 0,
            _ => return p.unknown(),
        }
    }
    Ok(o)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every name the repair's overrides accept sets its option and
    /// nothing else; an unknown name, a pair without `=` or a value that is
    /// not a count is refused with the pair quoted and the names listed.
    #[test]
    fn repair_overrides_set_what_they_name() {
        let d = DeformOptions::default();
        assert_eq!(with_repair_overrides(&d, "").unwrap(), d);
        let o = with_repair_overrides(
            &d,
            " rings=8, rounds=2 ,passes=4,surface=1, stall=2, replay=0",
        )
        .unwrap();
        assert_eq!(o.repair.most_rings, 8);
        assert_eq!(o.repair.rounds, 2);
        assert_eq!(o.repair_passes, 4);
        assert_eq!(o.surface_rounds, 1);
        assert_eq!(o.surface_stall, 2);
        assert!(!o.repair.replay && d.repair.replay);
        let back = DeformOptions {
            repair: d.repair,
            repair_passes: d.repair_passes,
            surface_rounds: d.surface_rounds,
            surface_stall: d.surface_stall,
            ..o
        };
        assert_eq!(back, d, "an override set another option");
        assert_eq!(
            with_repair_overrides(&d, "rings=all,stall=0")
                .unwrap()
                .repair
                .most_rings,
            usize::MAX
        );
        assert_eq!(
            with_repair_overrides(&d, "stall=0").unwrap().surface_stall,
            1
        );
        for bad in ["rings", "rounds=x", "stall=-1", "speed=2", "replay=yes"] {
            let e = with_repair_overrides(&d, bad).unwrap_err();
            assert!(
                e.contains(&format!("'{bad}'")) && e.contains("replay=0|1"),
                "{bad}: {e}"
            );
        }
    }
}
