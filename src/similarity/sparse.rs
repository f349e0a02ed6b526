//! The sparse similarity of a large database (issue 43): the full shape
//! measure only on the frame pairs that can hold a transition, found
//! without forming the `n²` matrix.
//!
//! 1. **Cheap descriptors**: the rotation-invariant magnitudes of each
//!    frame's histogram spectra ([`super::histogram::magnitudes`], 550
//!    values whose distance is at most the Eq. 1 distance), projected on
//!    their [`SparseOptions::dims`] principal axes (fitted on at most
//!    [`PCA_SAMPLE`] frames).
//! 2. **Candidate pairs** ([`super::candidates`], one exact k-d tree over
//!    all frames in that space): the [`SparseOptions::neighbours`] nearest
//!    frames of every frame, leaving out the frame's own neighbourhood
//!    within its sequence (closer than `min_gap` frames: not a
//!    transition); every [`SparseOptions::stride`]-th frame's
//!    [`SparseOptions::per_sequence`] nearest frames in each sequence (one
//!    tree per sequence: `n × sequences` candidates; or, an option since
//!    session 28, among its [`SparseOptions::pool`] nearest overall); and
//!    the centres of
//!    the [`SparseOptions::per_pair`] best transitions of every sequence
//!    pair ([`super::pair_scan`]: the graph keeps the best transitions of
//!    every sequence pair, also between dissimilar motions), examined
//!    from the [`SparseOptions::rerank`] best by the cheap distances and
//!    re-ranked by the full measure, each with its neighbours
//!    [`SparseOptions::spread`] frames either way along the other
//!    sequence.
//! 3. **Windows**: for each candidate `(a, b)` the full measure along the
//!    diagonal `(a+t, b+t)`, `|t| ≤ band`, and the two diagonals either
//!    side of it (what the transition search reads: its window and the
//!    8-neighbour minimum test, whose anti-diagonal neighbours lie two
//!    diagonals away), merged into runs along each diagonal; plus every
//!    frame's next and next-but-one frame (the retrieval's step costs).
//!    Stored both ways, row by row (a compressed sparse row matrix).
//!
//! Work and memory grow as `n · neighbours · band` pairs plus
//! `per_pair · band` pairs per sequence pair (plus the k-d tree's
//! `n log n` and the cheap scan's `n²` distances of `dims` values each),
//! not `n²` full measures. A pair that is not stored reads as
//! [`SparseSimilarity::get`]'s estimate: at least both frames' neighbour
//! radius (the largest full distance to their own candidates) and the
//! cheap descriptors' distance.

use super::candidates::{CandidateOptions, index_candidates, process_cpu_seconds, sequence_of};
use super::matrix::{Dissimilarity, PairDistance, Span};
use super::pair_scan;
use super::tiled::{self, Run};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// Bytes [`SparseSimilarity::write_to`] gathers before each write.
const WRITE_CHUNK: usize = 1 << 16;

/// Frames the principal axes are fitted on (evenly spaced).
pub(crate) const PCA_SAMPLE: usize = 2048;

/// Progress of [`sparse_pairs`]: each stage whose size is known before it
/// runs begins with its name and total ([`SparseProgress::stage`]), then
/// advances by the steps done. A closure `Fn(u64)` takes the steps alone.
pub trait SparseProgress: Sync {
    /// A stage of `total` steps begins: the sequence-pair scan (cheap
    /// distances, [`pair_scan::scan_total`]), then the full measure on the
    /// stored pairs (their count).
    fn stage(&self, _what: &str, _total: u64) {}
    /// `k` more steps of the stage are done.
    fn advance(&self, k: u64);
}

impl<F: Fn(u64) + Sync> SparseProgress for F {
    fn advance(&self, k: u64) {
        self(k)
    }
}

/// A set of frames with a cheap descriptor besides its full measure.
pub trait Features: PairDistance {
    /// Values of a frame's descriptor.
    fn feature_len(&self) -> usize;
    /// Writes frame `a`'s descriptor into `out` (`feature_len` values).
    fn feature(&self, a: usize, out: &mut [f32]);
}

/// Options of [`sparse_pairs`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SparseOptions {
    /// Candidate frames per frame (nearest by the cheap descriptor).
    /// Default: 24.
    pub neighbours: usize,
    /// Principal axes of the cheap descriptor. Default: 24.
    pub dims: usize,
    /// Half-length of the diagonal evaluated around each candidate: the
    /// transition search's largest half-window plus one. Default: 25.
    pub band: usize,
    /// Within a sequence, frames closer than this are not candidates (the
    /// transition search's `min_gap`). Default: 10.
    pub min_gap: usize,
    /// Besides the nearest frames overall, every `stride`-th frame's
    /// nearest frame in each sequence (the graph keeps the best
    /// transitions of every ordered sequence pair, also of dissimilar
    /// motions, whose frames are nobody's nearest overall). Default: 4.
    pub stride: usize,
    /// Nearest frames in each sequence of every `stride`-th frame: the
    /// dense method's transitions found at 3,234 frames rise from 78.8 %
    /// (1) to 90.8 % (3), 94.5 % (6) and 94.9 % (8), 96.3 % (12) alone;
    /// with the re-ranked per-pair candidates (8 per pair, spread 5) to
    /// 95.4 % (3, re-ranked from 32), 97.2 % (3, from 64), 95.9 % (4-6,
    /// from 32), session 26. Its candidates grow with `n × sequences`.
    /// Default: 3 (with `per_pair` 8 re-ranked from 64; 12 alone before
    /// session 26).
    pub per_sequence: usize,
    /// Where the per-sequence candidates come from: the `pool` nearest
    /// frames of every `stride`-th frame over the whole database (the one
    /// k-d tree of [`SparseOptions::neighbours`]), of which at most
    /// `per_sequence` in each sequence are kept, so that they number at
    /// most `n / stride · pool` whatever the number of sequences
    /// ([`super::candidates`]); 0: one k-d tree per sequence,
    /// `per_sequence` nearest in every sequence (`n / stride · sequences ·
    /// per_sequence` candidates: at 10⁴ frames and 34 sequences 16 M of
    /// the 20.7 M pairs compared). Measured (session 28, the options
    /// harness on the dense caches, with the rest of the default): at
    /// 3,234 frames the dense transitions found fall from 97.2 % (0) to
    /// 93.6 % (64), 95.9 % (128, 256) for 2.25 → 1.21, 1.46, 1.76 M pairs;
    /// at 1,014 frames 100 % → 98.3 % (64), 100 % (128, 256); the 10⁴ build
    /// with 64 compares 6.5 M pairs in 301 s of CPU (702 s with 0). A
    /// recall drop alone (the generated variant database of `db::sparse`:
    /// 91.2 % with 64, 92.3 % with 128 and `rerank` 128, 98.9 % with 0),
    /// so the default since session 29 takes 128 with
    /// [`SparseOptions::cover`]. Default: 128 (0 before session 29).
    pub pool: usize,
    /// With a pool: a sequence pair that fewer than `cover` of the pool's
    /// candidates link (either way) takes the per-sequence trees'
    /// candidates instead, both ways ([`super::candidates`], session 29):
    /// the pool for the sequences a frame is near, the trees for the
    /// pairs no pooled frame reaches (a turned or mirrored piece, a motion
    /// far from every other). 0: the pool's alone. Measured (session 29,
    /// with `pool` 128 and `rerank` 128): dense transitions found at 3,234
    /// frames 97.2 % (0) → 98.2 % (16: its one sequence pair linked once
    /// takes the trees), 1.46 → 1.51 M pairs; at 1,014 frames 100 %; the
    /// variant database of `db::sparse` 92.3 % (0, 1, 4: every pair there
    /// is linked at least 4 times) → 95.6 % (16), 98.9 % (64); at
    /// 10⁴ frames 7.6 → 11.4 M pairs, 352 s of CPU, 96.6 % of the previous
    /// default's transitions at the same frames (92.1 % with 0). Session
    /// 30, cover 32 at 10⁴ frames (main's binary, load ~19): 13.2 M pairs,
    /// 446.3 s of CPU (describe 88.8 s, where session 29's 16 measured
    /// 71.6 s: the load's ~1.24×; full measure 276.9 s against 217.6 s),
    /// 954 MB, 97.5 % of the trees' transitions (16: 96.6 %): over the
    /// 360 s line even scaled for the load (≈ 360-387 s), so 16 stays.
    /// Default: 16.
    pub cover: usize,
    /// Best transitions by the cheap distances per unordered sequence pair
    /// whose centres are candidates ([`super::pair_scan`]); their count
    /// does not grow with the sequences' lengths, but the cheap ranking
    /// misses many of the dense method's near-equal transitions unless
    /// they are re-ranked by the full measure ([`SparseOptions::rerank`];
    /// without `per_sequence`, 8 per pair found 71.1 % of the dense
    /// transitions at 3,234 frames, 84.4 % re-ranked from 32, session 25).
    /// Default: 8, re-ranked from 64 ([`SparseOptions::rerank`]).
    pub per_pair: usize,
    /// Each per-pair candidate also taken `spread` frames either way along
    /// the second sequence (its ±2 diagonals then cover ±(spread + 2)):
    /// for cheap centres, often a few frames off the full measure's; the
    /// re-ranked centres are the full measure's minima. Default: 5 (used
    /// when `per_pair` is on).
    pub spread: usize,
    /// Smallest half-window of the per-pair search (the transition
    /// search's `min_window`). Default: 4.
    pub min_window: usize,
    /// Cheap transitions examined per unordered sequence pair, of which the
    /// full measure keeps the `per_pair` best
    /// ([`pair_scan::best_per_pair_refined`]: each centre descended to the
    /// full measure's local minimum, then the transition search on those
    /// minima); 0: the `per_pair` best by the cheap distances, as they are.
    /// At 3,234 frames (8 per pair, no `per_sequence`) it raises the dense
    /// transitions found from 71.1 % to 84.4 % (32) and 88.5 % (spread 5,
    /// or 32 of 128), short of the 95 % `per_sequence` 12 reaches; with
    /// `per_sequence` 3 and spread 5, 97.2 % from 64 for 2.25 M pairs
    /// (+ 0.16 M re-ranking) where 12 per sequence alone compares 3.27 M
    /// for 96.3 % (session 26), at 110.9 s CPU against 129.8 s for the
    /// whole `db build`. With `pool` 128 at 3,234 frames: 95.9 % from 64,
    /// 97.2 % from 128 (session 28). Session 39, the 3,896-frame prefix of
    /// `scripts/scale-db.sh`'s 2,600-vertex pool (11 sequences, the
    /// options harness on the dense cache): 494 of the dense 524
    /// transitions (94.3 %) from 128, 502 (95.8 %) from 256; with the
    /// [`SparseOptions::closure`] 500 (95.4 %) from 128, 504 (96.2 %)
    /// from 192, 508 (96.9 %) from 256, for 0.57 M full measures of
    /// re-ranking instead of 0.36 M (the stored pairs 2.04 M).
    /// Default: 256 (128 from session 29, 64 before).
    pub rerank: usize,
    /// Sequence pairs per sequence (issue 43, session 33): each sequence
    /// takes the per-pair scan and the cover rule's trees only with itself
    /// and the `reach` other sequences its frames are most linked to by
    /// the index's candidates (its nearest frames and the pool), and a
    /// pair reached by either sequence is scanned
    /// ([`super::candidates::reached_pairs`]): at most `sequences ·
    /// (reach + 1)` pairs scanned instead of `sequences² / 2`, so that the
    /// pairs compared grow with the frames, not with frames × sequences
    /// (session 32: 104.5 M pairs at 3×10⁴ frames, 98 sequences, where
    /// 10⁴ frames compared 11.6 M). A pair not reached keeps only the
    /// transitions its nearest and pooled candidates store. 0 (or at least
    /// the other sequences): every pair, as before session 33. Measured
    /// with 16 (session 33, the 2,600-vertex pool of `scripts/scale-db.sh`):
    /// at 10⁴ frames (34 sequences) 369 of 595 pairs scanned, 7.16 M pairs
    /// compared (11.63 M), 166.5 s of CPU (227.8 s), 66.2 % of the
    /// transitions kept (98 % of the cheapest quarter, every one of the
    /// cheapest tenth; the 02_01 retargets unchanged); at 3×10⁴ (98)
    /// 25.3 M pairs (104.5 M), 562 s. Off by default: a third of the
    /// graph's transitions (dissimilar pairs' best) are lost. Since
    /// session 40 `db build` takes one where the full scan does not fit its
    /// budget ([`SparseOptions::budget_pairs`], [`super::scan`]).
    /// Default: 0.
    pub reach: usize,
    /// With a reach: transitions kept per sequence pair the reach does not
    /// scan, found by the far search ([`pair_scan::best_of_pairs`], issue
    /// 43, session 34): the pair's whole cheap block (the projected
    /// descriptors' distance, `dims` multiply-adds a frame pair), its
    /// [`SparseOptions::far_rerank`] best cheap transitions each descended
    /// to the full measure's local minimum, and the `far` best of those by
    /// the window cost (Eq. 3) stored with their windows: the centre's
    /// diagonal `band` frames either way, the two diagonals either side
    /// only at the centre (the 8-neighbour minimum test). So the graph's
    /// best `top_n` of every ordered pair (Sec. 4.2), dissimilar ones
    /// included, are kept for a few thousand full measures per pair. 0:
    /// the far pairs keep only what their nearest and pooled candidates
    /// store (session 33). Measured (session 34, the 2,600-vertex pool of
    /// `scripts/scale-db.sh`, against main's graph at 10⁴ frames, 34
    /// sequences, reach 16): 66.2 % of the transitions kept at the same
    /// frames and costs without it, 88.2 % with 6 of 16 (2.6 s of CPU
    /// more: 163 K full measures and 59 K stored pairs on the 226 far
    /// pairs), 93.1 % with 8 of 128 (823 K full measures); every ordered
    /// pair keeps transitions (188 had none). At 3,896 frames (11
    /// sequences, reach 3) against the dense graph: 70.6 % → 85.5 % (6 of
    /// 16), 89.7 % (8 of 128); main's default 94.3 %. The misses are
    /// near-ties: the transition kept instead lies a median 12-26 frames
    /// away at +0.8-1.5 % of the cost. Default: 6.
    pub far: usize,
    /// Cheap transitions examined per far pair ([`SparseOptions::far`]);
    /// at least `far`. Default: 16.
    pub far_rerank: usize,
    /// Rounds of the closure ([`super::closure`], issue 43, session 39):
    /// each sequence pair's best `per_pair` transitions on the stored
    /// pairs that the stored pairs cannot vouch for (a neighbour or a
    /// window pair not stored: a minimum only because its smaller
    /// neighbour is missing, at the edge of a re-timed copy's slanted
    /// valley) are descended on the full measure to a true minimum, whose
    /// runs are stored; then the search runs again (nothing without
    /// `per_pair`). 0: none (before session 39). On the 3,896-frame
    /// prefix of the 2,600-vertex pool (session 39, the options harness):
    /// the dense transitions found 494 → 500 of 524 (1 round or 3) for
    /// 953 / 1,483 more stored pairs (of 2.04 M); with `rerank` 256
    /// 502 → 508. Default: 3.
    pub closure: usize,
    /// The scan's budget, millions of full measures (issue 43, session
    /// 40): `db build` keeps the full scan (every sequence pair) when
    /// [`super::scan::estimate`] says it fits this and
    /// [`SparseOptions::budget_memory`], else takes the largest
    /// [`SparseOptions::reach`] of at least [`super::scan::MIN_REACH`] that
    /// fits ([`super::scan::choose`]; a reach given explicitly wins). Not in
    /// the cache key: the reach it gives is. 250 M full measures are about
    /// 3,100 s of one core at the 12.3 µs a pair measured at 10⁴ frames
    /// (session 32), under half the hour on two cores for 10⁵
    /// frames. 0: no limit. Default: 250.
    pub budget_pairs: usize,
    /// The scan's memory budget, MB (10⁶ bytes): the 8 GB for 10⁵
    /// frames (see [`SparseOptions::budget_pairs`]). 0: no limit.
    /// Default: 8000.
    pub budget_memory: usize,
}

impl Default for SparseOptions {
    fn default() -> Self {
        SparseOptions {
            neighbours: 24,
            dims: 24,
            band: 25,
            min_gap: 10,
            stride: 4,
            per_sequence: 3,
            pool: 128,
            cover: 16,
            per_pair: 8,
            spread: 5,
            min_window: 4,
            rerank: 256,
            reach: 0,
            far: 6,
            far_rerank: 16,
            closure: 3,
            budget_pairs: 250,
            budget_memory: 8000,
        }
    }
}

impl SparseOptions {
    /// The candidate index's options these options give (the index the
    /// build takes its nearest-frame, pool and cover candidates and its
    /// reached sequence pairs from).
    pub fn candidates(&self) -> CandidateOptions {
        CandidateOptions {
            neighbours: self.neighbours,
            stride: self.stride,
            per_sequence: self.per_sequence,
            pool: self.pool,
            cover: self.cover,
            min_gap: self.min_gap,
            reach: self.reach,
        }
    }

    /// These options with `name=value` pairs applied (comma-separated,
    /// names of the fields, e.g. `per_pair=8,rerank=32,per_sequence=0`):
    /// how `db build` takes other options for a measurement
    /// (`SURFMOTION_SPARSE`). `Err` naming the pair that is not an option
    /// or not a count.
    pub fn with_overrides(mut self, text: &str) -> Result<SparseOptions, String> {
        for pair in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (name, value) = pair
                .split_once('=')
                .ok_or_else(|| format!("'{pair}': expected name=value"))?;
            let v: usize = value
                .trim()
                .parse()
                .map_err(|_| format!("'{pair}': the value is not a count"))?;
            let field = match name.trim() {
                "neighbours" => &mut self.neighbours,
                "dims" => &mut self.dims,
                "band" => &mut self.band,
                "min_gap" => &mut self.min_gap,
                "stride" => &mut self.stride,
                "per_sequence" => &mut self.per_sequence,
                "pool" => &mut self.pool,
                "cover" => &mut self.cover,
                "per_pair" => &mut self.per_pair,
                "spread" => &mut self.spread,
                "min_window" => &mut self.min_window,
                "rerank" => &mut self.rerank,
                "reach" => &mut self.reach,
                "far" => &mut self.far,
                "far_rerank" => &mut self.far_rerank,
                "closure" => &mut self.closure,
                "budget_pairs" => &mut self.budget_pairs,
                "budget_memory" => &mut self.budget_memory,
                other => return Err(format!("'{other}' is not a sparse option")),
            };
            *field = v;
        }
        Ok(self)
    }
}

/// What [`sparse_pairs`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SparseStats {
    /// Candidate pairs from the nearest-neighbour index and the per-pair
    /// scan.
    pub candidates: u64,
    /// Of those, every frame's nearest frames overall.
    pub near_candidates: u64,
    /// Of those, the per-sequence nearest frames
    /// ([`SparseOptions::per_sequence`]).
    pub sequence_candidates: u64,
    /// Of those, from the per-pair scan (its seeds and their spread).
    pub pair_candidates: u64,
    /// Distinct pairs the windows of each kind of candidate would compare
    /// alone (nearest overall, per sequence, per pair; without the
    /// successors): what each adds to `pairs`, overlaps counted in each.
    pub pairs_by_source: [u64; 3],
    /// Seconds of the per-pair scan (part of `index_seconds`).
    pub scan_seconds: f64,
    /// Full measures evaluated by the per-pair re-ranking (not stored).
    pub rerank_pairs: u64,
    /// Unordered sequence pairs (a sequence with itself included) the
    /// per-pair scan ran on: every one, or those reached
    /// ([`SparseOptions::reach`]).
    pub sequence_pairs: u64,
    /// Unordered sequence pairs the far search ran on (those not reached,
    /// [`SparseOptions::far`]).
    pub far_sequence_pairs: u64,
    /// Candidate pairs from the far search (in `candidates`, not in
    /// `pair_candidates`; their pairs in `pairs_by_source`'s third).
    pub far_candidates: u64,
    /// Full measures evaluated by the far search's descents and windows
    /// (not stored unless a window is).
    pub far_rerank_pairs: u64,
    /// Closure rounds that found transitions to settle
    /// ([`SparseOptions::closure`]), the true minima they stored, and the
    /// full measures their descents evaluated (stored or not).
    pub closure: [u64; 3],
    /// Distinct pairs evaluated with the full measure.
    pub pairs: u64,
    /// Seconds: descriptors, projection and index.
    pub index_seconds: f64,
    /// Seconds: the full measure on the stored pairs.
    pub pairs_seconds: f64,
    /// CPU seconds of the process (every thread; 0 where the platform does
    /// not say): the projection and the index, the per-pair scan with its
    /// re-ranking, the full measure on the stored pairs.
    pub cpu_seconds: [f64; 3],
}

/// A symmetric dissimilarity stored on some frame pairs only.
#[derive(Debug, Clone)]
pub struct SparseSimilarity {
    /// The sequences, in row order.
    pub spans: Vec<Span>,
    n: usize,
    offsets: Vec<u64>,
    /// The stored pairs' columns and values, row by row.
    pairs: Stored,
    /// Per frame, the largest full distance to its candidates.
    radius: Vec<f32>,
    dims: usize,
    /// Per frame, the projected cheap descriptor (`n × dims`).
    features: Vec<f32>,
}

impl PartialEq for SparseSimilarity {
    fn eq(&self, o: &Self) -> bool {
        self.spans == o.spans
            && self.n == o.n
            && self.offsets == o.offsets
            && self.radius == o.radius
            && self.dims == o.dims
            && self.features == o.features
            && self.pairs.len() == o.pairs.len()
            && (0..self.pairs.len()).all(|k| {
                self.pairs.col(k) == o.pairs.col(k)
                    && self.pairs.val(k).to_bits() == o.pairs.val(k).to_bits()
            })
    }
}

/// The stored pairs' columns and values: in memory (a build), or read on
/// demand from the memory-mapped cache file (issue 43: at 10⁴ frames the
/// pairs are 0.5 GB, of which a retarget reads a few).
#[derive(Clone)]
enum Stored {
    /// Columns and values held in memory.
    Owned { cols: Vec<u32>, vals: Vec<f32> },
    /// `len` little-endian `u32` columns from byte `cols` of the map, and
    /// as many `f32` values from byte `vals`.
    Mapped {
        map: std::sync::Arc<memmap2::Mmap>,
        cols: usize,
        vals: usize,
        len: usize,
    },
}

impl std::fmt::Debug for Stored {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stored::Owned { cols, .. } => write!(f, "Owned({} pairs)", cols.len()),
            Stored::Mapped { len, .. } => write!(f, "Mapped({len} pairs)"),
        }
    }
}

impl Stored {
    /// No pairs (held in memory).
    fn empty() -> Stored {
        Stored::Owned {
            cols: Vec::new(),
            vals: Vec::new(),
        }
    }
    fn len(&self) -> usize {
        match self {
            Stored::Owned { cols, .. } => cols.len(),
            Stored::Mapped { len, .. } => *len,
        }
    }
    /// Four bytes of the map at `at` (all ones past its end: a column out
    /// of range, a value that is NaN; the length was checked on opening).
    fn word(map: &memmap2::Mmap, at: usize) -> [u8; 4] {
        map.get(at..at + 4)
            .and_then(|b| b.try_into().ok())
            .unwrap_or([0xff; 4])
    }
    /// The column of stored pair `k`.
    fn col(&self, k: usize) -> u32 {
        match self {
            Stored::Owned { cols, .. } => cols[k],
            Stored::Mapped { map, cols, .. } => u32::from_le_bytes(Self::word(map, cols + 4 * k)),
        }
    }
    /// The value of stored pair `k`.
    fn val(&self, k: usize) -> f32 {
        match self {
            Stored::Owned { vals, .. } => vals[k],
            Stored::Mapped { map, vals, .. } => f32::from_le_bytes(Self::word(map, vals + 4 * k)),
        }
    }
}

/// What [`SparseSimilarity`]'s bytes say before its pairs: where the pairs
/// start (bytes from the start of the bytes read).
struct Head {
    spans: Vec<Span>,
    n: usize,
    dims: usize,
    radius: Vec<f32>,
    features: Vec<f32>,
    offsets: Vec<u64>,
    nnz: usize,
    cols_at: usize,
    vals_at: usize,
}

impl SparseSimilarity {
    /// Number of frames.
    pub fn len(&self) -> usize {
        self.n
    }
    /// True for an empty database.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }
    /// Pairs stored (each unordered pair once).
    pub fn stored_pairs(&self) -> usize {
        self.pairs.len() / 2
    }
    /// True when the pairs are read from a memory-mapped cache file.
    pub fn is_mapped(&self) -> bool {
        matches!(self.pairs, Stored::Mapped { .. })
    }
    /// Lets the system take back the mapped pages read so far (the
    /// process's resident set shrinks; the file stays in the page cache and
    /// a later read maps it again). For a pass over every row (issue 43: at
    /// 10⁴ frames the pairs are 0.5 GB, and a read maps 64 KB around it).
    /// Nothing for pairs held in memory.
    pub fn release(&self) {
        if let Stored::Mapped { map, .. } = &self.pairs {
            // SAFETY: a read-only shared map of the database's own cache
            // file, written atomically (never changed in place): after
            // MADV_DONTNEED a read faults the same bytes in again from the
            // file. No reference into the map is held across this call
            // (columns and values are copied out as they are read).
            #[cfg(unix)]
            let _ = unsafe { map.unchecked_advise(memmap2::UncheckedAdvice::DontNeed) };
            #[cfg(not(unix))]
            let _ = map;
        }
    }
    /// The range of row `a` in the stored pairs.
    fn range(&self, a: usize) -> (usize, usize) {
        (self.offsets[a] as usize, self.offsets[a + 1] as usize)
    }
    /// The first stored pair of `s..e` (a row) whose column is not below
    /// `c` (`e` when none).
    fn lower(&self, mut s: usize, mut e: usize, c: u32) -> usize {
        while s < e {
            let mid = s + (e - s) / 2;
            if self.pairs.col(mid) < c {
                s = mid + 1;
            } else {
                e = mid;
            }
        }
        s
    }
    /// The stored columns and values of row `a`, columns ascending.
    pub fn row(&self, a: usize) -> impl Iterator<Item = (u32, f32)> + '_ {
        let (s, e) = self.range(a);
        (s..e).map(|k| (self.pairs.col(k), self.pairs.val(k)))
    }
    /// The stored dissimilarity of `a` and `b` (0 for `a == b`).
    pub fn stored(&self, a: usize, b: usize) -> Option<f32> {
        if a == b {
            return Some(0.0);
        }
        let (s, e) = self.range(a);
        let k = self.lower(s, e, b as u32);
        (k < e && self.pairs.col(k) == b as u32).then(|| self.pairs.val(k))
    }
    /// The dissimilarity of `a` and `b`: stored, else the estimate of a
    /// pair that is neither frame's candidate: the larger of both frames'
    /// neighbour radius and the distance of their cheap descriptors.
    pub fn get(&self, a: usize, b: usize) -> f32 {
        self.stored(a, b).unwrap_or_else(|| self.estimate(a, b))
    }
    fn estimate(&self, a: usize, b: usize) -> f32 {
        let d = self.dims;
        let fa = &self.features[a * d..(a + 1) * d];
        let fb = &self.features[b * d..(b + 1) * d];
        let lb = fa
            .iter()
            .zip(fb)
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f32>()
            .sqrt();
        lb.max(self.radius[a]).max(self.radius[b])
    }
    /// The stored pairs of sequences `i` (rows) and `j` (columns), as
    /// frame numbers within each, rows then columns ascending.
    pub fn block(&self, i: usize, j: usize) -> Vec<(usize, usize)> {
        let (si, sj) = (&self.spans[i], &self.spans[j]);
        let mut out = Vec::new();
        for r in si.start..si.start + si.len {
            let (s, e) = self.range(r);
            let from = self.lower(s, e, sj.start as u32);
            let to = self.lower(from, e, (sj.start + sj.len) as u32);
            // A column outside the block (a mapped file's columns are not
            // all checked on opening) is left out, never wrapped.
            out.extend((from..to).filter_map(|k| {
                (self.pairs.col(k) as usize)
                    .checked_sub(sj.start)
                    .filter(|&c| c < sj.len)
                    .map(|c| (r - si.start, c))
            }));
        }
        out
    }

    /// The bytes of [`SparseSimilarity::from_bytes`] (little-endian): `n`,
    /// `dims`, sequences (name length, name, start, length), radius,
    /// features, row offsets, columns, values. Written to `w` in pieces of
    /// at most [`WRITE_CHUNK`] bytes (issue 43, session 41: the whole file
    /// as one buffer was a second copy of the stored pairs, 1.6 GB at 10⁵
    /// frames, while the descriptors were still held).
    pub(crate) fn write_to(&self, w: &mut dyn std::io::Write) -> std::io::Result<()> {
        let mut b: Vec<u8> = Vec::with_capacity(WRITE_CHUNK + 64);
        let mut put = |b: &mut Vec<u8>, bytes: &[u8]| -> std::io::Result<()> {
            b.extend_from_slice(bytes);
            if b.len() >= WRITE_CHUNK {
                w.write_all(b)?;
                b.clear();
            }
            Ok(())
        };
        for v in [self.n, self.dims, self.spans.len()] {
            put(&mut b, &(v as u64).to_le_bytes())?;
        }
        for s in &self.spans {
            put(&mut b, &(s.name.len() as u64).to_le_bytes())?;
            put(&mut b, s.name.as_bytes())?;
            put(&mut b, &(s.start as u64).to_le_bytes())?;
            put(&mut b, &(s.len as u64).to_le_bytes())?;
        }
        for v in self.radius.iter().chain(&self.features) {
            put(&mut b, &v.to_le_bytes())?;
        }
        for o in &self.offsets {
            put(&mut b, &o.to_le_bytes())?;
        }
        for k in 0..self.pairs.len() {
            put(&mut b, &self.pairs.col(k).to_le_bytes())?;
        }
        for k in 0..self.pairs.len() {
            put(&mut b, &self.pairs.val(k).to_le_bytes())?;
        }
        w.write_all(&b)
    }

    /// [`SparseSimilarity::write_to`] into memory.
    #[cfg(test)]
    pub(crate) fn to_bytes(&self) -> Vec<u8> {
        let mut b = Vec::new();
        self.write_to(&mut b).expect("writing to memory");
        b
    }

    /// Reads [`SparseSimilarity::write_to`]'s bytes into memory; `Err` naming what
    /// is wrong (truncated, sizes that disagree, a value that is not a
    /// finite distance, a column out of range or out of order).
    pub fn from_bytes(bytes: &[u8]) -> Result<SparseSimilarity, String> {
        let h = Self::head(bytes)?;
        let cols: Vec<u32> = bytes[h.cols_at..h.cols_at + 4 * h.nnz]
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        let vals: Vec<f32> = bytes[h.vals_at..h.vals_at + 4 * h.nnz]
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        for a in 0..h.n {
            let row = &cols[h.offsets[a] as usize..h.offsets[a + 1] as usize];
            if row.windows(2).any(|w| w[0] >= w[1]) || row.iter().any(|&c| c as usize >= h.n) {
                return Err(format!("row {a}: columns out of range or out of order"));
            }
        }
        if !vals.iter().all(|v| v.is_finite() && *v >= 0.0) {
            return Err("a value that is not a finite distance".into());
        }
        Ok(Self::with_pairs(h, Stored::Owned { cols, vals }))
    }

    /// Reads [`SparseSimilarity::write_to`]'s bytes from byte `at` of a mapped
    /// cache file, the pairs left in the map and read on demand. Checked on
    /// opening as [`SparseSimilarity::from_bytes`] checks, except each
    /// row's columns and values (that would read the whole file): the file
    /// is the database's own, written atomically; a column out of range
    /// is then never found, never a panic.
    pub(crate) fn from_mapped(
        map: std::sync::Arc<memmap2::Mmap>,
        at: usize,
    ) -> Result<SparseSimilarity, String> {
        let h = Self::head(map.get(at..).ok_or("shorter than its header")?)?;
        let pairs = Stored::Mapped {
            cols: at + h.cols_at,
            vals: at + h.vals_at,
            len: h.nnz,
            map,
        };
        Ok(Self::with_pairs(h, pairs))
    }

    fn with_pairs(h: Head, pairs: Stored) -> SparseSimilarity {
        SparseSimilarity {
            spans: h.spans,
            n: h.n,
            offsets: h.offsets,
            pairs,
            radius: h.radius,
            dims: h.dims,
            features: h.features,
        }
    }

    /// Everything of [`SparseSimilarity::write_to`]'s bytes before the pairs, checked
    /// (sizes, sequences tiling the frames, rows in order, radius and
    /// descriptors finite), and where the pairs are.
    fn head(bytes: &[u8]) -> Result<Head, String> {
        let mut r = Reader { bytes, at: 0 };
        let n = r.u64()? as usize;
        let dims = r.u64()? as usize;
        let ns = r.u64()? as usize;
        if n > u32::MAX as usize || dims > 255 || ns > n.max(1) {
            return Err(format!("{n} frames, {dims} dimensions, {ns} sequences"));
        }
        let mut spans = Vec::with_capacity(ns);
        for _ in 0..ns {
            let l = r.u64()? as usize;
            let name = String::from_utf8(r.take(l)?.to_vec()).map_err(|e| e.to_string())?;
            let start = r.u64()? as usize;
            let len = r.u64()? as usize;
            spans.push(Span { name, start, len });
        }
        let radius = r.f32s(n)?;
        let features = r.f32s(n * dims)?;
        let mut offsets = Vec::with_capacity(n + 1);
        for _ in 0..=n {
            offsets.push(r.u64()?);
        }
        let nnz = *offsets.last().unwrap_or(&0) as usize;
        let cols_at = r.at;
        r.take(nnz.checked_mul(4).ok_or("size overflow")?)?;
        let vals_at = r.at;
        r.take(nnz.checked_mul(4).ok_or("size overflow")?)?;
        if r.at != bytes.len() {
            return Err(format!("{} bytes after the end", bytes.len() - r.at));
        }
        let mut next = 0;
        for s in &spans {
            if s.start != next {
                return Err(format!("sequence '{}' starts at {}", s.name, s.start));
            }
            next += s.len;
        }
        if next != n || offsets.first() != Some(&0) || offsets.windows(2).any(|w| w[0] > w[1]) {
            return Err("the rows disagree with the frame count".into());
        }
        if !radius.iter().all(|v| v.is_finite() && *v >= 0.0)
            || !features.iter().all(|v| v.is_finite())
        {
            return Err("a value that is not a finite distance".into());
        }
        Ok(Head {
            spans,
            n,
            dims,
            radius,
            features,
            offsets,
            nnz,
            cols_at,
            vals_at,
        })
    }
}

/// Little-endian values read off a byte slice, refusing to read past it.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, k: usize) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(k).ok_or("size overflow")?;
        let s = self
            .bytes
            .get(self.at..end)
            .ok_or_else(|| format!("truncated at byte {}", self.at))?;
        self.at = end;
        Ok(s)
    }
    fn u64(&mut self) -> Result<u64, String> {
        let b = self.take(8)?;
        Ok(u64::from_le_bytes(b.try_into().map_err(|_| "short")?))
    }
    fn f32s(&mut self, k: usize) -> Result<Vec<f32>, String> {
        let raw = self.take(k.checked_mul(4).ok_or("size overflow")?)?;
        Ok(raw
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect())
    }
}

impl Dissimilarity for SparseSimilarity {
    fn spans(&self) -> &[Span] {
        &self.spans
    }
    fn value(&self, a: usize, b: usize) -> f32 {
        self.stored(a, b).unwrap_or(f32::INFINITY)
    }
    fn cells(&self, i: usize, j: usize) -> Option<Vec<(usize, usize)>> {
        Some(self.block(i, j))
    }
}

/// The cheap descriptors of every frame projected on their `dims`
/// principal axes (`n × dims`, row-major), the axes fitted on at most
/// [`PCA_SAMPLE`] evenly spaced frames.
pub fn project(set: &dyn Features, dims: usize) -> (Vec<f32>, usize) {
    let n = set.frames();
    let f = set.feature_len();
    let mut raw = vec![0.0f32; n * f];
    raw.par_chunks_mut(f.max(1))
        .enumerate()
        .for_each(|(a, out)| set.feature(a, out));
    let dims = dims.clamp(1, f.max(1)).min(255);
    if n == 0 {
        return (Vec::new(), dims);
    }
    let sample: Vec<usize> = (0..PCA_SAMPLE.min(n))
        .map(|k| k * n / PCA_SAMPLE.min(n))
        .collect();
    let mut mean = vec![0.0f64; f];
    for &a in &sample {
        for (m, v) in mean.iter_mut().zip(&raw[a * f..(a + 1) * f]) {
            *m += *v as f64;
        }
    }
    mean.iter_mut().for_each(|m| *m /= sample.len() as f64);
    let mut cov = nalgebra::DMatrix::<f64>::zeros(f, f);
    for &a in &sample {
        let x = nalgebra::DVector::from_iterator(
            f,
            raw[a * f..(a + 1) * f]
                .iter()
                .zip(&mean)
                .map(|(v, m)| *v as f64 - m),
        );
        cov.syger(1.0, &x, &x, 1.0);
    }
    // syger fills the lower triangle; mirror it.
    for r in 0..f {
        for c in r + 1..f {
            cov[(r, c)] = cov[(c, r)];
        }
    }
    let eig = nalgebra::SymmetricEigen::new(cov);
    let mut order: Vec<usize> = (0..f).collect();
    order.sort_by(|&x, &y| {
        eig.eigenvalues[y]
            .total_cmp(&eig.eigenvalues[x])
            .then(x.cmp(&y))
    });
    let axes: Vec<Vec<f32>> = order[..dims]
        .iter()
        .map(|&k| {
            eig.eigenvectors
                .column(k)
                .iter()
                .map(|v| *v as f32)
                .collect()
        })
        .collect();
    let mut out = vec![0.0f32; n * dims];
    out.par_chunks_mut(dims)
        .zip(raw.par_chunks(f))
        .for_each(|(o, x)| {
            for (d, axis) in axes.iter().enumerate() {
                o[d] = axis.iter().zip(x).map(|(a, v)| a * v).sum();
            }
        });
    (out, dims)
}

/// The sparse similarity of `set`, whose frames form the sequences
/// `spans`. `progress` hears the number of pairs of each evaluated run.
pub fn sparse_pairs(
    set: &dyn Features,
    spans: Vec<Span>,
    opts: &SparseOptions,
    progress: &dyn SparseProgress,
) -> (SparseSimilarity, SparseStats) {
    let t0 = std::time::Instant::now();
    let cpu = process_cpu_seconds;
    let c0 = cpu();
    let n = set.frames();
    let seq = sequence_of(&spans, n);
    let (features, dims) = project(set, opts.dims);
    let copts = opts.candidates();
    let mut found = index_candidates(&features, dims, &spans, &copts);
    let reached = found.reached.as_deref();
    let sequence_pairs = pair_scan::scanned_pairs(&spans, reached).len() as u64;
    let far_pairs = if opts.far > 0 && opts.per_pair > 0 {
        pair_scan::far_pairs(&spans, reached)
    } else {
        Vec::new()
    };
    let c1 = cpu();
    let t_scan = std::time::Instant::now();
    let popts = per_pair_options(opts);
    if opts.per_pair > 0 {
        progress.stage(
            "sequence-pair distances scanned",
            pair_scan::scan_total(&spans, reached) + pair_scan::cells_of(&spans, &far_pairs),
        );
    }
    let step = |k| progress.advance(k);
    let (best, rerank_pairs) = if opts.rerank > 0 {
        let rerank = pair_scan::Rerank {
            full: set,
            examine: opts.rerank,
        };
        pair_scan::best_per_pair_refined(&features, dims, &spans, reached, &popts, rerank, &step)
    } else {
        let best = pair_scan::best_per_pair_with(&features, dims, &spans, reached, &popts, &step);
        (best, 0)
    };
    let per_pair = pair_scan::spread_seeds(&best, opts.spread, &spans, &seq);
    let (far, far_rerank_pairs) = if far_pairs.is_empty() {
        (Vec::new(), 0)
    } else {
        let fopts = super::transitions::TransitionOptions {
            top_n: opts.far,
            ..popts
        };
        let rerank = pair_scan::Rerank {
            full: set,
            examine: opts.far_rerank.max(opts.far),
        };
        pair_scan::best_of_pairs(&features, dims, &spans, &far_pairs, &fopts, rerank, &step)
    };
    let scan_seconds = t_scan.elapsed().as_secs_f64();
    let c2 = cpu();
    let index_seconds = t0.elapsed().as_secs_f64();
    let t1 = std::time::Instant::now();
    let near = found
        .near
        .iter()
        .enumerate()
        .flat_map(|(a, bs)| bs.iter().map(move |&b| (a, b)));
    let band = opts.band as i64;
    let (mut pair_runs, pair_count) =
        runs_around(per_pair.iter().copied(), &spans, &seq, band, band);
    // The far search's centres are the full measure's minima: their
    // diagonal for the windows, the neighbours for the minimum test.
    let (far_runs, far_count) = runs_around(far.iter().copied(), &spans, &seq, band, 1);
    pair_runs.extend(far_runs);
    let sources = [
        runs_around(near, &spans, &seq, band, band),
        runs_around(found.per_sequence.iter().copied(), &spans, &seq, band, band),
        (pair_runs, pair_count),
    ];
    let mut pairs_by_source = [0u64; 3];
    let mut counts = [0u64; 3];
    let mut runs = successor_runs(&spans);
    for (k, (r, c)) in sources.into_iter().enumerate() {
        let merged = merge_runs(r);
        pairs_by_source[k] = merged.iter().map(|r| (r.r1 - r.r0 + 1) as u64).sum();
        counts[k] = c;
        runs.extend(merged);
    }
    // The candidate lists are spent: only their runs are evaluated.
    drop((per_pair, far, best, std::mem::take(&mut found.per_sequence)));
    let mut merged = merge_runs(runs);
    let total: u64 = merged.iter().map(|r| (r.r1 - r.r0 + 1) as u64).sum();
    progress.stage("sparse pairs compared", total);
    // Straight into the rows (issue 43, session 42: the flat values, 4
    // bytes a pair, were held beside them at the 10⁵-frame build's peak).
    let (offsets, cols, vals) = rows_evaluated(n, &merged, set, &step);
    let mut sim = SparseSimilarity {
        spans,
        n,
        offsets,
        pairs: Stored::Owned { cols, vals },
        radius: vec![0.0; n],
        dims,
        features,
    };
    let closure = close(&mut sim, &mut merged, set, opts, &seq, progress);
    let pairs = sim.stored_pairs() as u64;
    sim.radius = radii(&sim, &found.near);
    let stats = SparseStats {
        candidates: counts.iter().sum::<u64>() + far_count,
        near_candidates: counts[0],
        sequence_candidates: counts[1],
        pair_candidates: counts[2],
        pairs_by_source,
        scan_seconds,
        rerank_pairs,
        sequence_pairs,
        far_sequence_pairs: far_pairs.len() as u64,
        far_candidates: far_count,
        far_rerank_pairs,
        closure,
        pairs,
        index_seconds,
        pairs_seconds: t1.elapsed().as_secs_f64(),
        cpu_seconds: [c1 - c0, c2 - c1, cpu() - c2],
    };
    (sim, stats)
}

impl super::closure::StoredPairs for SparseSimilarity {
    fn stored(&self, a: usize, b: usize) -> Option<f32> {
        SparseSimilarity::stored(self, a, b)
    }
    fn block(&self, i: usize, j: usize) -> Vec<(usize, usize)> {
        SparseSimilarity::block(self, i, j)
    }
}

/// The closure's rounds on `sim`, whose pairs are `merged`'s
/// ([`SparseOptions::closure`], [`super::closure`]): each round's true
/// minima stored with their runs. Only the pairs not stored yet are
/// evaluated (a stored value is the full measure's already), and they are
/// merged into the stored rows in place ([`merge_rows`]): the rows are
/// [`rows_of`] every run's, bit for bit, without a second copy of the
/// stored pairs (issue 43, session 41: that copy and the values of every
/// pair were the 10⁵-frame build's peak). Returns [`SparseStats::closure`].
fn close(
    sim: &mut SparseSimilarity,
    merged: &mut Vec<Run>,
    set: &dyn PairDistance,
    opts: &SparseOptions,
    seq: &[u32],
    progress: &dyn SparseProgress,
) -> [u64; 3] {
    let topts = per_pair_options(opts);
    let band = opts.band as i64;
    let mut done = [0u64; 3];
    for _ in 0..opts.closure {
        let (seeds, evaluated) = super::closure::uncertified_minima(&*sim, set, &sim.spans, &topts);
        done[2] += evaluated;
        if seeds.is_empty() {
            break;
        }
        done[0] += 1;
        done[1] += seeds.len() as u64;
        let (runs, _) = runs_around(seeds.into_iter(), &sim.spans, seq, band, band);
        let old = std::mem::take(merged);
        let all = merge_runs(old.iter().copied().chain(runs).collect());
        let fresh = runs_minus(&all, &old);
        drop(old);
        let total: u64 = fresh.iter().map(|r| r.len() as u64).sum();
        progress.stage("sparse pairs closed", total);
        let added = rows_evaluated(sim.n, &fresh, set, &|k| progress.advance(k));
        let (mut cols, mut vals) = match std::mem::replace(&mut sim.pairs, Stored::empty()) {
            Stored::Owned { cols, vals } => (cols, vals),
            mapped => {
                let cols = (0..mapped.len()).map(|k| mapped.col(k)).collect();
                let vals = (0..mapped.len()).map(|k| mapped.val(k)).collect();
                (cols, vals)
            }
        };
        merge_rows(&mut sim.offsets, &mut cols, &mut vals, &added);
        sim.pairs = Stored::Owned { cols, vals };
        *merged = all;
    }
    done
}

/// The pairs of `all` that are not in `old` (both sorted and merged as
/// [`merge_runs`] leaves them, each run of `old` within one of `all`'s),
/// as runs in the same order.
fn runs_minus(all: &[Run], old: &[Run]) -> Vec<Run> {
    let mut out = Vec::new();
    let mut j = 0;
    for r in all {
        while j < old.len() && (old[j].diag, old[j].r1) < (r.diag, r.r0) {
            j += 1;
        }
        let mut from = r.r0;
        while j < old.len() && old[j].diag == r.diag && old[j].r0 <= r.r1 {
            let o = old[j];
            if o.r0 > from {
                out.push(Run {
                    diag: r.diag,
                    r0: from,
                    r1: o.r0 - 1,
                });
            }
            from = from.max(o.r1.saturating_add(1));
            if o.r1 > r.r1 {
                break;
            }
            j += 1;
        }
        if from <= r.r1 {
            out.push(Run {
                diag: r.diag,
                r0: from,
                r1: r.r1,
            });
        }
    }
    out
}

/// Rows of a compressed sparse row matrix: offsets (one more than the
/// rows), columns and values.
type Rows = (Vec<u64>, Vec<u32>, Vec<f32>);

/// `added`'s rows (pairs none of which the rows `offsets`/`cols`/`vals`
/// hold; as many rows) merged into those rows in place, each row's columns
/// ascending: the rows [`rows_of`] gives of both matrices' runs together.
/// The buffers grow by `added`'s pairs only, and the rows move from the
/// last one back (a row never moves below where it was), so no second copy
/// of the stored pairs is held.
fn merge_rows(offsets: &mut [u64], cols: &mut Vec<u32>, vals: &mut Vec<f32>, added: &Rows) {
    let (aoff, acols, avals) = added;
    let n = offsets
        .len()
        .saturating_sub(1)
        .min(aoff.len().saturating_sub(1));
    if acols.is_empty() || n == 0 {
        return;
    }
    let old = cols.len();
    cols.reserve_exact(acols.len());
    vals.reserve_exact(avals.len());
    cols.resize(old + acols.len(), 0);
    vals.resize(old + avals.len(), 0.0);
    for a in (0..n).rev() {
        let (os, oe) = (offsets[a] as usize, offsets[a + 1] as usize);
        let (fs, fe) = (aoff[a] as usize, aoff[a + 1] as usize);
        let start = os + fs;
        let mut d = oe + fe;
        let (mut i, mut k) = (oe, fe);
        while k > fs {
            d -= 1;
            if i > os && cols[i - 1] > acols[k - 1] {
                i -= 1;
                cols[d] = cols[i];
                vals[d] = vals[i];
            } else {
                k -= 1;
                cols[d] = acols[k];
                vals[d] = avals[k];
            }
        }
        if start != os {
            cols.copy_within(os..i, start);
            vals.copy_within(os..i, start);
        }
    }
    for (o, f) in offsets.iter_mut().zip(aoff.iter()) {
        *o += *f;
    }
}

/// The transition search of the per-pair candidates: `per_pair` kept, the
/// windows the band covers.
fn per_pair_options(opts: &SparseOptions) -> super::transitions::TransitionOptions {
    let lo = opts.min_window.max(1);
    super::transitions::TransitionOptions {
        top_n: opts.per_pair,
        max_window: opts.band.saturating_sub(1).max(lo),
        min_window: lo,
        min_gap: opts.min_gap,
    }
}

/// The runs along the diagonals around each candidate `(a, b)`: the
/// diagonal through it `band` frames each way and the two either side
/// `side` frames each way (`band`: the windows of every pair near the
/// centre; 1: the centre's 8 neighbours), clipped to both sequences.
/// Returns the runs and the candidates' count.
fn runs_around(
    seeds: impl Iterator<Item = (usize, u32)>,
    spans: &[Span],
    seq: &[u32],
    band: i64,
    side: i64,
) -> (Vec<Run>, u64) {
    let mut runs: Vec<Run> = Vec::new();
    let mut candidates = 0u64;
    for (a, b) in seeds {
        candidates += 1;
        let (a, b) = (a.min(b as usize) as i64, a.max(b as usize) as i64);
        let (si, sj) = (
            &spans[seq[a as usize] as usize],
            &spans[seq[b as usize] as usize],
        );
        for e in -2..=2i64 {
            let d = b - a + e;
            if d == 0 {
                continue;
            }
            let reach = if e == 0 { band } else { side };
            let r0 = (a - reach).max(si.start as i64).max(sj.start as i64 - d);
            let r1 = (a + reach)
                .min((si.start + si.len) as i64 - 1)
                .min((sj.start + sj.len) as i64 - 1 - d);
            if r0 > r1 {
                continue;
            }
            runs.push(if d > 0 {
                Run {
                    diag: d as u32,
                    r0: r0 as u32,
                    r1: r1 as u32,
                }
            } else {
                Run {
                    diag: (-d) as u32,
                    r0: (r0 + d) as u32,
                    r1: (r1 + d) as u32,
                }
            });
        }
    }
    (runs, candidates)
}

/// Each sequence's first two off-diagonals (the retrieval's step costs).
fn successor_runs(spans: &[Span]) -> Vec<Run> {
    let mut runs = Vec::new();
    for s in spans {
        for d in 1..=2usize {
            if s.len > d {
                runs.push(Run {
                    diag: d as u32,
                    r0: s.start as u32,
                    r1: (s.start + s.len - 1 - d) as u32,
                });
            }
        }
    }
    runs
}

/// The runs sorted, overlapping and touching runs of a diagonal merged.
fn merge_runs(mut runs: Vec<Run>) -> Vec<Run> {
    runs.sort_unstable();
    let mut merged: Vec<Run> = Vec::with_capacity(runs.len() / 4);
    for r in runs {
        match merged.last_mut() {
            Some(m) if m.diag == r.diag && r.r0 <= m.r1 + 1 => m.r1 = m.r1.max(r.r1),
            _ => merged.push(r),
        }
    }
    merged
}

/// The rows of `merged`'s pairs (runs as [`merge_runs`] leaves them: no
/// pair twice) with the full measure of `set` evaluated straight into
/// them ([`tiled::evaluate_each`]): [`rows_of`] the runs and
/// [`tiled::evaluate`]'s values, bit for bit, without those values held
/// beside the rows (4 bytes a pair; issue 43, session 42). The columns are
/// laid out and sorted first; each value goes to its two slots, found by
/// binary search in the sorted rows.
fn rows_evaluated(
    n: usize,
    merged: &[Run],
    set: &dyn PairDistance,
    progress: &(dyn Fn(u64) + Sync),
) -> Rows {
    let (offsets, cols) = row_columns(n, merged);
    let slots: Vec<AtomicU32> = (0..cols.len()).map(|_| AtomicU32::new(0)).collect();
    let slot = |a: u32, b: u32| {
        let (s, e) = (
            offsets[a as usize] as usize,
            offsets[a as usize + 1] as usize,
        );
        // Every pair of the runs has its column in both rows.
        s + cols[s..e].binary_search(&b).unwrap_or_else(|k| k)
    };
    tiled::evaluate_each(set, merged, progress, &|a, b, _, v| {
        slots[slot(a, b)].store(v.to_bits(), Ordering::Relaxed);
        slots[slot(b, a)].store(v.to_bits(), Ordering::Relaxed);
    });
    let vals = slots
        .into_iter()
        .map(|v| f32::from_bits(v.into_inner()))
        .collect();
    (offsets, cols, vals)
}

/// The row offsets and columns (ascending in each row) of the pairs of
/// `merged` stored both ways.
fn row_columns(n: usize, merged: &[Run]) -> (Vec<u64>, Vec<u32>) {
    let mut offsets = vec![0u64; n + 1];
    for r in merged {
        for a in r.r0..=r.r1 {
            offsets[a as usize + 1] += 1;
            offsets[(a + r.diag) as usize + 1] += 1;
        }
    }
    for a in 0..n {
        offsets[a + 1] += offsets[a];
    }
    let mut cols = vec![0u32; offsets[n] as usize];
    let mut fill: Vec<u64> = offsets[..n].to_vec();
    for r in merged {
        for a in r.r0..=r.r1 {
            let b = a + r.diag;
            for (p, q) in [(a, b), (b, a)] {
                cols[fill[p as usize] as usize] = q;
                fill[p as usize] += 1;
            }
        }
    }
    drop(fill);
    let mut rows: Vec<&mut [u32]> = Vec::with_capacity(n);
    let mut rest = cols.as_mut_slice();
    for a in 0..n {
        let k = (offsets[a + 1] - offsets[a]) as usize;
        let (row, tail) = std::mem::take(&mut rest).split_at_mut(k);
        rows.push(row);
        rest = tail;
    }
    rows.par_iter_mut().for_each(|r| r.sort_unstable());
    drop(rows);
    (offsets, cols)
}

/// The runs' values stored both ways, row by row, columns ascending:
/// row offsets, columns and values of a compressed sparse row matrix
/// (the reference [`rows_evaluated`] is tested against).
#[cfg(test)]
fn rows_of(n: usize, merged: &[Run], values: &[f32]) -> Rows {
    let mut deg = vec![0u64; n + 1];
    for r in merged {
        for a in r.r0..=r.r1 {
            deg[a as usize] += 1;
            deg[(a + r.diag) as usize] += 1;
        }
    }
    let mut offsets = vec![0u64; n + 1];
    for a in 0..n {
        offsets[a + 1] = offsets[a] + deg[a];
    }
    let nnz = offsets[n] as usize;
    let mut cols = vec![0u32; nnz];
    let mut vals = vec![0.0f32; nnz];
    let mut fill: Vec<u64> = offsets[..n].to_vec();
    let at = tiled::offsets(merged);
    for (k, r) in merged.iter().enumerate() {
        for (a, x) in (r.r0..=r.r1).zip(&values[at[k]..at[k + 1]]) {
            let b = a + r.diag;
            for (p, q) in [(a, b), (b, a)] {
                let at = fill[p as usize] as usize;
                cols[at] = q;
                vals[at] = *x;
                fill[p as usize] += 1;
            }
        }
    }
    sort_rows(&deg[..n], &mut cols, &mut vals);
    (offsets, cols, vals)
}

/// Sorts each row (of `deg` entries) by column, in parallel over rows.
#[cfg(test)]
fn sort_rows(deg: &[u64], cols: &mut [u32], vals: &mut [f32]) {
    let mut rows: Vec<(&mut [u32], &mut [f32])> = Vec::with_capacity(deg.len());
    let (mut c, mut v) = (cols, vals);
    for &k in deg {
        let k = k as usize;
        let (c0, c1) = std::mem::take(&mut c).split_at_mut(k);
        let (v0, v1) = std::mem::take(&mut v).split_at_mut(k);
        rows.push((c0, v0));
        c = c1;
        v = v1;
    }
    rows.par_iter_mut().for_each(|(c, v)| {
        let mut p: Vec<(u32, f32)> = c.iter().copied().zip(v.iter().copied()).collect();
        p.sort_unstable_by_key(|x| x.0);
        for (k, (cc, vv)) in p.into_iter().enumerate() {
            c[k] = cc;
            v[k] = vv;
        }
    });
}

/// Per frame, the largest stored distance to its nearest frames.
fn radii(sim: &SparseSimilarity, near: &[Vec<u32>]) -> Vec<f32> {
    near.par_iter()
        .enumerate()
        .map(|(a, bs)| {
            bs.iter()
                .filter_map(|&b| sim.stored(a, b as usize))
                .fold(0.0f32, f32::max)
        })
        .collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Frames on a noisy 2-D loop: a periodic "motion" of period 40.
    struct Loop(Vec<[f32; 2]>);
    impl PairDistance for Loop {
        fn frames(&self) -> usize {
            self.0.len()
        }
        fn distance(&self, a: usize, b: usize) -> f64 {
            let (p, q) = (self.0[a], self.0[b]);
            (((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)) as f64).sqrt()
        }
    }
    impl Features for Loop {
        fn feature_len(&self) -> usize {
            2
        }
        fn feature(&self, a: usize, out: &mut [f32]) {
            out.copy_from_slice(&self.0[a]);
        }
    }

    /// Spans `s0`, `s1`, ... of the lengths `lens`, one after another (also
    /// read by the tests of `candidates`).
    pub(crate) fn spans(lens: &[usize]) -> Vec<Span> {
        let mut at = 0;
        lens.iter()
            .enumerate()
            .map(|(k, &len)| {
                at += len;
                Span {
                    name: format!("s{k}"),
                    start: at - len,
                    len,
                }
            })
            .collect()
    }

    /// Transitions as `(m, n, L, cost)`.
    type Found = Vec<(usize, usize, usize, f64)>;

    /// The transitions of sequences `i → j` found on `sim`'s stored pairs
    /// and on every pair of `set` (the dense method).
    fn both_ways(set: &Loop, sim: &SparseSimilarity, i: usize, j: usize) -> (Found, Found) {
        use super::super::transitions::{TransitionOptions, find, find_among};
        let (si, sj) = (&sim.spans[i], &sim.spans[j]);
        let opts = TransitionOptions::default();
        let dense = |r: usize, c: usize| set.distance(si.start + r, sj.start + c) as f32;
        let sparse = |r: usize, c: usize| sim.value(si.start + r, sj.start + c);
        let d = find(&dense, si.len, sj.len, i == j, &opts);
        let cells = sim.block(i, j).into_iter();
        let s = find_among(&sparse, si.len, sj.len, i == j, &opts, cells);
        (d, s)
    }

    /// Issue 43: a motion far from every other (its frames are nobody's
    /// nearest, and its nearest frames are its own) still gets the dense
    /// method's transitions to and from the others — from the per-pair
    /// candidates; the nearest frames alone give it none.
    #[test]
    fn a_far_motion_keeps_its_best_transitions() {
        let ring = |t: usize, centre: f32, speed: f32, wobble: f32| {
            let a = t as f32 * std::f32::consts::TAU / 40.0 * speed;
            [
                centre + a.cos() * (1.0 + wobble * (0.3 * t as f32).sin()),
                a.sin(),
            ]
        };
        let mut pts: Vec<[f32; 2]> = (0..160).map(|t| ring(t, 0.0, 1.0, 0.05)).collect();
        pts.extend((0..120).map(|t| ring(t, 0.0, 1.3, 0.1)));
        pts.extend((0..100).map(|t| ring(t, 9.0, 0.8, 0.2)));
        let set = Loop(pts);
        let spans = spans(&[160, 120, 100]);
        let base = SparseOptions {
            neighbours: 6,
            dims: 2,
            per_sequence: 0,
            per_pair: 8,
            spread: 5,
            rerank: 0,
            ..SparseOptions::default()
        };
        let (with, _) = sparse_pairs(&set, spans.clone(), &base, &|_: u64| {});
        let knn_only = SparseOptions {
            per_pair: 0,
            per_sequence: 0,
            ..base
        };
        let (without, _) = sparse_pairs(&set, spans, &knn_only, &|_: u64| {});
        for (i, j) in [(0, 2), (2, 0), (1, 2), (2, 1), (0, 1)] {
            let (dense, sparse) = both_ways(&set, &with, i, j);
            assert!(!dense.is_empty(), "({i}, {j})");
            assert_eq!(sparse, dense, "({i}, {j})");
        }
        for (i, j) in [(0, 2), (2, 1)] {
            let (_, sparse) = both_ways(&set, &without, i, j);
            assert!(sparse.is_empty(), "({i}, {j}): {sparse:?}");
        }
    }

    /// Each pair's own value (tells pairs and directions' slots apart).
    fn value_of(runs: &[Run]) -> Vec<f32> {
        runs.iter()
            .flat_map(|r| (r.r0..=r.r1).map(move |a| a as f32 * 1e-3 + r.diag as f32))
            .collect()
    }

    /// Issue 43, session 41: the closure's rows made in place — the stored
    /// rows, grown by the new pairs only — are [`rows_of`] every run's,
    /// offsets, columns and values bit for bit; [`runs_minus`] gives
    /// exactly the pairs not stored. On random runs (overlapping, touching,
    /// nested, one-pair runs, rows with nothing new, a first round with
    /// nothing stored) over 400 frames.
    #[test]
    fn new_pairs_merged_in_place_are_the_rows_of_every_run() {
        let mut rng = crate::similarity::test_rng::XorShift::new(0x9e37_79b9_7f4a_7c15);
        let mut rnd = move |m: u32| rng.below(m);
        let n = 400u32;
        let random_runs = |k: usize, rnd: &mut dyn FnMut(u32) -> u32| -> Vec<Run> {
            (0..k)
                .map(|_| {
                    let diag = 1 + rnd(60);
                    let r0 = rnd(n - diag);
                    let r1 = (r0 + rnd(30)).min(n - 1 - diag);
                    Run { diag, r0, r1 }
                })
                .collect()
        };
        for round in 0..40 {
            let old = if round == 0 {
                Vec::new()
            } else {
                merge_runs(random_runs(1 + round * 3, &mut rnd))
            };
            let new = random_runs(1 + (round % 7) * 5, &mut rnd);
            let all = merge_runs(old.iter().copied().chain(new).collect());
            let fresh = runs_minus(&all, &old);
            // The new runs hold exactly the pairs of `all` not in `old`.
            let pairs = |runs: &[Run]| -> Vec<(u32, u32)> {
                let mut p: Vec<(u32, u32)> = runs
                    .iter()
                    .flat_map(|r| (r.r0..=r.r1).map(move |a| (a, a + r.diag)))
                    .collect();
                p.sort_unstable();
                p
            };
            let (po, pf, pa) = (pairs(&old), pairs(&fresh), pairs(&all));
            assert!(pf.iter().all(|p| po.binary_search(p).is_err()), "{round}");
            let mut both = [po.clone(), pf.clone()].concat();
            both.sort_unstable();
            assert_eq!(both, pa, "{round}");
            let want = rows_of(n as usize, &all, &value_of(&all));
            let (mut offsets, mut cols, mut vals) = rows_of(n as usize, &old, &value_of(&old));
            let added = rows_of(n as usize, &fresh, &value_of(&fresh));
            merge_rows(&mut offsets, &mut cols, &mut vals, &added);
            assert_eq!(offsets, want.0, "{round}");
            assert_eq!(cols, want.1, "{round}");
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&vals), bits(&want.2), "{round}");
        }
    }

    /// Issue 43, session 42: the rows with the full measure evaluated
    /// straight into them are [`rows_of`] the runs and
    /// [`tiled::evaluate`]'s values — offsets, columns and value bits — on
    /// random merged runs (overlapping, touching, one-pair runs, far
    /// diagonals, rows with no pair, blocks' edges crossed) of a measure
    /// that tells a pair's two orders apart, and on no runs.
    #[test]
    fn pairs_evaluated_straight_into_the_rows_are_the_rows_of_the_values() {
        struct Asym(usize);
        impl PairDistance for Asym {
            fn frames(&self) -> usize {
                self.0
            }
            fn distance(&self, a: usize, b: usize) -> f64 {
                (a as f64 * 1.000_123).sin() * 3.0 + (b as f64).sqrt() + (a * 7 + b) as f64 * 1e-6
            }
        }
        let mut rng = crate::similarity::test_rng::XorShift::new(0x2545_f491_4f6c_dd1d);
        let mut rnd = move |m: u32| rng.below(m);
        for round in 0..30u32 {
            let n = 70 + rnd(600);
            let mut runs = vec![Run {
                diag: n - 1,
                r0: 0,
                r1: 0,
            }];
            for _ in 0..(1 + round * 7) {
                let diag = 1 + rnd(n - 1);
                let r0 = rnd(n - diag);
                let r1 = (r0 + rnd(90)).min(n - 1 - diag);
                runs.push(Run { diag, r0, r1 });
            }
            let runs = merge_runs(runs);
            let set = Asym(n as usize);
            let counted = std::sync::atomic::AtomicU64::new(0);
            let got = rows_evaluated(n as usize, &runs, &set, &|k| {
                counted.fetch_add(k, Ordering::Relaxed);
            });
            let want = rows_of(n as usize, &runs, &tiled::evaluate(&set, &runs, &|_| {}));
            assert_eq!(got.0, want.0, "{round}: offsets");
            assert_eq!(got.1, want.1, "{round}: columns");
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&got.2), bits(&want.2), "{round}: values");
            let pairs: u64 = runs.iter().map(|r| r.len() as u64).sum();
            assert_eq!(counted.into_inner(), pairs, "{round}: progress");
            assert_eq!(got.1.len() as u64, 2 * pairs, "{round}");
        }
        let none = rows_evaluated(5, &[], &Asym(5), &|_| {});
        assert_eq!(none, (vec![0u64; 6], Vec::new(), Vec::new()));
    }

    /// Issue 43, session 41: the closure that evaluates only the pairs not
    /// stored yet and merges them into the rows in place gives session
    /// 40's closure (every run's pairs evaluated again, the stored ones
    /// read, the rows made anew) bit for bit: the same rounds, runs,
    /// offsets, columns and values. Three re-timed loops (slanted valleys),
    /// a first store of the successors and a few seeds' diagonals with
    /// their neighbours only, so that the search's transitions are not all
    /// certified and the closure runs.
    #[test]
    fn the_closure_in_place_is_the_closure_of_every_run() {
        let mut pts: Vec<[f32; 2]> = Vec::new();
        for (len, speed) in [(300usize, 1.0f32), (260, 1.27), (340, 0.83)] {
            pts.extend((0..len).map(|t| {
                let a = t as f32 * speed * std::f32::consts::TAU / 40.0;
                [a.cos() * (1.0 + 0.04 * (0.37 * t as f32).sin()), a.sin()]
            }));
        }
        let set = Loop(pts);
        let n = set.frames();
        let spans = spans(&[300, 260, 340]);
        let seq = sequence_of(&spans, n);
        let opts = SparseOptions {
            band: 8,
            ..SparseOptions::default()
        };
        let make = |merged: &[Run]| {
            let values = tiled::evaluate(&set, merged, &|_: u64| {});
            let (offsets, cols, vals) = rows_of(n, merged, &values);
            SparseSimilarity {
                spans: spans.clone(),
                n,
                offsets,
                pairs: Stored::Owned { cols, vals },
                radius: vec![0.0; n],
                dims: 2,
                features: vec![0.0; 2 * n],
            }
        };
        let mut rounds_run = 0;
        for (step_a, step_b) in [(6usize, 9usize), (4, 7), (11, 13)] {
            // Seeds of the first sequence against the others, their
            // diagonals ±8 frames and the neighbours' diagonals ±1 only.
            let seeds: Vec<(usize, u32)> = (0..300)
                .step_by(step_a)
                .flat_map(|a| (300..900).step_by(step_b).map(move |b| (a, b as u32)))
                .collect();
            let (runs, _) = runs_around(seeds.into_iter(), &spans, &seq, 8, 1);
            let first = merge_runs(successor_runs(&spans).into_iter().chain(runs).collect());
            let (mut sim, mut merged) = (make(&first), first.clone());
            let done = close(&mut sim, &mut merged, &set, &opts, &seq, &|_: u64| {});
            rounds_run += done[0];
            // Session 40's closure.
            let (mut want, mut want_runs) = (make(&first), first);
            let topts = per_pair_options(&opts);
            let mut rounds = 0;
            for _ in 0..opts.closure {
                let (seeds, _) =
                    super::super::closure::uncertified_minima(&want, &set, &want.spans, &topts);
                if seeds.is_empty() {
                    break;
                }
                rounds += 1;
                let (runs, _) = runs_around(seeds.into_iter(), &spans, &seq, 8, 8);
                let all = merge_runs(want_runs.iter().copied().chain(runs).collect());
                let known = super::super::closure::Known {
                    stored: &want,
                    full: &set,
                };
                let values = tiled::evaluate(&known, &all, &|_: u64| {});
                let (offsets, cols, vals) = rows_of(n, &all, &values);
                want.offsets = offsets;
                want.pairs = Stored::Owned { cols, vals };
                want_runs = all;
            }
            assert_eq!(rounds, done[0], "{step_a} {step_b}");
            assert_eq!(merged, want_runs, "{step_a} {step_b}");
            assert!(
                sim == want,
                "{step_a} {step_b}: {} pairs against {}",
                sim.stored_pairs(),
                want.stored_pairs()
            );
        }
        assert!(rounds_run >= 1, "the closure never ran");
    }

    /// Issue 43, session 41: the stored pairs written in pieces
    /// ([`SparseSimilarity::write_to`]) are the file's layout byte for byte
    /// (written here in one piece as before) and read back exactly, in
    /// memory and mapped; each stored value is the pair's full measure, both
    /// ways.
    #[test]
    fn the_stored_pairs_round_trip_exactly() {
        let set = Loop(
            (0..2600)
                .map(|t| {
                    let a = t as f32 * std::f32::consts::TAU / (37.0 + (t / 500) as f32);
                    [
                        a.cos() + 0.003 * (t % 11) as f32,
                        a.sin() * (1.0 + 0.01 * (t % 5) as f32),
                    ]
                })
                .collect(),
        );
        let opts = SparseOptions {
            neighbours: 6,
            dims: 2,
            ..SparseOptions::default()
        };
        let (s, _) = sparse_pairs(&set, spans(&[700, 500, 900, 500]), &opts, &|_: u64| {});
        for a in 0..2600 {
            for (b, v) in s.row(a) {
                let (lo, hi) = (a.min(b as usize), a.max(b as usize));
                assert_eq!(v.to_bits(), (set.distance(lo, hi) as f32).to_bits());
            }
        }
        // The layout of session 40's one-buffer writer.
        let mut want: Vec<u8> = Vec::new();
        for v in [s.n, s.dims, s.spans.len()] {
            want.extend((v as u64).to_le_bytes());
        }
        for sp in &s.spans {
            want.extend((sp.name.len() as u64).to_le_bytes());
            want.extend(sp.name.as_bytes());
            want.extend((sp.start as u64).to_le_bytes());
            want.extend((sp.len as u64).to_le_bytes());
        }
        for v in s.radius.iter().chain(&s.features) {
            want.extend(v.to_le_bytes());
        }
        for o in &s.offsets {
            want.extend(o.to_le_bytes());
        }
        for k in 0..s.pairs.len() {
            want.extend(s.pairs.col(k).to_le_bytes());
        }
        for k in 0..s.pairs.len() {
            want.extend(s.pairs.val(k).to_le_bytes());
        }
        assert!(want.len() > 3 * WRITE_CHUNK, "{} bytes", want.len());
        let got = s.to_bytes();
        assert!(got == want, "{} bytes against {}", got.len(), want.len());
        assert_eq!(SparseSimilarity::from_bytes(&got).unwrap(), s);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("sparse.bin");
        crate::util::fsutil::write_atomic(&p, |w| {
            w.write_all(&[0u8; 16])?;
            s.write_to(w)
        })
        .unwrap();
        assert_eq!(std::fs::read(&p).unwrap()[16..], want[..]);
        let map = unsafe { memmap2::Mmap::map(&std::fs::File::open(&p).unwrap()) }.unwrap();
        let mapped = SparseSimilarity::from_mapped(std::sync::Arc::new(map), 16).unwrap();
        assert_eq!(mapped, s);
    }

    #[test]
    fn overrides_name_their_fields_and_refuse_the_rest() {
        let d = SparseOptions::default();
        let o = d
            .with_overrides(" per_pair=16, rerank=0 ,neighbours=8")
            .unwrap();
        assert_eq!((o.per_pair, o.rerank, o.neighbours), (16, 0, 8));
        assert_eq!(
            SparseOptions {
                per_pair: 16,
                rerank: 0,
                neighbours: 8,
                ..d
            },
            o
        );
        assert_eq!(d.with_overrides("").unwrap(), d);
        for bad in ["per_pair", "per_pair=x", "per_pair=-1", "nearest=3"] {
            assert!(d.with_overrides(bad).unwrap_err().contains('\''), "{bad}");
        }
    }

    #[test]
    fn stores_exact_values_both_ways_and_round_trips() {
        let set = Loop(
            (0..300)
                .map(|t| {
                    let a = t as f32 * std::f32::consts::TAU / 40.0;
                    [a.cos() + 0.001 * (t % 7) as f32, a.sin()]
                })
                .collect(),
        );
        let opts = SparseOptions {
            neighbours: 6,
            dims: 2,
            ..SparseOptions::default()
        };
        let (s, stats) = sparse_pairs(&set, spans(&[120, 180]), &opts, &|_: u64| {});
        assert!(stats.candidates >= 300 * 6);
        assert!(stats.pairs > 0 && (s.stored_pairs() as u64) == stats.pairs);
        assert!(
            s.stored_pairs() < 300 * 299 / 2,
            "sparse: {}",
            s.stored_pairs()
        );
        for a in 0..300 {
            for (b, v) in s.row(a) {
                assert_eq!(v, set.distance(a, b as usize) as f32);
                assert_eq!(s.stored(b as usize, a), Some(v));
            }
            // Every frame's successor is stored.
            if a != 119 && a != 299 {
                assert!(s.stored(a, a + 1).is_some());
            }
        }
        // A frame one period on is found (same phase, another sequence).
        assert!(s.stored(10, 130).is_some());
        // Estimates of pairs not stored are at least the radius.
        assert!(s.get(0, 20) >= s.radius[0]);
        let back = SparseSimilarity::from_bytes(&s.to_bytes()).unwrap();
        assert_eq!(back, s);
        let mut bad = s.to_bytes();
        bad.truncate(bad.len() - 3);
        assert!(SparseSimilarity::from_bytes(&bad).is_err());
        // Mapped from a file (16 bytes of header first, as the cache has):
        // the same pairs, values and blocks, read on demand.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("sparse.bin");
        let mut file = vec![7u8; 16];
        file.extend(s.to_bytes());
        std::fs::write(&p, &file).unwrap();
        let map = unsafe { memmap2::Mmap::map(&std::fs::File::open(&p).unwrap()) }.unwrap();
        let mapped = SparseSimilarity::from_mapped(std::sync::Arc::new(map), 16).unwrap();
        assert!(mapped.is_mapped() && !s.is_mapped());
        assert_eq!(mapped, s);
        for (a, b) in [(0, 20), (10, 130), (5, 6), (299, 0), (119, 120)] {
            assert_eq!(
                mapped.get(a, b).to_bits(),
                s.get(a, b).to_bits(),
                "({a}, {b})"
            );
        }
        for (i, j) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
            assert_eq!(mapped.block(i, j), s.block(i, j));
        }
        std::fs::write(&p, &file[..file.len() - 1]).unwrap();
        let map = unsafe { memmap2::Mmap::map(&std::fs::File::open(&p).unwrap()) }.unwrap();
        assert!(SparseSimilarity::from_mapped(std::sync::Arc::new(map), 16).is_err());
    }
}
