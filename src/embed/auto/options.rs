//! The automatic rig's settings and refusals.

use super::decompose::DecomposeOptions;

/// Settings of [`super::rig::auto_rig`]. The defaults are `db init`'s.
#[derive(Debug, Clone, Copy)]
pub struct AutoOptions {
    /// The frame of the capture the parts are found in (its positions are
    /// the decomposition's rest); the landmarks are written on the
    /// topology mesh whatever the frame. Default `None`: the topology mesh
    /// itself (the capture's frame 0). `db init` passes the frame
    /// `embed::rest::choose_rest_frame` chooses (the clearest of contact).
    pub rest_frame: Option<usize>,
    /// Frames of the capture used. Default 40.
    pub max_frames: usize,
    /// Which frames the decomposition fits ([`FrameSample`]). Default
    /// [`FrameSample::InOrder`]. With [`FrameSample::PoseQuantiles`] and
    /// the rest frame by [`crate::embed::rest::PoseRule::Standing`]
    /// (session 26) crane's right knee was 4.4 % of the height from the
    /// landmark rig's: that rest frame is a step of crane's walk (frame
    /// 86, the knee bent). With [`crate::embed::rest::PoseRule::Held`]
    /// (crane's A-pose, frame 5) and [`AutoOptions::thigh_hip`] (session
    /// 27's build with them as the default) crane's knees were 0.1 and
    /// 2.2 %, but samba's rest frame moved from its frame 2 to 4 (both of
    /// the still start) and its left elbow to 4.2 % (bound 3 %, r_knee
    /// 2.7 %, joints 1.94 %): not the default.
    pub frames: FrameSample,
    /// A leg's hip where its thigh's rigid part ends (the first crossing
    /// after the knee that bends, near the hip's usual distance from the
    /// toe), as the knee is found; else where the leg's path enters the
    /// trunk. Default false (sessions 20-26's; `hip=thigh` in
    /// [`AUTORIG_ENV`]).
    pub thigh_hip: bool,
    /// How the body's left-right axis, and so its facing, is found on the
    /// rest frame ([`Facing`]). Default [`Facing::Trunk`] (session 28;
    /// `facing=hips` in [`AUTORIG_ENV`] gives sessions 20-27's).
    pub facing: Facing,
    /// A leg's knee matched at a boundary that is no joint checked by
    /// splitting the parts beside it by their motion
    /// ([`super::straddle::split_knee`], session 33; `knee=split` in
    /// [`AUTORIG_ENV`]). Default false (`knee=crossing`, sessions
    /// 20-32's): measured on samba's `merge=settle` draws it moved no knee
    /// (`autorig_eval … spread 10 renumbered`: salt 1's left leg, the
    /// shin cut at mid-shin, splits into halves that bend 11.5° and 13.9°
    /// but neither half next to the cut moves with the part across it:
    /// 29.3° and 23.9°, each against the other part's whole motion).
    pub split_knee: bool,
    /// A joint's fixed point farther than [`super::straddle::LOOSE`] of the
    /// height from its own limb's path moved to the centre of its two
    /// parts' boundary ([`super::straddle::guard_pivot`], session 33).
    /// Default true (`pivot=guarded`; `pivot=free` in [`AUTORIG_ENV`]
    /// gives sessions 20-32's).
    pub guard_pivots: bool,
    /// The body's top read for a head ([`super::neck`], session 36): a
    /// body cut at the neck is rigged without one (no chin, no head top,
    /// `"absent": ["head"]`). Default true (`head=read`; `head=keep` in
    /// [`AUTORIG_ENV`] rigs a head on any top, sessions 20-35's).
    pub read_head: bool,
    /// The head's chain from the non-foot tip nearest the body's axis when
    /// the highest is farther from it than `neck::TOP_AXIS` of the height
    /// ([`super::limbs::Chains::head_nearest_axis`]). Default `true`
    /// (`head=axis`, session 39); `head=highest` in [`AUTORIG_ENV`] takes
    /// the highest tip (sessions 20-38's): the SMPL template cut at the
    /// neck joint has its hands 0.05 mm above the stump, and its left hand
    /// was rigged as the head and the left arm from the stump
    /// (`autorig_eval … confusion SMPL`, three motions: parts 70.3 / 68.0
    /// / 76.4 % → 95.4 / 95.6 / 97.4 %, left wrist 34.3 / 33.9 / 36.8 % of
    /// the height off → 3.1 / 3.1 / under 2 %).
    pub head_axis: bool,
    /// Where the extremities are sought from ([`super::centre`], session
    /// 36): default `tips=guarded` (the centroid's vertex unless it lies
    /// on a limb's end or hides a sixth limb, [`super::guard`], session
    /// 37); `tips=centroid` (sessions 20-36's) or `tips=centre` in
    /// [`AUTORIG_ENV`].
    pub tip_seed: super::centre::TipSeed,
    /// The decomposition's settings.
    pub decompose: DecomposeOptions,
}

impl Default for AutoOptions {
    fn default() -> Self {
        AutoOptions {
            rest_frame: None,
            max_frames: 40,
            frames: FrameSample::InOrder,
            thigh_hip: false,
            facing: Facing::Trunk,
            split_knee: false,
            guard_pivots: true,
            read_head: true,
            head_axis: true,
            tip_seed: super::centre::TipSeed::Guarded,
            decompose: DecomposeOptions::default(),
        }
    }
}

/// Where the automatic rig reads the body's left-right axis on the rest
/// frame ([`AutoOptions::facing`]); the facing is square to it, on the
/// side the toes point to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Facing {
    /// The widest horizontal axis of the chest and shoulders
    /// ([`super::facing::widest_across`]); the hips' line when the band is
    /// about as deep as it is wide.
    Trunk,
    /// The line through the hips found on the legs' paths (else the
    /// knees): sessions 20-27's. A hip found at a skirt band put samba's
    /// facing 31° off, (0.86, 0, −0.51).
    Hips,
}

impl Facing {
    /// The rule named `name` (`trunk`, `hips`).
    pub fn parse(name: &str) -> Option<Facing> {
        match name {
            "trunk" => Some(Facing::Trunk),
            "hips" => Some(Facing::Hips),
            _ => None,
        }
    }
}

/// Which frames of the capture the skinning decomposition fits
/// ([`AutoOptions::frames`]), up to [`AutoOptions::max_frames`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameSample {
    /// Spread evenly in the order given, after the topology's positions
    /// as the fit's first frame (sessions 20-25's default): the same
    /// capture started on another frame is fitted on other frames.
    InOrder,
    /// Farthest-point first from the rest frame's pose
    /// (`embed::pose_order::farthest_first`), the topology not in the fit
    /// (session 25's option): the extremes of the motion. As `db init`'s
    /// default it failed `embed::auto_arms` (samba l_elbow 3.84 % of the
    /// height from the landmark rig) and `embed::auto_knees` (4.20 %).
    Farthest,
    /// The frames ordered by their pose's distance from the rest frame's
    /// (`embed::pose_order::by_distance`, ties by pose), taken at evenly
    /// spaced ranks, the rest frame itself the first: the motion's poses
    /// in proportion to how often the capture holds them (as the even
    /// spread in time gave them), near and far, in any order of the
    /// frames.
    PoseQuantiles,
    /// Farthest-point first ([`crate::embed::pose_order::farthest_first`])
    /// from the per-coordinate median of all frames' poses
    /// ([`crate::embed::pose_order::median`]), the poses read on vertices
    /// chosen by their motion ([`crate::embed::pose_order::descriptor_vertices`]):
    /// the frames that spread the motion's poses widest, the same whichever
    /// frame is the rest, in any order of the frames and of the vertices
    /// (session 29).
    Spread,
    /// Evenly spaced ranks of the distance from the median pose
    /// ([`crate::embed::pose_order::quantiles`] seeded by
    /// [`crate::embed::pose_order::median`], on
    /// [`crate::embed::pose_order::descriptor_vertices`]): the poses in
    /// proportion to how long the capture holds them, independent of the
    /// rest frame and of both orders (session 29).
    MedianQuantiles,
}

impl FrameSample {
    /// The sample named `name` (`in-order`, `farthest`, `quantiles`,
    /// `spread`, `median-quantiles`).
    pub fn parse(name: &str) -> Option<FrameSample> {
        match name {
            "in-order" => Some(FrameSample::InOrder),
            "farthest" => Some(FrameSample::Farthest),
            "quantiles" => Some(FrameSample::PoseQuantiles),
            "spread" => Some(FrameSample::Spread),
            "median-quantiles" => Some(FrameSample::MedianQuantiles),
            _ => None,
        }
    }
}

/// The environment variable that overrides `db init`'s automatic rig for
/// measurements (as `SURFMOTION_SPARSE` does `db build`'s graph):
/// comma-separated `rest=first|held|standing|standing-near|median`,
/// `frames=in-order|farthest|quantiles|spread|median-quantiles`,
/// `hip=thigh|trunk`, `facing=trunk|hips`,
/// `seed=draws-N|consensus-N|vote-N|position|motion|index` (the
/// decomposition's [`super::decompose::Seeding`]), `salt=N` (its
/// [`super::decompose::DecomposeOptions::salt`]), `merge=greedy|settle|settle-split`
/// (what follows its merges, [`super::decompose::MergeRule`]),
/// `knee=split|crossing` ([`AutoOptions::split_knee`]),
/// `pivot=guarded|free` ([`AutoOptions::guard_pivots`]),
/// `head=read|keep|axis|highest` ([`AutoOptions::read_head`], [`AutoOptions::head_axis`]),
/// `neck=P` (a headless body's neck joint P % of the height below its
/// stump's top, 0-10; default 5; read by the embedding:
/// `crate::embed::stump`), `rim=P` (how far across from the body's axis
/// an open cut's rim may reach, P % of the height, 0-100; default 25; 0
/// reads no rim, session 40's top ring alone; read by the embedding),
/// `tips=centroid|centre|guarded` ([`AutoOptions::tip_seed`]),
/// `patches=position|vertex0` (the rest frame's contact patches,
/// [`crate::embed::contact::ContactOptions::seed_by_position`]), `max=N`.
pub const AUTORIG_ENV: &str = "SURFMOTION_AUTORIG";

/// `db init`'s automatic rig: the rest frame's rule (main's,
/// [`crate::embed::rest::RestOptions::default`]: a clear topology kept,
/// else the first clear frame) and `auto`, with the measurement override
/// [`AUTORIG_ENV`] applied when set (`rest=held,frames=quantiles,hip=thigh`:
/// the rules by pose, [`crate::embed::rest::PoseRule::Held`],
/// [`FrameSample::PoseQuantiles`] and [`AutoOptions::thigh_hip`], not the
/// default: see [`AutoOptions::frames`]). `Err` names the pair that is not
/// an option.
pub fn automatic_setup(
    auto: &AutoOptions,
) -> Result<(crate::embed::rest::RestOptions, AutoOptions), String> {
    let mut rule = crate::embed::rest::RestOptions::default();
    let mut auto = *auto;
    if let Ok(text) = std::env::var(AUTORIG_ENV) {
        apply_override(&text, &mut rule, &mut auto)?;
    }
    Ok((rule, auto))
}

/// [`automatic_setup`]'s override `text` applied to `rule` and `auto`.
pub(crate) fn apply_override(
    text: &str,
    rule: &mut crate::embed::rest::RestOptions,
    auto: &mut AutoOptions,
) -> Result<(), String> {
    use crate::embed::rest::PoseRule;
    for pair in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let bad = || {
            format!(
                "{AUTORIG_ENV}: '{pair}' is not an option (rest=first|held|standing|standing-near|median, frames=in-order|farthest|quantiles|spread|median-quantiles, hip=thigh|trunk, facing=trunk|hips, seed=draws-N|consensus-N|vote-N|position|motion|index, salt=N, merge=greedy|settle|settle-split, knee=split|crossing, pivot=guarded|free, head=read|keep|axis|highest, neck=P, rim=P, tips=centroid|centre|guarded, patches=position|vertex0, max=N)"
            )
        };
        let (k, v) = pair.split_once('=').ok_or_else(bad)?;
        match k {
            "rest" if v == "first" => rule.by_pose = false,
            "rest" => {
                rule.by_pose = true;
                rule.pose_rule = PoseRule::parse(v).ok_or_else(bad)?;
            }
            "frames" => auto.frames = FrameSample::parse(v).ok_or_else(bad)?,
            "hip" if v == "thigh" => auto.thigh_hip = true,
            "hip" if v == "trunk" => auto.thigh_hip = false,
            "facing" => auto.facing = Facing::parse(v).ok_or_else(bad)?,
            "seed" => {
                auto.decompose.seeding = super::decompose::Seeding::parse(v).ok_or_else(bad)?
            }
            "salt" => auto.decompose.salt = v.parse::<u32>().map_err(|_| bad())?,
            "merge" => {
                auto.decompose.merge = super::decompose::MergeRule::parse(v).ok_or_else(bad)?
            }
            "knee" if v == "split" => auto.split_knee = true,
            "knee" if v == "crossing" => auto.split_knee = false,
            "pivot" if v == "guarded" => auto.guard_pivots = true,
            "pivot" if v == "free" => auto.guard_pivots = false,
            "head" if v == "read" => auto.read_head = true,
            "head" if v == "keep" => auto.read_head = false,
            "head" if v == "axis" => {
                auto.read_head = true;
                auto.head_axis = true;
            }
            "head" if v == "highest" => {
                auto.read_head = true;
                auto.head_axis = false;
            }
            // Read by the embedding (`embed::stump::neck_below_top`).
            "neck" => {
                v.parse::<f64>()
                    .ok()
                    .filter(|p| (0.0..=10.0).contains(p))
                    .ok_or_else(bad)?;
            }
            // Read by the embedding (`embed::stump::rim_reach`).
            "rim" => {
                v.parse::<f64>()
                    .ok()
                    .filter(|p| (0.0..=100.0).contains(p))
                    .ok_or_else(bad)?;
            }
            "tips" => auto.tip_seed = super::centre::TipSeed::parse(v).ok_or_else(bad)?,
            "patches" if v == "position" => rule.contact.seed_by_position = true,
            "patches" if v == "vertex0" => rule.contact.seed_by_position = false,
            "max" => {
                auto.max_frames = v
                    .parse::<usize>()
                    .ok()
                    .filter(|&m| m >= 2)
                    .ok_or_else(bad)?
            }
            _ => return Err(bad()),
        }
    }
    Ok(())
}

/// Why a capture cannot be rigged automatically; each a one-line reason.
#[derive(Debug, thiserror::Error)]
pub enum AutoError {
    /// Fewer than two frames.
    #[error(
        "automatic rigging: the capture has {0} frame(s); the rig is learnt from how the body moves: give a sequence of several frames, or landmarks"
    )]
    TooFewFrames(usize),
    /// A frame with another vertex count than the mesh.
    #[error(
        "automatic rigging: frame {frame} has {have} vertices, the mesh {want}: every frame must be the mesh's vertices in its order"
    )]
    VertexCount {
        /// The frame.
        frame: usize,
        /// Its vertex count.
        have: usize,
        /// The mesh's.
        want: usize,
    },
    /// The rest frame asked for is not in the capture.
    #[error("automatic rigging: rest frame {frame} is past the capture's {frames} frames")]
    RestFrame {
        /// Asked.
        frame: usize,
        /// Frames.
        frames: usize,
    },
    /// The capture is not a standing humanoid; the reason says what was
    /// found.
    #[error("automatic rigging: not a humanoid: {0}; give landmarks")]
    NotHumanoid(String),
    /// The mesh without its vertices in no triangle is no mesh.
    #[error("automatic rigging: the mesh without its vertices in no triangle: {0}")]
    WithoutStray(crate::mesh::TopologyError),
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::embed::rest::{PoseRule, RestOptions};

    #[test]
    fn the_override_sets_what_it_names_and_refuses_the_rest() {
        let (mut rule, mut auto) = (RestOptions::automatic(), AutoOptions::default());
        apply_override("rest=median, frames=in-order,max=60", &mut rule, &mut auto).unwrap();
        assert!(rule.by_pose);
        assert_eq!(rule.pose_rule, PoseRule::NearestMedian);
        assert_eq!(auto.frames, FrameSample::InOrder);
        assert_eq!(auto.max_frames, 60);
        apply_override("rest=first", &mut rule, &mut auto).unwrap();
        assert!(!rule.by_pose);
        assert!(!auto.thigh_hip);
        apply_override("rest=held,hip=thigh", &mut rule, &mut auto).unwrap();
        assert!(rule.by_pose && auto.thigh_hip);
        assert_eq!(rule.pose_rule, PoseRule::Held);
        apply_override("hip=trunk", &mut rule, &mut auto).unwrap();
        assert!(!auto.thigh_hip);
        assert_eq!(auto.facing, Facing::Trunk);
        apply_override("facing=hips", &mut rule, &mut auto).unwrap();
        assert_eq!(auto.facing, Facing::Hips);
        use super::super::decompose::{DecomposeOptions, Seeding};
        assert_eq!(auto.decompose.seeding, DecomposeOptions::default().seeding);
        apply_override("seed=draws-3", &mut rule, &mut auto).unwrap();
        assert_eq!(auto.decompose.seeding, Seeding::Draws(3));
        apply_override("seed=index,frames=spread", &mut rule, &mut auto).unwrap();
        assert_eq!(auto.decompose.seeding, Seeding::Index);
        assert_eq!(auto.frames, FrameSample::Spread);
        apply_override("seed=consensus-5,salt=3", &mut rule, &mut auto).unwrap();
        assert_eq!(auto.decompose.seeding, Seeding::Consensus(5));
        assert_eq!(auto.decompose.salt, 3);
        apply_override("seed=vote-7,patches=position", &mut rule, &mut auto).unwrap();
        assert!(rule.contact.seed_by_position);
        assert_eq!(auto.decompose.seeding, Seeding::Vote(7));
        use super::super::decompose::MergeRule;
        assert_eq!(auto.decompose.merge, MergeRule::Greedy);
        apply_override("merge=settle", &mut rule, &mut auto).unwrap();
        assert_eq!(auto.decompose.merge, MergeRule::Settle);
        apply_override("merge=settle-split", &mut rule, &mut auto).unwrap();
        assert_eq!(auto.decompose.merge, MergeRule::SettleSplit);
        apply_override("merge=greedy", &mut rule, &mut auto).unwrap();
        assert_eq!(auto.decompose.merge, MergeRule::Greedy);
        apply_override("frames=median-quantiles", &mut rule, &mut auto).unwrap();
        assert_eq!(auto.frames, FrameSample::MedianQuantiles);
        assert!(auto.read_head && auto.head_axis);
        apply_override("head=highest", &mut rule, &mut auto).unwrap();
        assert!(auto.read_head && !auto.head_axis);
        apply_override("head=axis,neck=5", &mut rule, &mut auto).unwrap();
        apply_override("rim=0,rim=30", &mut rule, &mut auto).unwrap();
        assert!(auto.read_head && auto.head_axis);
        apply_override("head=keep", &mut rule, &mut auto).unwrap();
        assert!(!auto.read_head);
        apply_override("head=read", &mut rule, &mut auto).unwrap();
        assert!(auto.read_head);
        use super::super::centre::TipSeed;
        assert_eq!(auto.tip_seed, TipSeed::Guarded);
        apply_override("tips=centre", &mut rule, &mut auto).unwrap();
        assert_eq!(auto.tip_seed, TipSeed::Centre);
        apply_override("tips=centroid", &mut rule, &mut auto).unwrap();
        assert_eq!(auto.tip_seed, TipSeed::Centroid);
        apply_override("tips=guarded", &mut rule, &mut auto).unwrap();
        assert_eq!(auto.tip_seed, TipSeed::Guarded);
        for bad in [
            "head=cut",
            "neck=11",
            "neck=x",
            "rim=101",
            "rim=x",
            "tips=middle",
            "seed=random",
            "seed=draws-0",
            "seed=consensus-0",
            "seed=vote-x",
            "salt=-1",
            "merge=lazy",
            "patches=first",
            "rest=middle",
            "frames",
            "max=1",
            "sample=x",
            "hip=knee",
            "facing=toes",
        ] {
            let e = apply_override(bad, &mut rule, &mut auto).unwrap_err();
            assert!(e.contains(bad) && e.contains(AUTORIG_ENV), "{e}");
        }
    }
}
