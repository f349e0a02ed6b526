//! Tools over the pipeline's results: the papers' metrics and plausibility
//! checks ([`eval`]), what any supported file holds ([`inspect`]), a
//! small software rasteriser for PNG views ([`render`]), and the
//! evaluation of the automatic rig ([`autorig`], and on bodies cut at the
//! neck [`autorig_headless`]).

pub mod autorig;
pub mod autorig_headless;
pub mod eval;
pub mod inspect;
pub mod render;
