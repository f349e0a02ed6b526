//! Character databases: the real captures' manifests, synthetic databases.

mod captures;
mod sparse;
mod synth;
