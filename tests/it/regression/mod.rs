//! Regressions and issue acceptance tests named after what they pin.

mod issue17_acceptance;
mod issue39_item3_skating;
