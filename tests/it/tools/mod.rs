//! Tools: the plausibility evaluation.

mod plausibility;
