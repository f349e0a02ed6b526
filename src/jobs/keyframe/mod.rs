//! `jobs::keyframe`: key-frame animation through the Surface Motion Graph
//! (Huang et al. 2015, Sec. 5.1) as one job: key-frames resolved
//! ([`resolve_keys`]), one query written to a mesh output ([`write_path`]),
//! the Table III grid ([`grid`]), the least mean smoothness per target
//! ([`least_mean`]) and the smoothness floor ([`floor`]); the report and
//! heat-map files ([`files`]); a path's text summary
//! ([`summary::path_summary`]). The options
//! ([`KeyframeJobOptions`]) carry the defaults of `surfmotion keyframe`.

pub mod error;
pub mod files;
pub mod floor;
pub mod grid;
pub mod keys;
pub mod options;
pub mod path;
pub mod summary;
pub mod text;
pub mod verdict;

pub use error::KeyframeJobError;
pub use files::{write_grid_files, write_path_report, write_report};
pub use floor::{FloorReport, FloorStage, PathFloors, floor};
pub use grid::{GridTargets, LeastMean, grid, grid_planner, least_mean, least_mean_planner};
pub use keys::{Keys, resolve_keys};
pub use options::{DEFAULT_DISTANCES, DEFAULT_TIMES, KeyframeJobOptions};
pub use path::{PathReport, PathRun, write_path, write_path_with};
pub use verdict::{HEADING_TOLERANCE_DEG, Missed, missed_targets, segment_missed};
