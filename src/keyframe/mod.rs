//! Key-frame animation (Huang et al. 2015, Secs. 5.1 and 6.1): the path
//! through the Surface Motion Graph that passes the animator's key-frames
//! in order and best meets a travel distance and time.
//!
//! Pipeline: [`graph`] (the frame graph with each frame's floor step),
//! [`segment`] (the compressed graph between two key-frames, its walks and
//! loops), [`search`] (walks, loops and pruning, Eqs. 13-22) with
//! [`repeats`] (the loop repetition counts, Eqs. 20-25), [`place`]
//! (blending across transitions and placement along the accumulated root
//! motion), [`smoothness`] (Table III's transition smoothness), [`floor`]
//! (its lower bounds over a database), [`select`] (the key-frame
//! transitions re-chosen by that measured distortion) and [`grid`] (the
//! Table III evaluation over a grid of targets); [`lattice`] is the
//! exact-length search (the default) and [`pose`] resolves key-frames
//! given as skeleton poses to database frames. The searches' options are
//! in [`options`], the heading target in [`heading`], their errors in
//! [`error`]. Files import only files before them in this order: graph,
//! smoothness, select, floor, clock, heading, repeats, options, error,
//! segment, lattice, search, problem, planner, pose, report, place,
//! output, grid, smoothest, heatmap (no file-level circle, issue 40).
//!
//! The cost of a path `P` (Eq. 7) is
//! `C_tran(P) + w_dist |dist(P) − d_V| + w_time |time(P) − t_V|`, with
//! `C_tran` the sum of its transitions' costs (Eq. 8), `dist` the floor
//! distance travelled by the mesh centroid (Eq. 10) and `time = N_f Δt`
//! (Eq. 12). Zero targets ask for the shortest path.

pub mod clock;
pub mod error;
pub mod floor;
pub mod graph;
pub mod grid;
pub mod heading;
pub mod heatmap;
pub mod lattice;
pub mod options;
pub mod output;
pub mod place;
pub mod planner;
pub mod pose;
pub mod problem;
pub mod repeats;
pub mod report;
pub mod search;
pub mod segment;
pub mod select;
pub mod smoothest;
pub mod smoothness;

pub use output::{Output, Planned, Streamed, facing_change, plan_path, prepare, synthesise};
pub use planner::{CostTerms, LoopReport, Plan, Planner, SegmentReport, TargetReach, join, runs};
pub use problem::{
    KeyframeError, KeyframeOptions, MAX_TARGET_METRES, MAX_TARGET_SECONDS, Targets, TransitionCost,
    TransitionSet, key_graph, key_graph_with, key_name, parse_key, price_by_smoothness,
};
pub use report::{
    Report, TransitionReport, describe, mean_smoothness, mean_smoothness_vertex, segment_reports,
    transitions,
};
