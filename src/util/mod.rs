//! Utilities shared by every stage: job limits ([`budget`]), CPU clocks
//! ([`cpu`]), errors on one line ([`errtext`]), atomic writes and bounded reads ([`fsutil`]), short numbers
//! in messages ([`numfmt`]) and a run's stages timed ([`stages`]).

pub mod budget;
pub mod cpu;
pub mod errtext;
pub mod fsutil;
pub mod numfmt;
pub mod stages;
