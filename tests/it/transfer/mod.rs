//! Scan transfer (Confluent Motion).

mod feet;
mod scans;
