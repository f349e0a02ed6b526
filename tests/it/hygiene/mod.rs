//! The project itself: README, data gate, layering, library hygiene, warnings.

mod data_gate;
mod layering;
mod library;
mod readme;
mod warnings;
