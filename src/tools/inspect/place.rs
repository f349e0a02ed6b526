//! Where a path stands among a database's folders: a database folder or
//! its cache folder (shared by the database and rig cache reports).

use crate::db::{MANIFEST, Manifest};
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

/// The key after an 8-byte magic at the start of a cache file.
pub(crate) fn header_key(path: &Path, magic: &[u8; 8]) -> Result<u64, String> {
    let b = super::other::head(path, 16).map_err(|e| e.to_string())?;
    if b.len() < 16 || &b[..8] != magic {
        return Err("not a cache file of its kind".into());
    }
    let mut k = [0u8; 8];
    k.copy_from_slice(&b[8..16]);
    Ok(u64::from_le_bytes(k))
}

/// The rig's files a manifest names (`landmarks FILE`, `parts FILE`,
/// `glTF skin FILE`, `rig map FILE`), as the database's listing and the
/// rig cache's report say them.
pub(crate) fn rig_files(m: &Manifest) -> Vec<String> {
    [
        ("landmarks", &m.rig.landmarks),
        ("parts", &m.rig.parts),
        ("glTF skin", &m.rig.gltf_skin),
        ("rig map", &m.rig.rig_map),
    ]
    .into_iter()
    .filter_map(|(what, p)| p.as_ref().map(|p| format!("{what} {}", p.display())))
    .collect()
}
