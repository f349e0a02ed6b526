//! The smoothness floor of a database and of the paths between
//! consecutive key-frames (`keyframe::floor`, Sec. 6.1's measure).

use super::grid::GridTargets;
use crate::db::Character;
use crate::keyframe::floor::{
    FloorOptions, PathFloor, TransitionFloor, path_floor, transition_floor_with,
};
use crate::keyframe::graph::KeyGraph;
use crate::keyframe::smoothness::FrameSet;
use crate::keyframe::{KeyframeOptions, TransitionCost, key_graph, key_name};
use serde::Serialize;

/// The stage [`floor`] is at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FloorStage {
    /// Measuring the frames' surfaces.
    Surfaces,
    /// The transition floor: frame pairs done of total.
    Pairs(u64, u64),
    /// Pricing the graph by smoothness; the path floors.
    Paths,
}

/// The path floors between two consecutive key-frames.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PathFloors {
    /// Start key-frame (`SEQUENCE:FRAME`).
    pub from: String,
    /// End key-frame.
    pub to: String,
    /// Most transitions of a path considered.
    pub max_transitions: usize,
    /// Over the graph's transitions priced by smoothness.
    pub graph: PathFloor,
    /// Over every frame pair of the database (priced by the transition
    /// floor's bounds).
    pub every_frame_pair: PathFloor,
}

/// [`floor`]'s report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FloorReport {
    /// The database's transition floor.
    pub transitions: TransitionFloor,
    /// Per pair of consecutive key-frames.
    pub paths: Vec<PathFloors>,
    /// The windows and gap measured (those of the graph's transitions).
    #[serde(skip)]
    pub options: FloorOptions,
}

/// The transition floor of the database (every frame pair and window,
/// [`transition_floor_with`]) and the path floor between consecutive
/// key-frames, for paths of at most as many transitions as the longest of
/// `targets`' times can hold (one per 4 frames, the search's spacing; at
/// most 250). `progress` is told each stage.
pub fn floor(
    ch: &Character,
    keys: &[crate::graph::FlatFrame],
    opts: &KeyframeOptions,
    targets: &GridTargets,
    progress: &mut dyn FnMut(FloorStage),
) -> FloorReport {
    let fps = ch.manifest().fps;
    let longest = targets.times.iter().copied().fold(0.0, f64::max);
    let k_max = ((longest * fps / 4.0).ceil() as usize).clamp(1, 250);
    progress(FloorStage::Surfaces);
    let frames = FrameSet::new(ch);
    let options = FloorOptions::of_graph(ch.graph().options());
    progress(FloorStage::Pairs(0, 0));
    let transitions = transition_floor_with(ch, &frames, &options, &mut |done, total| {
        progress(FloorStage::Pairs(done, total))
    });
    progress(FloorStage::Paths);
    let priced = KeyframeOptions {
        transition_cost: TransitionCost::Smoothness,
        ..*opts
    };
    let graph = key_graph(ch, &priced);
    let all = KeyGraph::of_character_with(ch, Some(&transitions.bounds));
    let paths = keys
        .windows(2)
        .map(|w| PathFloors {
            from: key_name(ch, w[0]),
            to: key_name(ch, w[1]),
            max_transitions: k_max,
            graph: path_floor(&graph, w[0], w[1], k_max),
            every_frame_pair: path_floor(&all, w[0], w[1], k_max),
        })
        .collect();
    FloorReport {
        transitions,
        paths,
        options,
    }
}
