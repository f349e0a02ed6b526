//! `rig embed --pick` and `db init --pick` as a job: the page to look at a
//! rig and correct its landmarks ([`crate::web::pick`]) opened on a rest
//! mesh ([`open`]) or on a database's rest frame ([`open_db`]), served
//! until the caller stops it, then [`finish`]ed into a [`PickReport`].
//!
//! The page starts from a landmark file. Without one it starts from the
//! automatic landmarks: a database's `auto.landmarks.json` (the automatic
//! rig of `db init`) when it is there, else the rest mesh's landmarks
//! found from its geometry ([`crate::embed::scan_landmarks`]). Automatic
//! landmarks refused below [`PickOptions::min_confidence`] still open the
//! page, with what was found and the reason shown, to be corrected there;
//! only a mesh where nothing is found is refused
//! ([`PickError::NoLandmarks`]).

use crate::db::{DbError, MANIFEST, Manifest};
use crate::embed::landmarks::{LandmarkError, Landmarks};
use crate::mesh::Mesh;
use crate::web::pick::{PickServer, PickSession, SessionFiles};
use crate::web::serve::ServeError;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

/// Where the page starts from and listens.
#[derive(Clone, Debug)]
pub struct PickOptions {
    /// The rest mesh's name as the user gave it (a file, or
    /// `SEQ.pc2:FRAME`), shown on the page.
    pub mesh: String,
    /// The landmark file the page starts from. Default (`None`): the
    /// automatic landmarks (see the module's page).
    pub landmarks: Option<PathBuf>,
    /// Automatic landmarks below this confidence (0..1) open the page with
    /// the reason shown. Default 0.5 (the CLI's `--min-confidence`).
    pub min_confidence: f64,
    /// Where Save writes when the page names no path. Default (`None`):
    /// beside the landmark file, `NAME.picked.landmarks.json` for
    /// `NAME.landmarks.json` (`-2`, `-3`, … added while such a file
    /// exists), so the input is never overwritten unless the page names
    /// it explicitly.
    pub save: Option<PathBuf>,
    /// Files Save never writes (the mesh and every other input).
    pub inputs: Vec<PathBuf>,
    /// Address to listen on. Default: `127.0.0.1:0` (a free port).
    pub bind: String,
}

impl Default for PickOptions {
    fn default() -> Self {
        PickOptions {
            mesh: String::new(),
            landmarks: None,
            min_confidence: crate::embed::scan_landmarks::ScanOptions::default().min_confidence,
            save: None,
            inputs: Vec::new(),
            bind: "127.0.0.1:0".into(),
        }
    }
}

/// Why the page cannot be opened.
#[derive(Debug, thiserror::Error)]
pub enum PickError {
    /// No landmarks to start from: none given and none found automatically.
    #[error(
        "{mesh}: no landmarks to start the page from ({why}); give a landmark file (`PickOptions::landmarks`: chin, groin, l_/r_wrist, l_/r_elbow, l_/r_knee as vertex ids or [x, y, z], rough places are fine, the page moves them){}",
        if *.db { "; or run `db init` with `InitOptions::landmarks`" } else { "" }
    )]
    NoLandmarks {
        /// The mesh or database.
        mesh: String,
        /// Why the automatic landmarks found nothing.
        why: String,
        /// It is a database.
        db: bool,
    },
    /// The landmark file does not read.
    #[error(transparent)]
    Landmarks(#[from] LandmarkError),
    /// The database does not open.
    #[error(transparent)]
    Db(#[from] DbError),
    /// The address cannot be listened on.
    #[error(transparent)]
    Listen(#[from] ServeError),
}

/// What the page did.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PickReport {
    /// The page's address.
    pub url: String,
    /// Files Save wrote, one entry per save.
    pub saved: Vec<PathBuf>,
    /// Embeddings computed (the first included).
    pub embeds: usize,
    /// Requests answered.
    pub requests: usize,
    /// The database manifest pointed at the last file saved
    /// ([`open_db`] only).
    pub manifest: Option<PathBuf>,
}

/// A page being served, with what [`finish`] needs.
pub struct Pick {
    /// The server ([`PickServer::run_until`] serves it).
    pub server: PickServer,
    /// The database, when opened by [`open_db`].
    db: Option<PathBuf>,
}

impl Pick {
    /// The page's address.
    pub fn url(&self) -> String {
        self.server.url()
    }

    /// Serves until `stop` is set (a signal handler's flag).
    pub fn run_until(&self, stop: &AtomicBool) {
        self.server.run_until(stop)
    }

    /// Serves on a background thread until `stop` is set.
    pub fn spawn(self, stop: Arc<AtomicBool>) -> std::thread::JoinHandle<Pick> {
        let db = self.db;
        let h = self.server.spawn(stop);
        std::thread::spawn(move || Pick {
            server: h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)),
            db,
        })
    }
}

/// The default save path for landmarks read from `input` (or, without
/// one, beside `mesh`): `NAME.picked.landmarks.json`, numbered while it
/// exists.
pub(crate) fn default_save_path(input: Option<&Path>, mesh: &Path) -> PathBuf {
    let from = input.unwrap_or(mesh);
    let name = from
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "character".into());
    let stem = name
        .strip_suffix(".landmarks.json")
        .or_else(|| name.strip_suffix(".json"))
        .map(str::to_string)
        .unwrap_or_else(|| {
            Path::new(&name)
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or(name.clone())
        });
    let dir = from.parent().unwrap_or(Path::new(""));
    let mut p = dir.join(format!("{stem}.picked.landmarks.json"));
    for k in 2..1000 {
        if !p.exists() {
            break;
        }
        p = dir.join(format!("{stem}.picked-{k}.landmarks.json"));
    }
    p
}

/// The automatic landmarks of `mesh` (named `name`) for the page: the
/// landmarks and, when they were refused below `min_confidence`, the
/// reason (the page opens with it shown).
fn automatic(
    mesh: &Mesh,
    name: &str,
    min_confidence: f64,
    db: bool,
) -> Result<(Landmarks, Option<String>), PickError> {
    use crate::embed::scan_landmarks::{ScanLandmarkError, ScanOptions, find};
    let o = ScanOptions { min_confidence };
    match find(mesh.positions(), mesh.triangles(), &o) {
        Ok(a) => Ok((a.landmarks(), None)),
        Err(e @ ScanLandmarkError::Refused { .. }) => {
            let reason = e.to_string();
            let ScanLandmarkError::Refused { found, .. } = e else {
                unreachable!()
            };
            match *found {
                Some(f) if !f.marks.is_empty() => Ok((f.landmarks(), Some(reason))),
                _ => Err(PickError::NoLandmarks {
                    mesh: name.to_string(),
                    why: reason,
                    db,
                }),
            }
        }
        Err(e) => Err(PickError::NoLandmarks {
            mesh: name.to_string(),
            why: e.to_string(),
            db,
        }),
    }
}

/// Opens the page on the rest mesh `mesh` as `o` says: the landmarks read
/// (or found automatically) and embedded (landmarks no rig can be
/// embedded from still open the page, with the reason), the address bound.
pub fn open(mesh: Mesh, o: &PickOptions) -> Result<Pick, PickError> {
    let (lm, notice) = match &o.landmarks {
        Some(l) => (Landmarks::load(l, mesh.vertex_count())?, None),
        None => automatic(&mesh, &o.mesh, o.min_confidence, false)?,
    };
    let mesh_path = crate::mesh::io::split_frame_ref(&o.mesh).0;
    let files = SessionFiles {
        input: o.landmarks.clone(),
        default_save: o
            .save
            .clone()
            .unwrap_or_else(|| default_save_path(o.landmarks.as_deref(), &mesh_path)),
        protected: o.inputs.clone(),
    };
    let mut session = PickSession::new(mesh, &o.mesh, lm, files);
    session.set_notice(notice);
    Ok(Pick {
        server: PickServer::bind(session, &o.bind)?,
        db: None,
    })
}

/// Opens the page on the database in `dir`: its rest frame and the
/// landmarks its manifest names. Save writes a new landmark file (as
/// [`PickOptions::save`] says; `o.mesh` and `o.landmarks` are taken from
/// the manifest) and [`finish`] points the manifest at it.
pub fn open_db(dir: &Path, o: &PickOptions) -> Result<Pick, PickError> {
    let (m, mesh) = Manifest::open(dir)?;
    // The manifest's landmarks, else the automatic rig's file, else the
    // rest frame's automatic landmarks.
    let auto_file = dir.join(super::db_init::AUTO_LANDMARKS);
    let l = match &m.rig.landmarks {
        Some(l) => Some(Manifest::resolve(dir, l)),
        None => auto_file.is_file().then_some(auto_file),
    };
    let (lm, notice) = match &l {
        Some(l) => (Landmarks::load(l, mesh.vertex_count())?, None),
        None => automatic(&mesh, &dir.display().to_string(), o.min_confidence, true)?,
    };
    let topology = Manifest::resolve(dir, &m.topology);
    let mut protected = o.inputs.clone();
    protected.push(topology.clone());
    protected.push(dir.join(MANIFEST));
    protected.extend(m.sequences.iter().map(|s| Manifest::resolve(dir, &s.path)));
    protected.extend(
        [&m.rig.parts, &m.rig.gltf_skin, &m.rig.rig_map, &m.colors]
            .into_iter()
            .flatten()
            .map(|p| Manifest::resolve(dir, p)),
    );
    let files = SessionFiles {
        input: l.clone(),
        default_save: o
            .save
            .clone()
            .unwrap_or_else(|| default_save_path(l.as_deref(), &topology)),
        protected,
    };
    let name = format!("{} ({})", m.name, topology.display());
    let mut session = PickSession::new(mesh, &name, lm, files);
    session.set_notice(notice);
    Ok(Pick {
        server: PickServer::bind(session, &o.bind)?,
        db: Some(dir.to_path_buf()),
    })
}

/// The report of a page that has stopped; for a database, its manifest
/// is pointed at the last landmark file saved (an absolute path).
pub fn finish(p: Pick) -> Result<PickReport, PickError> {
    let url = p.server.url();
    let requests = p.server.requests();
    let (saved, embeds) = p.server.with_session(|s| (s.saved().to_vec(), s.embeds()));
    let mut manifest = None;
    if let (Some(dir), Some(last)) = (&p.db, saved.last()) {
        let mut m = Manifest::read(dir)?;
        // Relative to the folder when inside it, as `db init` writes paths.
        let abs = std::path::absolute(last).unwrap_or_else(|_| last.clone());
        let root = std::path::absolute(dir).unwrap_or_else(|_| dir.clone());
        let rel = abs.strip_prefix(&root).map(Path::to_path_buf);
        m.rig.landmarks = Some(rel.unwrap_or(abs));
        m.save(dir)?;
        manifest = Some(dir.join(MANIFEST));
    }
    Ok(PickReport {
        url,
        saved,
        embeds,
        requests,
        manifest,
    })
}
