//! How far the sparse build's sequence-pair scan reaches, chosen from an
//! up-front estimate (issue 43, session 40).
//!
//! The sparse similarity ([`super::sparse`]) scans every sequence pair by
//! default: the per-pair search of Sec. 4.2's best transitions of every
//! ordered pair and the cover rule's per-sequence trees. Its pairs grow
//! with `frames × sequences`, and the sequences of a capture library grow
//! with its frames: 11.6 M pairs at 10⁴ frames (34 sequences), 104.5 M at
//! 3×10⁴ (98), about 10⁹ at 10⁵ (321) — past the hour and 8 GB on
//! this project's 2-core, 24 GB machine (sessions 32-33). A reach
//! ([`SparseOptions::reach`], with the far search [`SparseOptions::far`])
//! bounds the pairs by `frames`, at the price of some of the full scan's
//! transitions (88 % kept at 10⁴ frames, session 34).
//!
//! So before the scan, [`choose`] estimates what the full scan would
//! compare and hold ([`estimate`]): if it fits the budget
//! ([`SparseOptions::budget_pairs`], [`SparseOptions::budget_memory`]) the
//! full scan runs, exactly as before; otherwise the largest reach of at
//! least [`MIN_REACH`] that fits (or [`MIN_REACH`] when none does, said so).
//! A reach given explicitly wins. The rule reads only the counts and the
//! options, never the machine, so a database builds the same everywhere.
//!
//! The estimate's coefficients are the measured builds of the 2,600-vertex
//! pool of `scripts/scale-db.sh` with the default options (sessions 32-39;
//! the full measure compares descriptors, so its cost does not depend on
//! the mesh): stored pairs `frames · (125 + 60 · P / S)` for `P` sequence
//! pairs scanned of `S` sequences (within 14 % of the nine measured
//! builds, 3,896 to 100,009 frames, full scans and reach 16), 280 per far
//! pair; re-ranking 34 full measures per cheap transition descended. Memory
//! (session 41, after the build stopped holding the stored pairs twice in
//! the closure and once more while writing its cache): 64 MiB, each
//! frame's descriptors (47.4 KB) and 22 bytes per stored pair (16 held,
//! 4 while the rows are made, 10 % for the runs and the pairs'
//! estimate); session 40's 128 MiB and 32 bytes a pair were 9 % low at
//! 10⁵ frames (8.77 GB measured, 7.96 GB estimated).

use super::histogram::{DESCRIPTOR_LEN, PHI_SUB};
use super::sparse::SparseOptions;
use serde::Serialize;

/// The smallest reach the rule chooses: at 10⁴ frames reach 16 with the far
/// search keeps 88 % of the full scan's transitions and every sequence pair
/// linked (session 34); smaller reaches were not measured at scale.
pub const MIN_REACH: usize = 16;

/// Stored pairs per frame whatever the sequences (the nearest frames'
/// windows and the successors).
const PER_FRAME: f64 = 125.0;
/// Stored pairs per frame and per sequence pair scanned per sequence (the
/// per-pair windows and the per-sequence trees' candidates).
const PER_FRAME_AND_PAIR: f64 = 60.0;
/// Of the `reach` other sequences each sequence takes, the share that adds
/// a pair (the rest are taken both ways): 3,624 pairs for 321 sequences at
/// reach 16, 1,138 for 98, 369 for 34 (0.62-0.66).
const REACHED_SHARE: f64 = 0.65;
/// Stored pairs per far pair (its `far` centres' diagonals and
/// neighbours): 13.7 M for 48,057 far pairs at 10⁵ frames (session 34).
const FAR_STORED: f64 = 280.0;
/// Full measures per cheap transition descended by the re-ranking
/// (0.57 M for 66 sequence pairs at `rerank` 256, session 39; 36.9 M for
/// 48,057 far pairs at 16, session 34: 34 and 48).
const PER_DESCENT: f64 = 34.0;
/// Bytes held whatever the frames (the program, the mesh, the index's
/// fixed part).
const BASE_BYTES: f64 = (64u64 << 20) as f64;
/// Bytes per frame held at the build's peak: its shape descriptor and
/// norms (held through the closure, whose descents read them), and 1,600
/// bytes of the rest (the projected descriptor, the nearest frames, the
/// radius, the rows' offsets): fitted on main's 10⁴ and 10⁵ builds
/// (47.4 KB a frame with 40 bytes a pair, session 41).
const FRAME_BYTES: f64 = (4 * DESCRIPTOR_LEN + 8 * PHI_SUB + 1600) as f64;
/// Bytes per stored pair at the build's peak (session 41): column and
/// value both ways (16) and the value while the rows are made from the
/// runs (4), with 10 % for the runs and for the stored-pair estimate (5 %
/// low at 10⁵ frames). Session 40 took 32, fitted on builds that held the
/// pairs twice in the closure (40 bytes: 8.77 GB measured at 10⁵ frames,
/// 7.96 GB estimated). Since session 42 the values go straight into the
/// rows (no 4 bytes while they are made), so 22 is a margin over the 16
/// held and the closure's new pairs; kept until a 10⁵-frame build of that
/// code is measured, as a smaller figure moves the rule's reach there.
const PAIR_BYTES: f64 = 22.0;

/// What a scan of some reach would compare and hold (estimates).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ScanEstimate {
    /// The reach (0: every sequence pair).
    pub reach: usize,
    /// Unordered sequence pairs scanned (a sequence with itself included).
    pub sequence_pairs: u64,
    /// Unordered sequence pairs the far search runs on.
    pub far_pairs: u64,
    /// Frame pairs compared and stored.
    pub pairs: u64,
    /// Full measures evaluated: the stored pairs and the re-rankings'.
    pub full_measures: u64,
    /// Peak memory of the build, bytes.
    pub bytes: u64,
}

/// Why the scan is what it is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ScanReason {
    /// The full scan fits the budget.
    Fits,
    /// The full scan does not fit: the largest reach that does.
    Budget,
    /// The full scan does not fit and neither does [`MIN_REACH`]: that.
    OverBudget,
    /// Too few sequences for a reach of [`MIN_REACH`] to bound the scan.
    FewSequences,
    /// A reach given explicitly (`SURFMOTION_SPARSE=reach=N`).
    Given,
}

/// The scan chosen for a database, with the estimates it was chosen from.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ScanChoice {
    /// Frames of the database.
    pub frames: usize,
    /// Its sequences.
    pub sequences: usize,
    /// What the full scan would take.
    pub full: ScanEstimate,
    /// What the chosen scan takes (the full scan's when it is the one).
    pub chosen: ScanEstimate,
    /// Why.
    pub reason: ScanReason,
    /// The budget: full measures (0: no limit).
    pub budget_pairs: u64,
    /// The budget: bytes (0: no limit).
    pub budget_bytes: u64,
}

/// The estimate of a scan of `reach` (0: every pair) of `frames` frames in
/// `sequences` sequences with `opts`'s per-pair, re-ranking and far
/// options.
pub fn estimate(
    frames: usize,
    sequences: usize,
    opts: &SparseOptions,
    reach: usize,
) -> ScanEstimate {
    let s = sequences.max(1) as f64;
    let all = s * (s + 1.0) / 2.0;
    let bounded = reach > 0 && reach + 1 < sequences;
    let scanned = if bounded {
        (s + (REACHED_SHARE * s * reach as f64).round()).min(all)
    } else {
        all
    };
    let per_pair = opts.per_pair > 0;
    let far = if bounded && per_pair && opts.far > 0 {
        all - scanned
    } else {
        0.0
    };
    let stored = frames as f64 * (PER_FRAME + PER_FRAME_AND_PAIR * scanned / s) + FAR_STORED * far;
    let rerank = if per_pair { opts.rerank as f64 } else { 0.0 };
    let far_rerank = opts.far_rerank.max(opts.far) as f64;
    let descents = scanned * rerank + far * far_rerank;
    ScanEstimate {
        reach: if bounded { reach } else { 0 },
        sequence_pairs: scanned as u64,
        far_pairs: far as u64,
        pairs: stored as u64,
        full_measures: (stored + PER_DESCENT * descents) as u64,
        bytes: (BASE_BYTES + FRAME_BYTES * frames as f64 + PAIR_BYTES * stored) as u64,
    }
}

/// The scan of `frames` frames in `sequences` sequences: `opts.reach` when
/// `reach_given`; else the full scan when its [`estimate`] fits
/// [`SparseOptions::budget_pairs`] (millions of full measures) and
/// [`SparseOptions::budget_memory`] (MB; 0: no limit either), else the
/// largest reach of at least [`MIN_REACH`] that fits (or [`MIN_REACH`]).
pub fn choose(
    frames: usize,
    sequences: usize,
    opts: &SparseOptions,
    reach_given: bool,
) -> ScanChoice {
    let budget_pairs = opts.budget_pairs as u64 * 1_000_000;
    let budget_bytes = opts.budget_memory as u64 * 1_000_000;
    let fits = |e: &ScanEstimate| {
        (budget_pairs == 0 || e.full_measures <= budget_pairs)
            && (budget_bytes == 0 || e.bytes <= budget_bytes)
    };
    let full = estimate(frames, sequences, opts, 0);
    let (chosen, reason) = if reach_given {
        (
            estimate(frames, sequences, opts, opts.reach),
            ScanReason::Given,
        )
    } else if fits(&full) {
        (full, ScanReason::Fits)
    } else if MIN_REACH + 1 >= sequences {
        (full, ScanReason::FewSequences)
    } else {
        match (MIN_REACH..sequences - 1)
            .rev()
            .map(|r| estimate(frames, sequences, opts, r))
            .find(fits)
        {
            Some(e) => (e, ScanReason::Budget),
            None => (
                estimate(frames, sequences, opts, MIN_REACH),
                ScanReason::OverBudget,
            ),
        }
    };
    ScanChoice {
        frames,
        sequences,
        full,
        chosen,
        reason,
        budget_pairs,
        budget_bytes,
    }
}

impl ScanChoice {
    /// The options to build with: `opts` with the chosen reach.
    pub fn options(&self, opts: &SparseOptions) -> SparseOptions {
        SparseOptions {
            reach: self.chosen.reach,
            ..*opts
        }
    }

    /// One line for people: "10,014 frames, 34 sequences: the full scan ≈
    /// 11.8 M pairs compared, 16.9 M full measures, 0.99 GB → the full
    /// scan (budget …)".
    pub fn describe(&self) -> String {
        let m = |v: u64| format!("{:.1} M", v as f64 / 1e6);
        let gb = |v: u64| format!("{:.2} GB", v as f64 / 1e9);
        let budget = match (self.budget_pairs, self.budget_bytes) {
            (0, 0) => "no budget".to_string(),
            (p, 0) => format!("budget {} full measures", m(p)),
            (0, b) => format!("budget {}", gb(b)),
            (p, b) => format!("budget {} full measures, {}", m(p), gb(b)),
        };
        let c = &self.chosen;
        let chosen = match self.reason {
            ScanReason::Fits => "the full scan".to_string(),
            ScanReason::FewSequences => format!(
                "the full scan (over the {budget}, but {} sequences are too few for a reach of {MIN_REACH} to bound it)",
                self.sequences
            ),
            _ if c.reach == 0 => "the full scan (given)".to_string(),
            r => format!(
                "reach {} ({}: {} of {} sequence pairs scanned, the far search on {} ≈ {} pairs, {} full measures, {})",
                c.reach,
                match r {
                    ScanReason::Given => "given",
                    ScanReason::OverBudget => "the least the rule takes; over the budget",
                    _ => "the largest within the budget",
                },
                crate::util::budget::thousands(c.sequence_pairs as u128),
                crate::util::budget::thousands(self.full.sequence_pairs as u128),
                crate::util::budget::thousands(c.far_pairs as u128),
                m(c.pairs),
                m(c.full_measures),
                gb(c.bytes)
            ),
        };
        format!(
            "{} frames, {} sequences: the full scan ≈ {} pairs compared, {} full measures, {} → {chosen} ({budget})",
            crate::util::budget::thousands(self.frames as u128),
            self.sequences,
            m(self.full.pairs),
            m(self.full.full_measures),
            gb(self.full.bytes)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Generated counts: small databases keep the full scan, large ones get
    /// a reach of at least [`MIN_REACH`] within the budget, an explicit
    /// reach is kept, and the estimates grow with what they count.
    #[test]
    fn the_full_scan_is_kept_where_it_fits_and_a_reach_chosen_where_not() {
        let o = SparseOptions::default();
        // Where the full scan ran (sessions 32-39) and a sweep of smaller
        // databases of as many frames per sequence (about 300).
        for (frames, seqs) in [(1014, 5), (3896, 11), (4004, 12), (10014, 34), (30016, 98)] {
            let c = choose(frames, seqs, &o, false);
            assert_eq!(c.reason, ScanReason::Fits, "{}", c.describe());
            assert_eq!(c.chosen, c.full);
            assert_eq!(
                c.options(&o),
                o,
                "the full scan's options are the default's"
            );
        }
        for k in 1..=30 {
            let (frames, seqs) = (300 * k, k);
            assert_eq!(choose(frames, seqs, &o, false).chosen.reach, 0, "{k}");
        }
        // 10⁵ frames in 321 sequences: a reach of at least 16 within 8 GB.
        let big = choose(100_009, 321, &o, false);
        assert!(big.full.pairs > 500_000_000, "{}", big.describe());
        assert!(big.full.bytes > 16_000_000_000, "{}", big.describe());
        assert_eq!(big.reason, ScanReason::Budget, "{}", big.describe());
        assert!(big.chosen.reach >= MIN_REACH);
        assert!(big.chosen.bytes <= 8_000_000_000);
        assert!(big.chosen.full_measures <= 250_000_000);
        assert!(big.chosen.far_pairs > 0);
        assert_eq!(big.options(&o).reach, big.chosen.reach);
        // The next reach would not fit: the largest that does.
        let next = estimate(100_009, 321, &o, big.chosen.reach + 1);
        assert!(next.bytes > 8_000_000_000 || next.full_measures > 250_000_000);
        // The same frames in fewer, longer sequences: the full scan fits.
        assert_eq!(choose(50_000, 34, &o, false).reason, ScanReason::Fits);
        assert_eq!(choose(50_000, 400, &o, false).reason, ScanReason::Budget);
        // Many short sequences: the sequence pairs alone are over.
        let many = choose(20_000, 2000, &o, false);
        assert_ne!(many.chosen.reach, 0, "{}", many.describe());
        // Ten times the frames: over the budget even at 16, said so.
        let huge = choose(1_000_090, 3210, &o, false);
        assert_eq!(huge.reason, ScanReason::OverBudget);
        assert_eq!(huge.chosen.reach, MIN_REACH);
        // Too few sequences for a reach to bound anything: the full scan.
        let few = choose(2_000_000, 17, &o, false);
        assert_eq!(
            (few.reason, few.chosen.reach),
            (ScanReason::FewSequences, 0)
        );
        // An explicit reach wins, both ways.
        let given = SparseOptions { reach: 8, ..o };
        let c = choose(10014, 34, &given, true);
        assert_eq!((c.reason, c.chosen.reach), (ScanReason::Given, 8));
        let c = choose(100_009, 321, &o, true);
        assert_eq!((c.reason, c.chosen.reach), (ScanReason::Given, 0));
        // No budget: the full scan whatever the size.
        let unbounded = SparseOptions {
            budget_pairs: 0,
            budget_memory: 0,
            ..o
        };
        assert_eq!(choose(100_009, 321, &unbounded, false).chosen.reach, 0);
        // A smaller budget bounds 10⁴ frames too.
        let tight = SparseOptions {
            budget_memory: 500,
            ..o
        };
        assert_eq!(choose(10014, 34, &tight, false).chosen.reach, MIN_REACH);
        // Monotone: more frames, more sequences or a larger reach never
        // estimate less.
        for r in [0, 16, 32] {
            let a = estimate(50_000, 200, &o, r);
            for b in [estimate(60_000, 200, &o, r), estimate(50_000, 240, &o, r)] {
                assert!(
                    b.pairs >= a.pairs && b.bytes >= a.bytes && b.full_measures >= a.full_measures
                );
            }
        }
        let by_reach: Vec<u64> = (16..60)
            .map(|r| estimate(50_000, 200, &o, r).pairs)
            .collect();
        assert!(by_reach.windows(2).all(|w| w[0] <= w[1]), "{by_reach:?}");
    }

    /// The estimates against the builds they were fitted on (sessions
    /// 32-39) and the later ones: stored pairs within 15 %; memory (peak
    /// RSS of `db build DIR --similarity sparse --json` on the 2,600-vertex
    /// pool; 10⁵ the default command) within −5 / +30 % (the small builds'
    /// fixed part is overestimated): session 42's builds (the values
    /// evaluated straight into the rows) up to 10⁴, session 41's at 3×10⁴
    /// and 10⁵ (4 bytes a pair more at their peak: no build of session
    /// 42's code at those sizes was measured; the constants were not
    /// refitted, as that alone moves the rule's reach at 10⁵ — 29 → 30).
    #[test]
    fn the_estimate_is_near_the_measured_builds() {
        let o = SparseOptions::default();
        let no_far = SparseOptions { far: 0, ..o };
        // (frames, sequences, reach, options, pairs, peak KB or 0)
        let measured = [
            (1014, 5, 0, o, 271_066u64, 95_456u64),
            (3234, 10, 0, o, 1_511_677, 206_012),
            (3896, 11, 0, o, 2_046_957, 0),
            (4004, 12, 0, o, 2_159_933, 0),
            (10014, 34, 0, o, 11_649_747, 715_768),
            (30016, 98, 0, o, 104_543_698, 0),
            (30016, 98, 0, o, 104_546_669, 3_519_016),
            (10014, 34, 16, no_far, 7_156_415, 0),
            (30016, 98, 16, no_far, 25_289_973, 0),
            (100_009, 321, 16, no_far, 78_436_670, 0),
            (10014, 34, 16, o, 7_263_095, 0),
            (100_009, 321, 16, o, 92_171_575, 0),
            (100_009, 321, 16, o, 99_231_466, 0),
            (100_009, 321, 29, o, 141_513_693, 7_338_624),
        ];
        for (frames, seqs, reach, opts, pairs, kb) in measured {
            let e = estimate(frames, seqs, &opts, reach);
            let r = e.pairs as f64 / pairs as f64;
            assert!((0.85..1.15).contains(&r), "{frames} {reach}: {r}");
            if kb > 0 {
                let r = e.bytes as f64 / (kb as f64 * 1024.0);
                assert!((0.95..1.3).contains(&r), "{frames} {reach}: memory {r}");
            }
        }
    }
}
