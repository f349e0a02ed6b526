//! The jobs layer, batches and streamed output.

mod batch;
mod layer;
mod scale_out;
mod stream_output;
mod verbs;
