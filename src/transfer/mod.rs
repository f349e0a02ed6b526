//! Scanned-mesh transfer: Confluent Motion (de Aguiar et al. 2007). A
//! static scan is animated by a mocap clip or a moving template mesh
//! through a sparse set of marker triangles: marker rotations are spread
//! over the scan as harmonic quaternion fields and the mesh is rebuilt from
//! the per-triangle rotations by a prefactored Poisson solve.
//!
//! Pipeline order: [`scan`] (repair, markers) → [`markers`] (placement
//! rule, files) → [`source`] (marker motion per frame) → [`signs`]
//! (quaternion signs, singularities) → [`confluent`] (the per-frame
//! deformation) → [`run`] (a whole clip in parallel, held or streamed).

pub mod confluent;
pub mod job;
pub mod markers;
pub mod run;
pub mod scan;
pub mod signs;
pub mod source;

pub use confluent::{Confluent, ConfluentError};
pub use job::{Driving, Job, SetupError, alignment, mocap_motion, up_axis};
/// The old name of [`Driving`].
#[deprecated(note = "renamed `Driving` (issue 40: `Source` names a live input stream)")]
pub type Source<'a> = Driving<'a>;
pub use markers::{Marker, MarkerError, MarkerFile, MarkerOptions};
pub use run::{TransferOptions, TransferStats, transfer, transfer_into};
pub use scan::{MarkerSpec, PreparedScan, ScanError, prepare};
pub use signs::SignMode;
pub use source::MarkerMotion;
