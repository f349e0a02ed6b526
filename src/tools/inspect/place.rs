//! Where a path stands among a database's folders: a database folder or
//! its cache folder (shared by the database and rig cache reports).

use crate::db::MANIFEST;
use std::path::{Path, PathBuf};

/// The database folder `path` is (it holds [`MANIFEST`]).
pub(crate) fn is_database(path: &Path) -> bool {
    path.is_dir() && path.join(MANIFEST).is_file()
}

/// The database whose cache folder `path` is.
pub(crate) fn database_of_cache(path: &Path) -> Option<PathBuf> {
    if !path.is_dir() || path.file_name()? != "cache" {
        return None;
    }
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    is_database(&parent).then_some(parent)
}
