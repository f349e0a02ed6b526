//! The site's manifest as the page reads it (sequences, the Surface Motion
//! Graph's transition table, parametric spaces) and the export's error.

use super::codec::CodecError;
use crate::db::DbError;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Errors of the export.
#[derive(Debug, thiserror::Error)]
pub enum WebError {
    /// The database failed to load.
    #[error(transparent)]
    Db(#[from] DbError),
    /// A result file failed to load.
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    /// The geometry could not be encoded or decoded.
    #[error(transparent)]
    Codec(#[from] CodecError),
    /// The parametric model (motion spaces) or the transition blender
    /// could not be built.
    #[error(transparent)]
    Param(#[from] crate::parametric::ParamError),
    /// The output folder holds something this export may not replace, or
    /// an input lies inside it.
    #[error("{path}: {msg}")]
    Refused {
        /// The file or folder.
        path: PathBuf,
        /// Why.
        msg: String,
    },
    /// Writing the site failed.
    #[error("{path}: {msg}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// What went wrong.
        msg: String,
    },
}

/// A sequence as the page sees it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SiteSequence {
    /// Name (the button's label).
    pub name: String,
    /// Frames.
    pub frames: usize,
    /// Frames per second.
    pub fps: f64,
    /// Ground-plane alignment `[cos θ, sin θ, tx, tz]` carrying frame 0 onto
    /// the last frame: the page's fallback when a motion ends with no
    /// transition to take.
    pub restart: [f64; 4],
}

/// One transition of the Surface Motion Graph, as the page's engine plays
/// it: frames `m−L..=m+L` of `from` blended into `n−L..=n+L` of `to`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SiteTransition {
    /// Source sequence index.
    pub from: usize,
    /// Target sequence index.
    pub to: usize,
    /// Centre frame in the source.
    pub m: usize,
    /// Centre frame in the target.
    pub n: usize,
    /// Half-window L.
    pub window: usize,
    /// The graph's cost.
    pub cost: f64,
    /// Ground-plane alignment `[cos θ, sin θ, tx, tz]` carrying the target's
    /// frame `n` onto the source's frame `m` (a rotation about +Y, then a
    /// translation in x and z; least squares over all vertices).
    pub align: [f64; 4],
    /// The geometry sequence holding the window's `2L + 1` frames blended
    /// non-linearly (Huang et al. 2015, Sec. 4.4: frame `i` is
    /// `G(from[m−L+i], align·to[n−L+i], i / 2L)`, [`crate::mesh::blend::Blender`]),
    /// in the source's coordinates; absent: the page blends linearly.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blended: Option<usize>,
}

/// A parametric motion space (Casas et al. 2013, Sec. 3) as the page plays
/// it: the hybrid blend's stored reference frames (Eq. 3; each a geometry
/// sequence of `grid` phase samples in the body frame, metres), the root
/// motion per phase step, and the parameter maps with their valid ranges.
/// A frame is the bilinear blend of four stored frames: the two references
/// bracketing the weight, each at the two phase samples around the phase.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SiteSpace {
    /// Name (the button's label).
    pub name: String,
    /// Its sequences, in blend order (weight coordinate `u = i` is sequence `i`).
    pub sequences: Vec<String>,
    /// Its parameters (`"speed"`, `"turn"`); the first is blended, a later
    /// `turn` steers the heading.
    pub parameters: Vec<String>,
    /// Phase samples per cycle, `K`.
    pub grid: usize,
    /// Frames per second of the model.
    pub fps: f64,
    /// Per pair of neighbouring sequences: reference weights in `[0, 1]`
    /// (increasing, 0 and 1 included) and the geometry sequence of each.
    pub pairs: Vec<SitePair>,
    /// The geometry sequence of the space's first block (its sequence 0;
    /// the whole blend when the space has a single sequence).
    pub first_block: usize,
    /// Root motion per sequence and phase step: travel `(x, z)` in the
    /// body frame (metres), heading change (radians), duration (frames).
    pub steps: Vec<Vec<[f64; 4]>>,
    /// `(u, speed m/s, turn deg/s)` measured at weight step 0.05.
    pub measured: Vec<[f64; 3]>,
    /// The inverse map `u = h⁻¹(p)` of the first parameter (Sec. 3.1.4).
    pub axis: Option<crate::parametric::params::ParamMap>,
    /// Valid range `[min, max]` of each parameter (a steering `turn`: the
    /// blend's own turning; the page allows ±90°/s around it).
    pub ranges: Vec<[f64; 2]>,
}

/// The references between two neighbouring sequences of a space.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SitePair {
    /// ClipNeutral weights in `[0, 1]`, increasing.
    pub weights: Vec<f64>,
    /// The geometry sequence of each reference.
    pub blocks: Vec<usize>,
}

/// `manifest.json` of a site.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SiteManifest {
    /// Always [`super::export::FORMAT`].
    pub format: String,
    /// Layout version of the manifest (1).
    pub version: u32,
    /// `"character"` (the interactive engine) or `"result"` (a timeline).
    pub mode: String,
    /// Character or result name.
    pub name: String,
    /// The geometry file.
    pub geometry: String,
    /// Its size in bytes.
    pub geometry_bytes: usize,
    /// The measured maximum vertex error of the geometry (metres).
    pub max_error: f64,
    /// Sequences (one for a result).
    pub sequences: Vec<SiteSequence>,
    /// The transition table (empty for a result).
    pub transitions: Vec<SiteTransition>,
    /// Parametric motion spaces (absent without `[[space]]` entries).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub spaces: Vec<SiteSpace>,
    /// Sequences in the geometry file: the `sequences` above first, then
    /// the spaces' reference blocks and the blended transition windows.
    #[serde(default)]
    pub geometry_sequences: usize,
}
