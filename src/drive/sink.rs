//! One frame sink for held and streamed output (issue 40): surface
//! synthesis ([`super::Prepared::synthesise`]), the retarget job and scan
//! transfer ([`crate::transfer::run::transfer_into`]) hand every output
//! frame, in order, to a [`FrameSink`]. Holding every frame is the sink
//! `Vec<[f64; 3]>`; streaming to a file is a
//! [`SequenceWriter`]; anything else (keeping the first frames, reading a
//! skeleton off each) is a closure in [`Each`].

use crate::mesh::MeshError;
use crate::mesh::io::stream::SequenceWriter;
use std::convert::Infallible;

/// Where output frames go, one at a time in frame order (each the
/// character's vertices).
pub trait FrameSink {
    /// Why a frame could not be taken.
    type Error;
    /// Takes the next frame.
    fn push(&mut self, frame: &[[f64; 3]]) -> Result<(), Self::Error>;
}

/// Every frame held, appended frame-major.
impl FrameSink for Vec<[f64; 3]> {
    type Error = Infallible;
    fn push(&mut self, frame: &[[f64; 3]]) -> Result<(), Infallible> {
        self.extend_from_slice(frame);
        Ok(())
    }
}

/// Every frame written as it comes (point caches, OBJ folders), or held
/// by the writer until `finish` (a GLB).
impl FrameSink for SequenceWriter {
    type Error = MeshError;
    fn push(&mut self, frame: &[[f64; 3]]) -> Result<(), MeshError> {
        SequenceWriter::push(self, frame)
    }
}

/// A closure as a sink.
pub struct Each<F>(pub F);

impl<F, E> FrameSink for Each<F>
where
    F: FnMut(&[[f64; 3]]) -> Result<(), E>,
{
    type Error = E;
    fn push(&mut self, frame: &[[f64; 3]]) -> Result<(), E> {
        (self.0)(frame)
    }
}

impl<S: FrameSink + ?Sized> FrameSink for &mut S {
    type Error = S::Error;
    fn push(&mut self, frame: &[[f64; 3]]) -> Result<(), S::Error> {
        (**self).push(frame)
    }
}
