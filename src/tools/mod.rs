//! Tools over the pipeline's results: the papers' metrics and plausibility
//! checks ([`eval`]), what any supported file holds ([`inspect`]), a
//! small software rasteriser for PNG views ([`render`]), and the
//! evaluation of the automatic rig ([`autorig`], on bodies cut at the
//! neck [`autorig_headless`], where the extremities are sought from
//! [`autorig_tips`]).

pub mod autorig;
pub mod autorig_confusion;
pub mod autorig_cut;
pub mod autorig_headless;
pub mod autorig_stump;
pub mod autorig_tips;
pub mod eval;
pub mod inspect;
pub mod render;
