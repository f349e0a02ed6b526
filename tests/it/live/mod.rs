//! Live retargeting from a mocap stream (issue 45): the fixed-lag trellis
//! and the per-frame session against the offline synthesis.

mod actors;
mod carried;
mod decompose;
mod long;
mod offline;
mod online;
mod overlap;
mod page;
mod protocols;
mod stages;
mod stream_rules;
