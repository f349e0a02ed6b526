//! `db init` as a job: a character's manifest (`character.toml`) written
//! from its files, every file read and checked first
//! ([`crate::db::init::assemble`]), nothing written on a refusal.

use super::JobError;
use super::outputs::check_output_folder;
use crate::db::init::{InitOptions, assemble};
use crate::db::{MANIFEST, Manifest};
use std::path::{Path, PathBuf};

/// What [`init_database`] wrote.
#[derive(Clone, Debug, serde::Serialize)]
pub struct InitReport {
    /// The manifest written (paths inside the folder relative to it).
    pub manifest: Manifest,
    /// Where it was written (`DIR/character.toml`).
    pub path: PathBuf,
    /// What the `auto` guesses decided, one line each (the up axis read
    /// as Z, the unit read as cm or mm).
    pub notes: Vec<String>,
}

/// Writes the manifest of `opts` into the database folder `dir` (created
/// if missing). Refused before anything is written: a `dir` that is a file,
/// an existing manifest without `force`, a file that does not read, a
/// sequence of another mesh, a rest frame not a person's size in its unit.
pub fn init_database(dir: &Path, opts: &InitOptions) -> Result<InitReport, JobError> {
    check_output_folder(
        "",
        dir,
        "db init writes the database's character.toml into a folder",
    )?;
    let mut notes = Vec::new();
    let manifest = assemble(dir, opts, &mut notes)?;
    manifest.save(dir)?;
    Ok(InitReport {
        manifest,
        path: dir.join(MANIFEST),
        notes,
    })
}
