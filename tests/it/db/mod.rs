//! Character databases: the real captures' manifests, synthetic databases.

mod captures;
mod frames;
mod sparse;
mod synth;
