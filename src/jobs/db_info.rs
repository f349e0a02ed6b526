//! `db info`'s verdict (issue 39, item 6): a database whose report lists
//! a problem is a failure, so that scripts can rely on it (it listed
//! problems and exited 0).

use crate::db::DbInfo;
use std::path::{Path, PathBuf};

/// Where the problems were shown to the reader.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Listed {
    /// In the printed report, above the verdict.
    Above,
    /// In the JSON report's `problems`.
    InJson,
}

/// A database with problems.
#[derive(Debug, thiserror::Error)]
#[error(
    "{}: {} ({})",
    dir.display(),
    crate::batch::summary::count(*problems, "problem"),
    match listed {
        Listed::Above => "listed above",
        Listed::InJson => "\"problems\" in the JSON",
    }
)]
pub struct HasProblems {
    /// The database folder, as given.
    pub dir: PathBuf,
    /// How many problems it has.
    pub problems: usize,
    /// Where they were shown.
    pub listed: Listed,
}

/// `Ok` when `info` (of the database `dir`) lists no problem.
pub fn verdict(info: &DbInfo, dir: &Path, listed: Listed) -> Result<(), HasProblems> {
    if info.problems.is_empty() {
        return Ok(());
    }
    Err(HasProblems {
        dir: dir.to_path_buf(),
        problems: info.problems.len(),
        listed,
    })
}
