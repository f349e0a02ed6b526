//! The integration tests: one binary, one module per pipeline stage in the
//! order data flows (docs/architecture.md), then the CLI, hostile input,
//! regressions and the project's own hygiene. `tests/README.md` maps every
//! module: what it checks and which data it reads. Run one group with
//! `CI=true cargo test --release --test it mocap::`.
//!
//! Add tests to the module of their stage (a new file is a new `mod` line
//! here, not a new binary); helpers go in `common`.

mod common;

// The stages, in the order data flows (blank lines keep rustfmt from
// sorting them).
mod mocap; // clip readers

mod rig; // canonical mapping

mod pose; // the pose kernel

mod embed; // rig embedding on a mesh

mod mesh; // kernels, mesh I/O

mod graph; // similarity, graph

mod db; // databases

mod deform; // deformation

mod parametric; // parametric motion

mod drive; // surface synthesis

mod live; // live retargeting from a stream

mod keyframe; // key-frame animation

mod transfer; // scan transfer

mod web; // web viewer

mod jobs; // jobs, batch, streamed output

mod tools; // eval

// Across the stages.
mod cli; // the binary as a user runs it

mod hostile; // malformed and hostile input

mod regression; // issue acceptance tests, pinned bugs

mod hygiene; // README, data gate, layering, library hygiene
