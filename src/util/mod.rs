//! Utilities shared by every stage: job limits ([`budget`]), atomic writes
//! and bounded reads ([`fsutil`]), and short numbers in messages
//! ([`numfmt`]).

pub mod budget;
pub mod fsutil;
pub mod numfmt;
