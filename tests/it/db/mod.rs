//! Character databases: the real captures' manifests, synthetic databases.

mod caches;
mod captures;
mod frames;
mod sparse;
mod synth;
