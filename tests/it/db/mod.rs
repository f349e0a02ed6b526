//! Character databases: the real captures' manifests, synthetic databases.

mod cache_inspect;
mod cache_trust;
mod caches;
mod captures;
mod examples;
mod frames;
mod histogram_reference;
mod sparse;
mod synth;
