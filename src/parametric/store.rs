//! The parametric model's cache file, `DIR/cache/parametric.bin`, written
//! by `db build` and read by `play` until an input changes.
//!
//! Format (little-endian): magic `SMPAR001`, key `u64` (xxh3 of the frames'
//! inputs, the `[[space]]` entries and the options), the length `u64` and
//! bytes of a JSON header (spaces without their reference blocks, tables
//! without their values), then every space's reference blocks and every
//! table's values as `u64` counts of f32. On load every count is checked
//! against the header before anything is allocated, and every value must
//! be finite (similarities in `[0, 1]`); a file that fails is rebuilt with
//! a warning.

use super::ParamError;
use super::space::{Motion, MotionOptions, MotionSpace, SpaceParts};
use super::transition::SimilarityTable;
use crate::db::cache::{KeyHasher, cache_dir, frames_key};
use crate::db::{DbError, Manifest};
use crate::util::fsutil::write_atomic;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"SMPAR001";
/// Bump when the model's algorithm or layout changes (old caches are rebuilt).
pub(crate) const FORMAT_VERSION: u32 = 4;

/// The cache file of a database's parametric model.
pub fn cache_path(dir: &Path) -> PathBuf {
    cache_dir(dir).join("parametric.bin")
}

#[derive(Deserialize)]
struct Header {
    fps: f64,
    spaces: Vec<SpaceParts>,
    tables: Vec<SimilarityTable>,
    options: MotionOptions,
}

/// The cache key of a database's model.
pub fn key(dir: &Path, m: &Manifest, opts: &MotionOptions) -> Result<u64, DbError> {
    let mut h: KeyHasher = frames_key(dir, m)?;
    h.text("units", &m.units);
    h.text("parametric", &FORMAT_VERSION.to_string());
    h.text(
        "spaces",
        &serde_json::to_string(&m.spaces).unwrap_or_default(),
    );
    h.text("options", &serde_json::to_string(opts).unwrap_or_default());
    Ok(h.finish())
}

/// Writes the model with its key, atomically.
pub fn save(path: &Path, key: u64, motion: &Motion) -> Result<(), ParamError> {
    let header = serde_json::to_vec(&HeaderRef {
        fps: motion.fps,
        spaces: &motion.spaces,
        tables: &motion.tables,
        options: &motion.options,
    })
    .map_err(|e| DbError::Manifest {
        path: path.to_path_buf(),
        msg: e.to_string(),
    })?;
    write_atomic(path, |w| {
        w.write_all(MAGIC)?;
        w.write_all(&key.to_le_bytes())?;
        w.write_all(&(header.len() as u64).to_le_bytes())?;
        w.write_all(&header)?;
        let mut put = |v: &[f32]| -> std::io::Result<()> {
            w.write_all(&(v.len() as u64).to_le_bytes())?;
            for x in v {
                w.write_all(&x.to_le_bytes())?;
            }
            Ok(())
        };
        for s in &motion.spaces {
            for b in &s.blend().blocks {
                put(b)?;
            }
        }
        for t in &motion.tables {
            put(&t.sim)?;
        }
        Ok(())
    })?;
    Ok(())
}

#[derive(Serialize)]
struct HeaderRef<'a> {
    fps: f64,
    spaces: &'a [MotionSpace],
    tables: &'a [SimilarityTable],
    options: &'a MotionOptions,
}

/// Parses a cache file's bytes for `key` against the topology (`n`
/// vertices) and the options `opts` the key was made with; `Err(reason)`
/// when it is stale or malformed. A key does not make the contents right
/// (issue 46, item 6: a header whose block index said 10¹², or whose
/// transition depth said 10⁹, with its key intact, made `play` abort on a
/// 24 TB allocation): the options must be `opts`, the frame rate a rate
/// ([`crate::util::budget::is_frame_rate`]), every count must fit the bytes that
/// follow, every index its array and every weight `[0, 1]`, in order.
pub fn parse(
    bytes: &[u8],
    key: u64,
    topology: &crate::mesh::Mesh,
    opts: &MotionOptions,
) -> Result<Motion, String> {
    let mut r = Cursor { bytes, at: 0 };
    let (header, hl) = read_header(&mut r, key, opts)?;
    let n = topology.vertex_count();
    // What is left after the header: every block below must fit it.
    let body = bytes.len().saturating_sub(24 + hl);
    let spaces = header
        .spaces
        .into_iter()
        .map(|s| read_space_blocks(&mut r, s, n, body))
        .collect::<Result<Vec<_>, _>>()?;
    let mut tables = header.tables;
    read_tables(&mut r, &mut tables, &spaces, body)?;
    Ok(Motion {
        fps: header.fps,
        topology: topology.clone(),
        spaces,
        tables,
        options: header.options,
    })
}

/// A read position in a cache file's bytes; every read is checked against
/// the end.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    /// The next `k` bytes.
    fn take(&mut self, k: usize) -> Result<&'a [u8], String> {
        let s = self
            .bytes
            .get(self.at..self.at.checked_add(k).ok_or("size overflow")?)
            .ok_or("truncated")?;
        self.at += k;
        Ok(s)
    }

    /// A block of `expect` finite `f32` values after its count; `what` names
    /// it in the error.
    fn floats(&mut self, expect: usize, what: &str) -> Result<Vec<f32>, String> {
        let len = usize::try_from(u64_of(self.take(8)?)).map_err(|_| "count")?;
        if len != expect {
            return Err(format!("{what}: {len} values, expected {expect}"));
        }
        let body = self.take(len.checked_mul(4).ok_or("size overflow")?)?;
        let v: Vec<f32> = body
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        if v.iter().any(|x| !x.is_finite()) {
            return Err(format!("{what}: a value that is not finite"));
        }
        Ok(v)
    }
}

/// A little-endian `u64` (0 for fewer than 8 bytes).
fn u64_of(b: &[u8]) -> u64 {
    u64::from_le_bytes(b.try_into().unwrap_or([0; 8]))
}

/// Step 1 of [`parse`]: the magic, the key, the JSON header (its frame rate
/// a rate and its options `opts`); returns it with its length in bytes.
fn read_header(r: &mut Cursor, key: u64, opts: &MotionOptions) -> Result<(Header, usize), String> {
    if r.take(8)? != MAGIC {
        return Err("not a parametric cache".into());
    }
    if u64_of(r.take(8)?) != key {
        return Err("stale (inputs changed)".into());
    }
    let hl = usize::try_from(u64_of(r.take(8)?)).map_err(|_| "header size")?;
    let header: Header = serde_json::from_slice(r.take(hl)?).map_err(|e| format!("header: {e}"))?;
    if !crate::util::budget::is_frame_rate(header.fps) {
        return Err(format!(
            "frame rate {} (expected {}-{} fps)",
            crate::util::numfmt::Short(header.fps),
            crate::util::budget::MIN_FPS,
            crate::util::budget::MAX_FPS
        ));
    }
    if header.options != *opts {
        return Err(format!(
            "its options ({}) are not the ones its key was made with ({})",
            serde_json::to_string(&header.options).unwrap_or_default(),
            serde_json::to_string(opts).unwrap_or_default()
        ));
    }
    Ok((header, hl))
}

/// Step 2 of [`parse`], per space: its parts checked
/// ([`SpaceParts::check`]), its reference blocks (a phase grid of `n`
/// vertices each, every count checked against the `body` bytes after the
/// header before anything is allocated), then the space made from both
/// ([`MotionSpace::new`]).
fn read_space_blocks(
    r: &mut Cursor,
    s: SpaceParts,
    n: usize,
    body: usize,
) -> Result<MotionSpace, String> {
    let named = |e: String| format!("space '{}': {e}", s.name);
    let k = s.alignment.grid;
    let per_block = k
        .checked_mul(n)
        .and_then(|x| x.checked_mul(3))
        .filter(|&x| x > 0 && x <= body / 4)
        .ok_or_else(|| named(format!("a phase grid of {k} samples does not fit the file")))?;
    let blocks = s
        .pairs
        .iter()
        .flat_map(|p| p.blocks.iter().copied())
        .max()
        .map_or(1, |b| b.saturating_add(1))
        .max(s.sequences.len());
    // Each block is a count and its values: more than the bytes left
    // can hold is a lie, refused before anything is allocated for it.
    if blocks > body / (8 + 4 * per_block) {
        return Err(named(format!(
            "{blocks} reference blocks of {per_block} values do not fit the file"
        )));
    }
    s.check().map_err(named)?;
    let mut out = Vec::with_capacity(blocks);
    for b in 0..blocks {
        out.push(r.floats(per_block, &named(format!("block {b}")))?);
    }
    let blend = super::hybrid::HybridBlend {
        n,
        grid: k,
        blocks: out,
        pairs: s.pairs.clone(),
    };
    let name = s.name.clone();
    MotionSpace::new(s, blend).map_err(|e| format!("space '{name}': {e}"))
}

/// Step 3 of [`parse`]: the similarity tables, one per ordered pair of
/// `spaces` (their sizes matching the spaces' grids and the `body` bytes),
/// every similarity in `[0, 1]`.
fn read_tables(
    r: &mut Cursor,
    tables: &mut [SimilarityTable],
    spaces: &[MotionSpace],
    body: usize,
) -> Result<(), String> {
    if tables.len() != spaces.len() * spaces.len() {
        return Err("table count".into());
    }
    for (i, t) in tables.iter_mut().enumerate() {
        let (src, tgt) = (&spaces[i / spaces.len()], &spaces[i % spaces.len()]);
        let diagonal = i / spaces.len() == i % spaces.len();
        let sorted =
            |u: &[f64]| u.windows(2).all(|w| w[0] <= w[1]) && u.iter().all(|x| x.is_finite());
        let consistent = if diagonal {
            t.ks == 0 && t.kt == 0
        } else {
            t.ks == src.alignment().grid && t.kt == tgt.alignment().grid
        };
        let expect =
            t.us.len()
                .checked_mul(t.ut.len())
                .and_then(|x| x.checked_mul(t.ks))
                .and_then(|x| x.checked_mul(t.kt))
                .filter(|&x| x <= body / 4);
        let Some(expect) = expect.filter(|_| consistent && sorted(&t.us) && sorted(&t.ut)) else {
            return Err(format!(
                "similarity table {i}: {} × {} references and {} × {} phase samples do not match its spaces or the file",
                t.us.len(),
                t.ut.len(),
                t.ks,
                t.kt
            ));
        };
        t.sim = r.floats(expect, "similarity table")?;
        if t.sim.iter().any(|x| !(0.0..=1.0).contains(x)) {
            return Err("a similarity outside [0, 1]".into());
        }
    }
    Ok(())
}

/// The model of the database in `dir`: from the cache when current, else
/// built and cached. Returns the model and whether it came from the cache.
/// Errors when the manifest declares no space.
pub fn load_or_build(
    dir: &Path,
    opts: &MotionOptions,
    force: bool,
) -> Result<(Motion, bool), ParamError> {
    let m = Manifest::load(dir)?;
    m.require_spaces(dir)?;
    let key = key(dir, &m, opts)?;
    let path = cache_path(dir);
    if !force && let Ok(bytes) = crate::util::fsutil::read_bytes(&path) {
        match read_cached(dir, &m, &bytes, key, opts)? {
            Ok(motion) => return Ok((motion, true)),
            Err(why) => {
                if !why.starts_with("stale") {
                    tracing::warn!("{}: {why}; rebuilding the parametric model", path.display());
                }
            }
        }
    }
    let motion = Motion::build(dir, &m, opts)?;
    save(&path, key, &motion)?;
    Ok((motion, false))
}

/// The model in a cache file's `bytes` for the database in `dir` (manifest
/// `m`), its `key` and `opts`: `Ok(Err(why))` when the file is stale or
/// cannot be trusted ([`parse`], and a frame rate other than the
/// database's), `Err` when the database itself does not load.
fn read_cached(
    dir: &Path,
    m: &Manifest,
    bytes: &[u8],
    key: u64,
    opts: &MotionOptions,
) -> Result<Result<Motion, String>, ParamError> {
    let topo = metres_topology(dir, m)?;
    Ok(parse(bytes, key, &topo, opts).and_then(|motion| {
        // The model plays at the database's rate: a cache that says
        // otherwise is not the database's (a corrupt rate made `play`
        // blame its output: "18446744073709551615 frames do not fit").
        if motion.fps == m.fps {
            Ok(motion)
        } else {
            Err(format!(
                "frame rate {} fps, the database's is {} fps",
                crate::util::numfmt::Short(motion.fps),
                crate::util::numfmt::Short(m.fps)
            ))
        }
    }))
}

/// Checks the cache file at `path` of the database in `dir` as `play`
/// would before trusting it (`inspect` of the cache): `Ok(())` when `play`
/// would use it with the default options, else why not ("stale ..." for a
/// file of other inputs).
pub(crate) fn check_file(dir: &Path, m: &Manifest, path: &Path) -> Result<(), String> {
    let opts = MotionOptions::default();
    let key = key(dir, m, &opts).map_err(|e| e.to_string())?;
    let bytes = crate::util::fsutil::read_bytes(path).map_err(|e| e.to_string())?;
    read_cached(dir, m, &bytes, key, &opts)
        .map_err(|e| e.to_string())?
        .map(|_| ())
}

/// The topology in metres, Y-up.
fn metres_topology(dir: &Path, m: &Manifest) -> Result<crate::mesh::Mesh, ParamError> {
    let mpu = crate::mocap::units::parse_unit(&m.units)
        .map(|u| u.metres_per_unit)
        .unwrap_or(1.0);
    let z_up = m.up.eq_ignore_ascii_case("z");
    let t = m.load_topology(dir)?;
    let p: Vec<[f64; 3]> = t
        .positions()
        .iter()
        .map(|p| (crate::similarity::y_up(*p, z_up) * mpu).to_array())
        .collect();
    Ok(t.with_positions(&p)
        .map_err(crate::mesh::MeshError::from)
        .map_err(DbError::from)?)
}
