//! The page to look at a rig and correct its landmarks (issue 41): `rig
//! embed --pick` and `db init --pick` serve, on 127.0.0.1, the rest mesh
//! coloured by body part with the skeleton and the landmarks as handles;
//! dragging a handle (snapped to the surface) posts the landmarks, the
//! server re-embeds ([`crate::embed::Embedding::new`]) and the page
//! redraws; Save writes the landmark file atomically.
//!
//! - [`session`]: the state and the HTTP API, without sockets;
//! - [`server`]: the small server answering it (the static
//!   [`super::serve`] takes no request bodies).
//!
//! The page is `assets/pick.html` and `assets/pick.js` (WebGL2, no
//! third-party script), embedded in the binary.

pub mod server;
pub mod session;

pub use server::PickServer;
pub use session::{PickSession, Response, SessionFiles};

/// The page.
pub(crate) const PAGE: &[u8] = include_bytes!("../assets/pick.html");
/// Its script.
pub const SCRIPT: &[u8] = include_bytes!("../assets/pick.js");
