//! The jobs layer, batches and streamed output.

mod batch;
mod layer;
mod stream_output;
mod verbs;
