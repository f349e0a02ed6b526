//! `jobs::web`: the `web` verb's steps. Export a character database or a
//! result as a static site ([`WebSource::export`]); before serving one,
//! check the address is free ([`check_listen`]) and that a given folder is
//! an exported site ([`exported_site`]); a temporary export for the
//! server ([`temp_export`], [`TempSite`]).

use crate::web::{ExportOptions, ExportReport, WebError, export_db, export_result};
use std::path::{Path, PathBuf};

/// What a site shows.
#[derive(Debug, Clone, PartialEq)]
pub enum WebSource {
    /// A character database: the interactive character.
    Database(PathBuf),
    /// A result to view with a timeline (`.glb`, or `.pc2`/`.mdd` with
    /// the `.obj` of the same name or `topology`).
    Result {
        /// The result file.
        path: PathBuf,
        /// The topology of a point cache (default: the `.obj` beside it).
        topology: Option<PathBuf>,
    },
}

impl WebSource {
    /// Writes the site of this source into `out` ([`export_db`],
    /// [`export_result`]).
    pub fn export(&self, out: &Path, opts: &ExportOptions) -> Result<ExportReport, WebError> {
        match self {
            WebSource::Database(db) => export_db(db, out, opts),
            WebSource::Result { path, topology } => {
                export_result(path, topology.as_deref(), out, opts)
            }
        }
    }
}

/// What can go wrong before a site is served.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// The address cannot be listened on (not this machine's, or in use).
    #[error("cannot listen on {addr}: {error}")]
    Listen {
        /// The address, `HOST:PORT`.
        addr: String,
        /// Why.
        error: std::io::Error,
    },
    /// The folder given as a site holds no `index.html`.
    #[error(
        "{}: not an exported site (no index.html); make one with `surfmotion web export`",
        .0.display()
    )]
    NotASite(PathBuf),
    /// The temporary export folder could not be made.
    #[error("{}: {error}", dir.display())]
    TempFolder {
        /// The folder it was to be made in.
        dir: PathBuf,
        /// Why.
        error: std::io::Error,
    },
}

/// Refuses an address this machine cannot listen on (`HOST:PORT`), tried
/// before the export (seconds to minutes): an address this machine does
/// not have, or a port in use, failed only after it.
pub fn check_listen(addr: &str) -> Result<(), ServeError> {
    match std::net::TcpListener::bind(addr) {
        Ok(l) => {
            drop(l);
            Ok(())
        }
        Err(error) => Err(ServeError::Listen {
            addr: addr.to_string(),
            error,
        }),
    }
}

/// `dir` when it is an exported site (it holds `index.html`).
pub fn exported_site(dir: &Path) -> Result<PathBuf, ServeError> {
    match dir.join("index.html").is_file() {
        true => Ok(dir.to_path_buf()),
        false => Err(ServeError::NotASite(dir.to_path_buf())),
    }
}

/// A temporary export folder in `parent` ([`crate::web::export_folder`]),
/// removed when dropped; the site goes into its `site` subfolder.
pub fn temp_export(parent: &Path) -> Result<tempfile::TempDir, ServeError> {
    crate::web::export_folder(parent).map_err(|error| ServeError::TempFolder {
        dir: parent.to_path_buf(),
        error,
    })
}

/// The temporary export of `web serve`: a folder made by [`temp_export`]
/// after the exports of earlier servers that were stopped are removed
/// ([`crate::web::remove_stale_exports`]); the site goes into
/// [`TempSite::site`]. Removed on [`TempSite::close`] or when dropped.
pub struct TempSite {
    dir: tempfile::TempDir,
}

impl TempSite {
    /// Removes the stale exports in `parent` (`removed` told each folder),
    /// then makes a new temporary export folder there.
    pub fn new(parent: &Path, removed: &mut dyn FnMut(&Path)) -> Result<TempSite, ServeError> {
        for d in crate::web::remove_stale_exports(parent) {
            removed(&d);
        }
        Ok(TempSite {
            dir: temp_export(parent)?,
        })
    }

    /// The folder the site is exported into (`site` in the temporary
    /// folder).
    pub fn site(&self) -> PathBuf {
        self.dir.path().join("site")
    }

    /// Removes the temporary folder: its path, and whether that worked.
    pub fn close(self) -> (PathBuf, std::io::Result<()>) {
        let p = self.dir.path().to_path_buf();
        (p, self.dir.close())
    }
}

#[cfg(test)]
mod tests {
    /// A folder without `index.html` is refused as a site, with what to do.
    #[test]
    fn a_folder_without_index_html_is_not_a_site() {
        let d = tempfile::tempdir().unwrap();
        let e = super::exported_site(d.path()).unwrap_err().to_string();
        assert!(
            e.ends_with(
                "not an exported site (no index.html); make one with `surfmotion web export`"
            ),
            "{e}"
        );
        std::fs::write(d.path().join("index.html"), "").unwrap();
        assert_eq!(super::exported_site(d.path()).unwrap(), d.path());
    }

    /// A port in use is refused, naming the address.
    #[test]
    fn an_address_in_use_is_refused() {
        let held = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = held.local_addr().unwrap().to_string();
        let e = super::check_listen(&addr).unwrap_err().to_string();
        assert!(e.starts_with(&format!("cannot listen on {addr}: ")), "{e}");
    }
}
