//! Tools over the pipeline's results: the papers' metrics and plausibility
//! checks ([`eval`]), what any supported file holds ([`inspect`]), and a
//! small software rasteriser for PNG views ([`render`]).

pub mod eval;
pub mod inspect;
pub mod render;
