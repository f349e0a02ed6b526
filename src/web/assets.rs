//! The page, embedded in the binary and copied into every export: plain
//! JavaScript modules and WebGL2 shaders written for this project (no
//! third-party script, nothing fetched from the network at run time).
//!
//! - `index.html`: the page (canvas, motion buttons, timeline, error box);
//! - `app.js`: loading, the orbit camera, keys and buttons, the frame loop,
//!   the self-test (`?selftest=1`);
//! - `engine.js`: the character animation engine walking the Surface Motion
//!   Graph (Volino et al. 2015, Sec. 5);
//! - `render.js`: the WebGL2 renderer (blend of two frames on the GPU,
//!   ground plane, planar shadow);
//! - `decode.js` and `worker.js`: the `.sm4d` decoder ([`super::codec`]),
//!   run in a worker.

/// `(file name, contents)` of every asset, in the order they are written.
pub(crate) const FILES: &[(&str, &[u8])] = &[
    ("index.html", include_bytes!("assets/index.html")),
    ("app.js", include_bytes!("assets/app.js")),
    ("engine.js", include_bytes!("assets/engine.js")),
    ("render.js", include_bytes!("assets/render.js")),
    ("decode.js", include_bytes!("assets/decode.js")),
    ("worker.js", include_bytes!("assets/worker.js")),
];
