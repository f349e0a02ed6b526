//! Utilities shared by every stage: job limits ([`budget`]), CPU clocks
//! ([`cpu`]), atomic writes and bounded reads ([`fsutil`]), and short
//! numbers in messages ([`numfmt`]).

pub mod budget;
pub mod cpu;
pub mod fsutil;
pub mod numfmt;
