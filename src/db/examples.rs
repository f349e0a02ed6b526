//! The part deformation's example frames, chosen once per database and
//! kept in its cache (issue 43, session 31): `cache/examples.json`.
//!
//! Each region of the part deformation (Huang et al. 2015, Sec. 5.2.3,
//! Eq. 32) takes the database frames farthest apart in its joints'
//! rotations as its examples (`deform::regions::region_examples`): the
//! global rotations of every database frame, then a farthest-point
//! selection over all of them, per region. That depends only on the
//! database (its skeletons and rig) and the options, yet every `retarget`
//! made it again: at 10⁴ frames, about sixteen passes over every frame's
//! rotations. The choice is kept here, keyed by the skeleton cache's key
//! (the frames, the rig, the skeleton kind and the skeleton code's
//! fingerprint) and the fingerprint of the code that chooses
//! ([`EXAMPLES_SOURCE`]): a changed database or choosing code chooses
//! again; the same frames are chosen either way, so the outputs are the
//! same bit for bit.
//!
//! File (JSON): `{"format": "surfmotion examples", "key": "16 hex digits",
//! "frames": N, "entries": [{"joints": ["l_hip", ...], "want": 40,
//! "frames": [ids]}]}`, written atomically when a load chose new examples.

use crate::graph::FlatFrame;
use crate::rig::Canonical;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The fingerprint of the code that chooses the examples and keeps them
/// (`build.rs`: the skeleton's sources, `src/deform/regions.rs` and this
/// file): a build whose choice may differ chooses again.
pub(crate) const EXAMPLES_SOURCE: &str = env!("SURFMOTION_EXAMPLES_SOURCE");

const FORMAT: &str = "surfmotion examples";

/// The example memo file of the database `dir`.
pub fn examples_path(dir: &Path) -> PathBuf {
    super::cache::cache_dir(dir).join("examples.json")
}

/// The memo's key for a database whose skeleton cache key is `skeletons`.
pub(crate) fn examples_key(skeletons: u64) -> u64 {
    let mut h = super::cache::KeyHasher::default();
    h.text("examples", FORMAT);
    h.text("skeletons", &skeletons.to_string());
    h.text("source", EXAMPLES_SOURCE);
    h.finish()
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct Entry {
    joints: Vec<String>,
    want: usize,
    frames: Vec<u32>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct MemoFile {
    format: String,
    key: String,
    frames: usize,
    entries: Vec<Entry>,
}

/// What the memo file `path` holds: its key, the database's frame count
/// it was chosen over, and its entries (joints, wanted count, frames), or
/// why it is not a memo (cut, changed, a frame out of range).
pub(crate) fn read_examples(path: &Path) -> Result<(u64, usize, usize), String> {
    let file = read_file(path)?;
    let key = parse_key(&file.key).ok_or_else(|| {
        format!(
            "{}: key '{}' is not 16 hex digits",
            path.display(),
            file.key
        )
    })?;
    Ok((key, file.frames, file.entries.len()))
}

fn parse_key(s: &str) -> Option<u64> {
    (s.len() == 16)
        .then(|| u64::from_str_radix(s, 16).ok())
        .flatten()
}

fn read_file(path: &Path) -> Result<MemoFile, String> {
    let text = crate::util::fsutil::read_small_text(path).map_err(|e| e.to_string())?;
    let file: MemoFile = serde_json::from_str(&text)
        .map_err(|e| format!("{}: not an example memo ({e})", path.display()))?;
    if file.format != FORMAT {
        return Err(format!(
            "{}: format '{}', not '{FORMAT}'",
            path.display(),
            file.format
        ));
    }
    for (i, e) in file.entries.iter().enumerate() {
        if let Some(f) = e.frames.iter().find(|&&f| f as usize >= file.frames) {
            return Err(format!(
                "{}: entry {i}: frame {f} of a database of {} frames",
                path.display(),
                file.frames
            ));
        }
        if e.frames.len() > e.want.max(1) {
            return Err(format!(
                "{}: entry {i}: {} frames where {} were wanted",
                path.display(),
                e.frames.len(),
                e.want
            ));
        }
    }
    Ok(file)
}

/// The chosen examples of one database, read from its memo on first use
/// and written back when new ones were chosen ([`ExampleMemo::save`]).
#[derive(Debug)]
pub struct ExampleMemo {
    path: PathBuf,
    key: u64,
    frames: usize,
    state: Mutex<State>,
}

#[derive(Debug, Default)]
struct State {
    /// Read from the file (once).
    loaded: bool,
    known: BTreeMap<(Vec<String>, usize), Vec<u32>>,
    /// Entries chosen since the file was read.
    dirty: bool,
}

impl ExampleMemo {
    /// The memo of the database `dir` of `frames` frames whose skeleton
    /// cache key is `skeletons` (nothing read yet).
    pub fn new(dir: &Path, skeletons: u64, frames: usize) -> ExampleMemo {
        ExampleMemo {
            path: examples_path(dir),
            key: examples_key(skeletons),
            frames,
            state: Mutex::new(State::default()),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The examples chosen for `joints` wanting `want`: from the memo when
    /// it holds them, else `choose()` (remembered; [`ExampleMemo::save`]
    /// writes them).
    pub fn chosen(
        &self,
        joints: &[Canonical],
        want: usize,
        choose: impl FnOnce() -> Vec<FlatFrame>,
    ) -> Vec<FlatFrame> {
        let k = (joints.iter().map(|j| j.name().to_string()).collect(), want);
        {
            let mut s = self.lock();
            if !s.loaded {
                s.loaded = true;
                s.known = self.read();
            }
            if let Some(f) = s.known.get(&k) {
                return f
                    .iter()
                    .map(|&i| FlatFrame::from_index(i as usize))
                    .collect();
            }
        }
        let chosen = choose();
        let mut s = self.lock();
        s.known
            .insert(k, chosen.iter().map(|f| f.index() as u32).collect());
        s.dirty = true;
        chosen
    }

    /// The file's entries when it is this database's memo; empty (with a
    /// warning naming it when it is there but cannot be used) otherwise.
    fn read(&self) -> BTreeMap<(Vec<String>, usize), Vec<u32>> {
        let file = match read_file(&self.path) {
            Ok(f) => f,
            Err(why) => {
                if self.path.exists() {
                    tracing::warn!("{why}; choosing the deformation's examples again");
                }
                return BTreeMap::new();
            }
        };
        if parse_key(&file.key) != Some(self.key) || file.frames != self.frames {
            return BTreeMap::new();
        }
        file.entries
            .into_iter()
            .map(|e| ((e.joints, e.want), e.frames))
            .collect()
    }

    /// Writes the memo when new examples were chosen since it was read (a
    /// file that cannot be written is logged: the next load chooses again).
    pub fn save(&self) {
        let mut s = self.lock();
        if !s.dirty {
            return;
        }
        let file = MemoFile {
            format: FORMAT.into(),
            key: format!("{:016x}", self.key),
            frames: self.frames,
            entries: s
                .known
                .iter()
                .map(|((joints, want), frames)| Entry {
                    joints: joints.clone(),
                    want: *want,
                    frames: frames.clone(),
                })
                .collect(),
        };
        let written = serde_json::to_string(&file)
            .map_err(|e| e.to_string())
            .and_then(|t| {
                crate::util::fsutil::write_bytes_atomic(&self.path, t.as_bytes())
                    .map_err(|e| e.to_string())
            });
        match written {
            Ok(()) => s.dirty = false,
            Err(why) => tracing::warn!("the deformation's examples are not cached: {why}"),
        }
    }
}
