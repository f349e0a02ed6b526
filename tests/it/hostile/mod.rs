//! Hostile and malformed input: every verb and every reader.

mod malformed;
mod verbs;
