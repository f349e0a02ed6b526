//! Tools: the plausibility evaluation.

mod plausibility;
mod surface;
