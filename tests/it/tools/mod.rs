//! Tools: the plausibility evaluation.

mod plausibility;
mod surface;
mod surface_bend;
mod surface_crumple;
mod surface_knees;
mod surface_look;
mod surface_repair;
mod surface_turned;
