//! The database's frames streamed, not loaded (issue 43): every frame of
//! every sequence, converted once to metres, Y-up, in a cache file that is
//! memory-mapped, so a retarget touches (and the system pages in) only the
//! frames it reads, and the per-frame skeletons beside it.
//!
//! Frame cache (`cache/frames.bin`, little-endian): magic `SMFRM001`, key
//! `u64`, vertices per frame `u64`, frames `u64`, zeros to byte 64; then
//! every frame's positions as `f64` triples (metres, Y-up, exactly the
//! values [`Character`](super::Character) held in memory before), then each
//! frame's lowest Y (`f64`). Skeleton cache (`cache/poses-KIND.bin`):
//! magic `SMPOS001`, key, frames, joints per pose, then the joints as
//! `f64` triples. Both are written atomically, streamed sequence by
//! sequence (one sequence in memory at a time), and checked against their
//! key and their exact length before use: a truncated or foreign file is a
//! [`FrameCacheError`] naming it, and the caller rebuilds it.

use super::cache::{KeyHasher, add_rig, cache_dir, frames_key};
use super::manifest::{DbError, MANIFEST, Manifest};
use crate::embed::Embedding;
use crate::embed::frames::{SkeletonKind, poses, rigid_fit};
use crate::graph::FlatFrame;
use crate::mocap::units::y_up;
use crate::pose::Pose;
use crate::util::fsutil::{FsError, write_atomic};
use glam::DVec3;
use std::io::Read;
use std::path::{Path, PathBuf};

const FRAMES_MAGIC: &[u8; 8] = b"SMFRM001";
const POSES_MAGIC: &[u8; 8] = b"SMPOS001";
/// Bytes before the first frame (a multiple of 8: the mapped `f64`s are
/// aligned, the map itself being page-aligned).
const HEADER: usize = 64;
/// Joints of a pose.
const JOINTS: usize = std::mem::size_of::<Pose>() / 24;

/// Why a frame or skeleton cache file cannot be used (the caller rebuilds
/// it).
#[derive(Debug, thiserror::Error)]
pub enum FrameCacheError {
    /// The file cannot be opened, read or mapped.
    #[error("{}: {source}", path.display())]
    Io {
        /// The cache file.
        path: PathBuf,
        /// The failure.
        source: std::io::Error,
    },
    /// Not a cache file of this kind (another magic), or made for other
    /// inputs (another key) or another size.
    #[error("{}: {what}", path.display())]
    Header {
        /// The cache file.
        path: PathBuf,
        /// What does not match.
        what: String,
    },
    /// Shorter (or longer) than its header says: cut by a full disk or a
    /// killed copy.
    #[error("{}: {len} bytes where its header needs {expected}", path.display())]
    Length {
        /// The cache file.
        path: PathBuf,
        /// Its length.
        len: u64,
        /// The length its header needs.
        expected: u64,
    },
}

impl FrameCacheError {
    /// The I/O failure on `path`, as `map_err` takes it.
    fn io_at(path: &Path) -> impl Fn(std::io::Error) -> FrameCacheError + Copy + '_ {
        move |source| FrameCacheError::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    /// The header mismatch `what` in `path`.
    fn header_at(path: &Path) -> impl Fn(String) -> FrameCacheError + Copy + '_ {
        move |what| FrameCacheError::Header {
            path: path.to_path_buf(),
            what,
        }
    }
}

/// The frame cache file of the database `dir`.
pub fn frames_path(dir: &Path) -> PathBuf {
    cache_dir(dir).join("frames.bin")
}

/// The skeleton cache file of `kind` in the database `dir`.
pub fn poses_path(dir: &Path, kind: SkeletonKind) -> PathBuf {
    cache_dir(dir).join(format!("poses-{}.bin", kind_name(kind)))
}

fn kind_name(kind: SkeletonKind) -> &'static str {
    match kind {
        SkeletonKind::Rigid => "rigid",
        SkeletonKind::Regressor => "regressor",
        SkeletonKind::Centroid => "centroid",
    }
}

/// Where a [`FrameStore`]'s positions live.
enum Backing {
    /// The cache file, memory-mapped (positions from byte [`HEADER`],
    /// then the lowest Y of each frame).
    Mapped(memmap2::Mmap),
    /// Held in memory (positions, then lows): built by [`FrameStore::owned`].
    Owned(Vec<[f64; 3]>, Vec<f64>),
}

/// Every frame of a database, `n` positions a frame, metres, Y-up: a
/// memory-mapped cache file (or, for a database built in memory, a
/// vector). [`FrameStore::frame`] borrows one frame without copying.
pub struct FrameStore {
    backing: Backing,
    /// Vertices per frame.
    n: usize,
    /// Frames.
    count: usize,
}

impl std::fmt::Debug for FrameStore {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kind = match self.backing {
            Backing::Mapped(_) => "mapped",
            Backing::Owned(..) => "owned",
        };
        write!(f, "FrameStore({kind}, {} frames × {})", self.count, self.n)
    }
}

impl FrameStore {
    /// Frames held in memory (`frames`: `n` positions a frame).
    pub fn owned(frames: Vec<[f64; 3]>, n: usize) -> FrameStore {
        let count = frames.len() / n.max(1);
        let lows = frames.chunks_exact(n.max(1)).map(lowest).collect();
        FrameStore {
            backing: Backing::Owned(frames, lows),
            n,
            count,
        }
    }

    /// Maps the frame cache `path` written for `key`, `n` vertices and
    /// `count` frames: an error naming the file when it is missing, of
    /// another key or size, or not exactly as long as its header says.
    pub fn open(
        path: &Path,
        key: u64,
        n: usize,
        count: usize,
    ) -> Result<FrameStore, FrameCacheError> {
        let (io, header) = (
            FrameCacheError::io_at(path),
            FrameCacheError::header_at(path),
        );
        let mut file = std::fs::File::open(path).map_err(io)?;
        let mut head = [0u8; 32];
        file.read_exact(&mut head)
            .map_err(|_| FrameCacheError::Length {
                path: path.to_path_buf(),
                len: file.metadata().map(|m| m.len()).unwrap_or(0),
                expected: HEADER as u64,
            })?;
        if &head[..8] != FRAMES_MAGIC {
            return Err(header("not a frame cache file (no SMFRM001 header)".into()));
        }
        let word = |k: usize| u64::from_le_bytes(head[k..k + 8].try_into().unwrap_or([0; 8]));
        if word(8) != key {
            return Err(header("made from other sequences (another key)".into()));
        }
        if (word(16), word(24)) != (n as u64, count as u64) {
            return Err(header(format!(
                "{} frames of {} vertices, where the database has {count} of {n}",
                word(24),
                word(16)
            )));
        }
        let expected = frames_len(n, count);
        let len = file.metadata().map_err(io)?.len();
        if len != expected {
            return Err(FrameCacheError::Length {
                path: path.to_path_buf(),
                len,
                expected,
            });
        }
        // SAFETY: the cache file is the database's own, written atomically
        // (a new file renamed over the old, never changed in place), so the
        // mapped bytes do not change under the map; its length was checked
        // above.
        let map = unsafe { memmap2::Mmap::map(&file) }.map_err(io)?;
        if map.len() as u64 != expected || !cfg!(target_endian = "little") {
            return Err(header("cannot be mapped as little-endian f64".into()));
        }
        let store = FrameStore {
            backing: Backing::Mapped(map),
            n,
            count,
        };
        // The positions start 8-aligned (the map is page-aligned).
        if store.mapped_f64(HEADER, 0).is_none() {
            return Err(header("not 8-byte aligned in memory".into()));
        }
        Ok(store)
    }

    /// `len` f64 of the map from byte `at`, when aligned.
    fn mapped_f64(&self, at: usize, len: usize) -> Option<&[f64]> {
        let Backing::Mapped(map) = &self.backing else {
            return None;
        };
        let bytes = map.get(at..at + len * 8)?;
        // SAFETY: every bit pattern is a valid f64; `align_to` checks the
        // alignment (an unaligned start leaves a prefix, refused).
        let (pre, mid, _) = unsafe { bytes.align_to::<f64>() };
        (pre.is_empty() && mid.len() == len).then_some(mid)
    }

    /// `len` points (three f64 each) of the mapped file from byte `at`.
    fn mapped_xyz(&self, at: usize, len: usize) -> Option<&[[f64; 3]]> {
        let Backing::Mapped(map) = &self.backing else {
            return None;
        };
        let bytes = map.get(at..at + len * 24)?;
        // SAFETY: every bit pattern is a valid `[f64; 3]`; `align_to`
        // checks the alignment (an unaligned start leaves a prefix, refused).
        let (pre, mid, _) = unsafe { bytes.align_to::<[f64; 3]>() };
        (pre.is_empty() && mid.len() == len).then_some(mid)
    }

    /// Vertices per frame.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.count
    }

    /// True without frames.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// True when the frames are read from a memory-mapped file.
    pub fn is_mapped(&self) -> bool {
        matches!(self.backing, Backing::Mapped(_))
    }

    /// Every frame, frame-major (touching all of them pages in the whole
    /// file: [`FrameStore::frame`] reads one).
    pub fn all(&self) -> &[[f64; 3]] {
        match &self.backing {
            Backing::Owned(f, _) => f,
            Backing::Mapped(_) => self.mapped_xyz(HEADER, self.count * self.n).unwrap_or(&[]),
        }
    }

    /// Frame `id`'s positions (`n` of them).
    pub fn frame(&self, id: FlatFrame) -> &[[f64; 3]] {
        let (a, b) = (id.index() * self.n, (id.index() + 1) * self.n);
        match &self.backing {
            Backing::Owned(f, _) => &f[a..b],
            Backing::Mapped(_) => {
                assert!(id.index() < self.count, "frame {id} of {}", self.count);
                self.mapped_xyz(HEADER + a * 24, self.n).unwrap_or(&[])
            }
        }
    }

    /// Asks the system to read frames `ids` of a mapped store into the
    /// page cache now, all at once and only their bytes (nothing for a
    /// store held in memory). A scattered read of cold frames otherwise
    /// faults each page in with the device's read-around (8 MB on this
    /// project's VM, `read_ahead_kb`): a retarget's 480 deformation
    /// examples at 10⁴ frames read 1 GB of the 2.4 GB cache cold instead
    /// of their 115 MB (issue 43, session 45).
    pub fn prefetch(&self, ids: &[FlatFrame]) {
        let Backing::Mapped(map) = &self.backing else {
            return;
        };
        for id in ids.iter().filter(|id| id.index() < self.count) {
            let at = HEADER + id.index() * self.n * 24;
            let len = self.n * 24;
            if at + len <= map.len() && len > 0 {
                let _ = map.advise_range(memmap2::Advice::WillNeed, at, len);
            }
        }
    }

    /// Lets the system drop the pages of frames `first..first + count`
    /// from this process's memory (a mapped store; nothing for one held
    /// in memory): a pass over every frame (the plausibility reference)
    /// then holds one sequence at a time, not the whole file. The frames
    /// stay readable: a later read pages them in again from the file.
    pub fn release(&self, first: usize, count: usize) {
        let Backing::Mapped(map) = &self.backing else {
            return;
        };
        let at = HEADER + first * self.n * 24;
        let len = count * self.n * 24;
        if at + len <= map.len() && len > 0 {
            // SAFETY: the map is a read-only mapping of a file that is not
            // changed in place (see `open`): dropped pages read back the
            // same bytes, so no borrowed slice sees a change.
            let _ =
                unsafe { map.unchecked_advise_range(memmap2::UncheckedAdvice::DontNeed, at, len) };
        }
    }

    /// The lowest Y of frame `id` (metres; +∞ for a frame without
    /// vertices), kept beside the frames so that no scan reads them all.
    pub fn lowest(&self, id: FlatFrame) -> f64 {
        match &self.backing {
            Backing::Owned(_, lows) => lows[id.index()],
            Backing::Mapped(_) => self
                .mapped_f64(HEADER + self.count * self.n * 24 + id.index() * 8, 1)
                .map_or(f64::INFINITY, |v| v[0]),
        }
    }
}

/// The lowest Y of a frame's positions.
pub fn lowest(f: &[[f64; 3]]) -> f64 {
    f.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min)
}

/// The length of a frame cache of `count` frames of `n` vertices.
fn frames_len(n: usize, count: usize) -> u64 {
    HEADER as u64 + (count as u64) * (n as u64) * 24 + count as u64 * 8
}

/// The length of a skeleton cache of `count` poses.
fn poses_len(count: usize) -> u64 {
    32 + (count * JOINTS * 24) as u64
}

/// The keys of the frame and skeleton caches: the database's frames (the
/// files' bytes), the unit and up axis, and for the skeletons the rig's
/// inputs, the kind and the fingerprint of the code that makes and reads
/// them ([`super::skeletons::SKELETON_SOURCE`]: a changed reader or
/// skeleton code rebuilds the cache instead of reading the old one).
pub fn keys(
    dir: &Path,
    m: &Manifest,
    metres_per_unit: f64,
    kind: SkeletonKind,
) -> Result<(u64, u64), DbError> {
    keys_of_code(
        dir,
        m,
        metres_per_unit,
        kind,
        super::skeletons::SKELETON_SOURCE,
    )
}

/// [`keys`] as a build whose skeleton code has the fingerprint `source`
/// computes them (the keys of another version's caches).
pub fn keys_of_code(
    dir: &Path,
    m: &Manifest,
    metres_per_unit: f64,
    kind: SkeletonKind,
    source: &str,
) -> Result<(u64, u64), DbError> {
    let mut h = frames_key(dir, m)?;
    h.text("frame cache", "metres, y up, f64");
    h.text("metres per unit", &metres_per_unit.to_bits().to_string());
    let fk = h.finish();
    let mut p = KeyHasher::for_db(dir);
    p.text("frames", &fk.to_string());
    add_rig(&mut p, dir, m)?;
    super::rig_cache::add_rig_choice(&mut p, dir, m)?;
    p.save();
    p.text("skeleton", kind_name(kind));
    p.text("skeleton source", source);
    let pk = p.finish();
    tracing::debug!(
        "{}: cache keys: frames {fk:016x}, poses ({}) {pk:016x}",
        dir.display(),
        kind_name(kind)
    );
    Ok((fk, pk))
}

/// How one database's frames are converted (file units and axes to metres,
/// Y-up).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Conversion {
    /// Metres per file unit.
    pub metres_per_unit: f64,
    /// The files are Z-up.
    pub z_up: bool,
}

impl Conversion {
    /// The manifest's conversion: its `units` (1 metre a unit when they
    /// cannot be read) and its `up` axis.
    pub(crate) fn of(m: &Manifest) -> Conversion {
        Conversion {
            metres_per_unit: crate::mocap::units::parse_unit(&m.units)
                .map(|u| u.metres_per_unit)
                .unwrap_or(1.0),
            z_up: m.up.eq_ignore_ascii_case("z"),
        }
    }
    fn point(&self, p: [f64; 3]) -> [f64; 3] {
        (y_up(p, self.z_up) * self.metres_per_unit).to_array()
    }
    fn pose(&self, p: Pose) -> Pose {
        p.map(|j| y_up(j.to_array(), self.z_up) * self.metres_per_unit)
    }
}

/// What a database's frame and skeleton caches are made from: the
/// database `dir` with its manifest and rig, `count` frames of `n`
/// vertices, converted by `conv`, skeletons of `kind`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CacheInputs<'a> {
    /// The database folder.
    pub dir: &'a Path,
    /// Its manifest.
    pub manifest: &'a Manifest,
    /// The rig embedded on its rest frame.
    pub rig: &'a Embedding,
    /// Vertices per frame.
    pub n: usize,
    /// Frames.
    pub count: usize,
    /// File units and axes to metres, Y-up.
    pub conv: Conversion,
    /// The skeletons' kind.
    pub kind: SkeletonKind,
}

/// The skeletons a load reads by default (`CharacterOptions::default`):
/// the regressed joints.
pub(crate) const LOAD_SKELETON: SkeletonKind = SkeletonKind::Regressor;

/// The rig, frame and skeleton caches a default load (`Character::load`)
/// reads, made current for the database `dir` whose sequences have `lens`
/// frames (the manifest's order): the rig embedded (or read from its cache)
/// on the same frames a load's takes, then every sequence streamed once into
/// the frame and skeleton caches ([`open_or_build`]). `db build` runs this
/// while it compares frames (issue 43, session 44): the sequences' second
/// reading and the 2.4 GB frame cache's write at 10⁴ frames of 10K
/// vertices, mostly waiting on the disk, overlap the comparison instead of
/// following the graph. Caches already current are only checked.
pub(crate) fn prepare_frame_caches(
    dir: &Path,
    manifest: &Manifest,
    lens: &[usize],
) -> Result<(), DbError> {
    let topology = manifest.load_topology(dir)?;
    let (rig, _) = super::rig_cache::embed_rig_cached(dir, manifest, &topology, Some(lens))?;
    open_or_build(&CacheInputs {
        dir,
        manifest,
        rig: &rig,
        n: topology.vertex_count(),
        count: lens.iter().sum(),
        conv: Conversion::of(manifest),
        kind: LOAD_SKELETON,
    })?;
    Ok(())
}

/// The frames and skeletons of the database `inp.dir`: from the cache
/// when current, else streamed from the sequences (one at a time) into the
/// cache and mapped. A cache that cannot be used is rebuilt with a warning
/// naming it and why. Also returns the skeleton cache's key (the frames,
/// the rig and the kind: what a cache derived from both depends on).
pub(crate) fn open_or_build(inp: &CacheInputs) -> Result<(FrameStore, Vec<Pose>, u64), DbError> {
    let CacheInputs {
        dir,
        manifest: m,
        rig,
        n,
        count,
        conv,
        kind,
    } = *inp;
    let (fkey, pkey) = keys(dir, m, conv.metres_per_unit, kind)?;
    let fpath = frames_path(dir);
    let ppath = poses_path(dir, kind);
    let store = open_logged(FrameStore::open(&fpath, fkey, n, count));
    let cached_poses = open_logged(read_poses(&ppath, pkey, count));
    let (write_frames, cached_poses) = match (store, cached_poses) {
        (Some(store), Some(poses)) => return Ok((store, poses, pkey)),
        // A mapped store not used is unmapped here, before it is rewritten.
        (store, poses) => (store.is_none(), poses),
    };
    let measured = stream(inp, write_frames.then_some((&fpath, fkey)))?;
    let poses = match cached_poses {
        Some(p) => p,
        None => {
            let p = finish_poses(rig, measured, kind, conv);
            save_poses(&ppath, pkey, &p).map_err(|e| DbError::cache_write(dir, e))?;
            p
        }
    };
    let store = FrameStore::open(&fpath, fkey, n, count).map_err(|e| DbError::Manifest {
        path: dir.join(MANIFEST),
        msg: format!("the frame cache just written cannot be read: {e}"),
    })?;
    Ok((store, poses, pkey))
}

/// `Some` of a usable cache; `None` with a warning naming the file when it
/// is there but cannot be used, silently when it is missing.
fn open_logged<T>(r: Result<T, FrameCacheError>) -> Option<T> {
    match r {
        Ok(v) => Some(v),
        Err(FrameCacheError::Io { source, .. })
            if source.kind() == std::io::ErrorKind::NotFound =>
        {
            None
        }
        Err(e) => {
            tracing::warn!("{e}; rebuilding it from the sequences");
            None
        }
    }
}

/// Reads every sequence once, in order: writes the frame cache (when
/// `frames` names it) and returns each frame's measured skeleton (file
/// units; the rigid kind's measurement is the regressor's).
fn stream(inp: &CacheInputs, frames: Option<(&PathBuf, u64)>) -> Result<Vec<Pose>, DbError> {
    let CacheInputs {
        dir,
        manifest: m,
        rig,
        n,
        count,
        conv,
        kind,
    } = *inp;
    let measure_kind = match kind {
        SkeletonKind::Rigid => SkeletonKind::Regressor,
        k => k,
    };
    let mut measured = Vec::with_capacity(count);
    let mut each = |w: Option<&mut dyn std::io::Write>, lows: &mut Vec<f64>| {
        let mut w = w;
        let mut total = 0usize;
        for s in &m.sequences {
            let seq = m.load_sequence(dir, s)?;
            if seq.mesh().vertex_count() != n {
                return Err(DbError::Manifest {
                    path: dir.join(MANIFEST),
                    msg: format!(
                        "sequence '{}': vertex count differs from the topology",
                        s.name
                    ),
                });
            }
            let file_frames = seq.all_positions();
            total += file_frames.len() / n.max(1);
            measured.extend(poses(rig, file_frames, n, measure_kind));
            if let Some(w) = w.as_deref_mut() {
                let mut bytes = Vec::with_capacity(n * 24);
                for f in file_frames.chunks_exact(n.max(1)) {
                    bytes.clear();
                    let mut low = f64::INFINITY;
                    for p in f {
                        let q = conv.point(*p);
                        low = low.min(q[1]);
                        for c in q {
                            bytes.extend_from_slice(&c.to_le_bytes());
                        }
                    }
                    lows.push(low);
                    w.write_all(&bytes)
                        .map_err(|e| DbError::Io(fs(&frames_path(dir), e)))?;
                }
            }
        }
        if total != count {
            return Err(DbError::Manifest {
                path: dir.join(MANIFEST),
                msg: "the sequences changed while loading; run `surfmotion db build` again".into(),
            });
        }
        Ok(())
    };
    match frames {
        None => each(None, &mut Vec::new())?,
        Some((path, key)) => {
            let mut failed = None;
            let written = write_atomic(path, |w| {
                w.write_all(FRAMES_MAGIC)?;
                for v in [key, n as u64, count as u64] {
                    w.write_all(&v.to_le_bytes())?;
                }
                w.write_all(&[0u8; HEADER - 32])?;
                let mut lows = Vec::with_capacity(count);
                if let Err(e) = each(Some(w), &mut lows) {
                    failed = Some(e);
                    return Err(std::io::Error::other("reading the sequences failed"));
                }
                for l in lows {
                    w.write_all(&l.to_le_bytes())?;
                }
                Ok(())
            });
            if let Some(e) = failed {
                return Err(e);
            }
            written.map_err(|e| DbError::cache_write(dir, e))?;
        }
    }
    Ok(measured)
}

fn fs(path: &Path, source: std::io::Error) -> FsError {
    FsError {
        path: path.to_path_buf(),
        source,
    }
}

/// The skeletons of `kind` from the measured ones (the rigid skeleton is
/// calibrated over all of them), converted to metres, Y-up.
fn finish_poses(
    rig: &Embedding,
    measured: Vec<Pose>,
    kind: SkeletonKind,
    conv: Conversion,
) -> Vec<Pose> {
    let file_units = match kind {
        SkeletonKind::Rigid => {
            let (_, fits) = rigid_fit(rig, &[&measured]);
            fits.into_iter().flatten().map(|f| f.pose).collect()
        }
        _ => measured,
    };
    file_units.into_iter().map(|p| conv.pose(p)).collect()
}

fn save_poses(path: &Path, key: u64, poses: &[Pose]) -> Result<(), FsError> {
    write_atomic(path, |w| {
        w.write_all(POSES_MAGIC)?;
        for v in [key, poses.len() as u64, JOINTS as u64] {
            w.write_all(&v.to_le_bytes())?;
        }
        let mut bytes = Vec::with_capacity(poses.len() * JOINTS * 24);
        for p in poses {
            for j in p {
                for c in j.to_array() {
                    bytes.extend_from_slice(&c.to_le_bytes());
                }
            }
        }
        w.write_all(&bytes)
    })
}

/// Reads the skeleton cache `path` of `key` and `count` frames.
pub fn read_poses(path: &Path, key: u64, count: usize) -> Result<Vec<Pose>, FrameCacheError> {
    let (io, header) = (
        FrameCacheError::io_at(path),
        FrameCacheError::header_at(path),
    );
    let len = std::fs::metadata(path).map_err(io)?.len();
    let expected = poses_len(count);
    if len != expected {
        return Err(FrameCacheError::Length {
            path: path.to_path_buf(),
            len,
            expected,
        });
    }
    let bytes = std::fs::read(path).map_err(io)?;
    if &bytes[..8] != POSES_MAGIC {
        return Err(header(
            "not a skeleton cache file (no SMPOS001 header)".into(),
        ));
    }
    let word = |k: usize| u64::from_le_bytes(bytes[k..k + 8].try_into().unwrap_or([0; 8]));
    if word(8) != key || word(16) != count as u64 || word(24) != JOINTS as u64 {
        return Err(header(
            "made from other inputs (another key or size)".into(),
        ));
    }
    let f = |k: usize| f64::from_le_bytes(bytes[k..k + 8].try_into().unwrap_or([0; 8]));
    Ok((0..count)
        .map(|i| {
            std::array::from_fn(|j| {
                let at = 32 + (i * JOINTS + j) * 24;
                DVec3::new(f(at), f(at + 8), f(at + 16))
            })
        })
        .collect())
}

/// A frame or skeleton cache file's header, read and checked against the
/// file's own length (`inspect` of the file: [`read_frames_head`],
/// [`read_poses_head`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct CacheHead {
    /// The key it was written under.
    pub key: u64,
    /// Frames it holds.
    pub frames: u64,
    /// Vertices per frame (frame cache) or joints per pose (skeleton cache).
    pub per_frame: u64,
    /// Its length in bytes (the length its header needs).
    pub bytes: u64,
}

/// The first `n` bytes of `path` (fewer when shorter), with its length.
fn head_of(path: &Path, n: usize) -> Result<(Vec<u8>, u64), FrameCacheError> {
    let io = FrameCacheError::io_at(path);
    let f = std::fs::File::open(path).map_err(io)?;
    let len = f.metadata().map_err(io)?.len();
    let mut b = Vec::with_capacity(n);
    f.take(n as u64).read_to_end(&mut b).map_err(io)?;
    Ok((b, len))
}

/// The header of the frame cache `path`: its magic, then its length
/// against the frames and vertices it declares (a file cut short, or of
/// another kind, is an error naming it). The frames themselves are not
/// read ([`verify_frames`]).
pub(crate) fn read_frames_head(path: &Path) -> Result<CacheHead, FrameCacheError> {
    let (b, len) = head_of(path, 32)?;
    if b.len() < 8 || &b[..8] != FRAMES_MAGIC {
        return Err(FrameCacheError::header_at(path)(
            "not a frame cache file (no SMFRM001 header)".into(),
        ));
    }
    if b.len() < 32 {
        return Err(FrameCacheError::Length {
            path: path.to_path_buf(),
            len,
            expected: HEADER as u64,
        });
    }
    let word = |k: usize| u64::from_le_bytes(b[k..k + 8].try_into().unwrap_or([0; 8]));
    let (key, n, count) = (word(8), word(16), word(24));
    // Checked: a header of huge counts is a damaged file, not an overflow.
    let expected = n
        .checked_mul(count)
        .and_then(|v| v.checked_mul(24))
        .and_then(|v| v.checked_add(count.checked_mul(8)?))
        .and_then(|v| v.checked_add(HEADER as u64))
        .ok_or_else(|| {
            FrameCacheError::header_at(path)(format!(
                "{count} frames of {n} vertices: not a size a frame cache can have"
            ))
        })?;
    sized(
        path,
        CacheHead {
            key,
            frames: count,
            per_frame: n,
            bytes: len,
        },
        expected,
    )
}

/// Every frame of the frame cache `path` (header `head`, from
/// [`read_frames_head`]) read once: each position finite and each frame's
/// stored lowest point its positions' lowest Y (bit for bit), so that a
/// file changed after it was written (a lowered point, bytes that are not
/// numbers) is an error naming it and the frame. Pages are released as
/// it goes. A changed coordinate that keeps the frame's lowest point and
/// stays finite is not seen (the file carries no checksum).
pub(crate) fn verify_frames(path: &Path, head: &CacheHead) -> Result<(), FrameCacheError> {
    let (n, count) = (head.per_frame as usize, head.frames as usize);
    let store = FrameStore::open(path, head.key, n, count)?;
    let header = FrameCacheError::header_at(path);
    for i in 0..count {
        let id = FlatFrame::from_index(i);
        let f = store.frame(id);
        if let Some(v) = f.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(header(format!(
                "frame {i}, vertex {v}: a coordinate that is not a finite number (changed after it was written)"
            )));
        }
        let (low, stored) = (lowest(f), store.lowest(id));
        if low.to_bits() != stored.to_bits() {
            return Err(header(format!(
                "frame {i}: its lowest point {low} m is not the {stored} m stored with it (changed after it was written)"
            )));
        }
        if (i + 1) % 256 == 0 || i + 1 == count {
            store.release(i + 1 - ((i % 256) + 1), (i % 256) + 1);
        }
    }
    Ok(())
}

/// The header of the skeleton cache `path`: its magic and joints per pose,
/// then its length against the poses it declares.
pub(crate) fn read_poses_head(path: &Path) -> Result<CacheHead, FrameCacheError> {
    let (b, len) = head_of(path, 32)?;
    let header = FrameCacheError::header_at(path);
    if b.len() < 8 || &b[..8] != POSES_MAGIC {
        return Err(header(
            "not a skeleton cache file (no SMPOS001 header)".into(),
        ));
    }
    if b.len() < 32 {
        return Err(FrameCacheError::Length {
            path: path.to_path_buf(),
            len,
            expected: 32,
        });
    }
    let word = |k: usize| u64::from_le_bytes(b[k..k + 8].try_into().unwrap_or([0; 8]));
    let (key, count, joints) = (word(8), word(16), word(24));
    if joints != JOINTS as u64 {
        return Err(header(format!(
            "{joints} joints a pose, where a skeleton cache has {JOINTS}"
        )));
    }
    let expected = count
        .checked_mul(JOINTS as u64 * 24)
        .and_then(|v| v.checked_add(32))
        .ok_or_else(|| {
            header(format!(
                "{count} poses: not a size a skeleton cache can have"
            ))
        })?;
    sized(
        path,
        CacheHead {
            key,
            frames: count,
            per_frame: joints,
            bytes: len,
        },
        expected,
    )
}

/// `head` when the file's length (`head.bytes`) is the `expected` one its
/// header declares; else the length error naming the file.
fn sized(path: &Path, head: CacheHead, expected: u64) -> Result<CacheHead, FrameCacheError> {
    if head.bytes != expected {
        return Err(FrameCacheError::Length {
            path: path.to_path_buf(),
            len: head.bytes,
            expected,
        });
    }
    Ok(head)
}

/// The skeleton kind of a skeleton cache file named as
/// [`poses_path`] names it (`poses-regressor.bin`, ...).
pub(crate) fn poses_kind_of(path: &Path) -> Option<SkeletonKind> {
    let name = path.file_name()?.to_str()?;
    let kind = name.strip_prefix("poses-")?.strip_suffix(".bin")?;
    [
        SkeletonKind::Rigid,
        SkeletonKind::Regressor,
        SkeletonKind::Centroid,
    ]
    .into_iter()
    .find(|&k| kind_name(k) == kind)
}

/// The name of a skeleton kind in its cache file's name.
pub(crate) fn skeleton_kind_name(kind: SkeletonKind) -> &'static str {
    kind_name(kind)
}
