//! The 4D character in a web browser (Volino, Huang & Hilton 2015): a
//! compact streaming geometry format ([`codec`]), the static site export
//! with the Surface Motion Graph's transition table ([`export`]), a local
//! server that keeps to the site's folder ([`serve`]), the site's manifest
//! types ([`site`]), the transition
//! windows' non-linear blend precomputed for the page ([`windows`]), and the
//! page's engine and WebGL2 renderer ([`assets`], embedded in the binary).

pub mod assets;
pub mod codec;
pub mod export;
pub mod pick;
pub mod serve;
pub mod site;
pub mod windows;

pub use codec::{CodecError, Decoded, EncodeOptions, EncodeReport, Geometry, Predictor};
pub use export::{ExportOptions, ExportReport, export_db, export_result, load_db_geometry};
pub use serve::{ServeOptions, SiteServer, resolve_path};
pub use serve::{export_folder, remove_stale_exports};
pub use site::{SiteManifest, SitePair, SiteSequence, SiteSpace, SiteTransition, WebError};
pub use windows::{WindowOptions, blend_windows};
