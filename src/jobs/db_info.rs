//! `db info`'s verdict (issue 39, item 6): a database whose report lists
//! a problem is a failure, so that scripts can rely on it (it listed
//! problems and exited 0).

use crate::db::{DbError, DbInfo};
use std::path::{Path, PathBuf};

/// How many of the rig check's warnings `db info` quotes.
const QUOTED: usize = 3;

/// `db info`'s report: [`crate::db::info`], and what `db init`'s setup
/// report (`setup.json`, when there is one) found of the rig: the rest
/// frame, the automatic rig's confidence and warnings, the rig check's
/// warnings (issue 41: a database whose automatic rig `db init` warned
/// about listed nothing of it). They are notes, not problems: the rig was
/// embedded; whether it is right is for the picture and the user.
pub fn info(dir: &Path) -> Result<DbInfo, DbError> {
    let mut i = crate::db::info(dir)?;
    i.notes.extend(setup_notes(dir));
    Ok(i)
}

/// The notes read from `DIR/setup.json` (none without the file).
fn setup_notes(dir: &Path) -> Vec<String> {
    let path = dir.join(super::db_init::SETUP);
    let Ok(text) = std::fs::read_to_string(&path) else {
        return Vec::new();
    };
    let Ok(v) = serde_json::from_str::<serde_json::Value>(&text) else {
        return vec![format!(
            "{}: not the setup report `db init` writes (unreadable JSON); run `db init` again to see the rig's setup",
            path.display()
        )];
    };
    let strings = |x: &serde_json::Value| -> Vec<String> {
        x.as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|x| x.as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default()
    };
    let mut notes = Vec::new();
    if let Some(rest) = v["rest_frame"].as_str() {
        notes.push(format!(
            "rig set up by `db init` on the rest frame {rest} (setup.json)"
        ));
    }
    notes.extend(strings(&v["automatic"]));
    let warnings: Vec<String> = v["check"]["warnings"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|w| w["message"].as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default();
    if !warnings.is_empty() {
        let shown = warnings[..warnings.len().min(QUOTED)].join("; ");
        let more = warnings.len().saturating_sub(QUOTED);
        notes.push(format!(
            "the rig's check at `db init`: {}: {shown}{} (setup.json; look at `db init --png`)",
            crate::batch::summary::count(warnings.len(), "warning"),
            if more > 0 {
                format!("; {more} more")
            } else {
                String::new()
            }
        ));
    }
    notes.extend(
        strings(&v["check"]["skipped"])
            .into_iter()
            .map(|s| format!("the rig's check: {s}")),
    );
    notes
}

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
