//! Command-line interface: one file per subcommand; `app.rs` holds the
//! command enum and its dispatch, the helpers are in small files; this file
//! only declares them and re-exports the helpers the subcommands share.

mod app;
mod argv;
mod batch;
mod blend;
mod db;
mod db_init;
#[cfg(test)]
mod defaults;
mod demo;
mod eval;
mod flags;
mod given;
mod graph;
mod inspect;
mod keyframe;
mod live;
mod live_run;
mod live_send;
mod log;
mod malloc;
mod mesh;
mod mirror;
mod mocap;
mod opts;
mod out;
mod parse;
mod pick;
mod play;
mod render;
mod repair;
mod retarget;
mod rig;
mod signals;
mod synth;
mod transfer;
mod transfer_run;
mod values;
mod web;

pub use argv::Usage;
pub use log::warnings_in_summary;
pub use opts::{ClipOpts, RunOpts, load_mesh_groups};
pub use out::{
    Bars, OutputClosed, emit, emit_json, one_line, progress, report, report_sorted, report_with,
    spinner, write_json,
};
pub use parse::{
    bounded_count, confidence, dynamics_amount, fraction, frame_rate, heading, horizon,
    length_unit, max_error_mm, mesh_spec, non_negative, png_path, positive, session_seconds,
    t_skel, targets, weight,
};

pub use app::main;
