//! Scan transfer (Confluent Motion).

mod feet;
mod options;
mod scans;
