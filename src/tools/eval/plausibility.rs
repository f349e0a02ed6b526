//! The plausibility report of a result: every check of this module on one
//! sequence, next to the same checks on the character's own captured frames,
//! with a warning wherever the result leaves that range.
//!
//! Acceptance line for the head (issue 17): a result's head-to-torso p95
//! should not exceed the database's own p95 by more than 3°.

use super::EvalError;
use super::feet::{Feet, FootOptions, Sliding};
use super::ground::{Ground, floor_height, ground, lowest_heights};
use super::head::{HeadOptions, HeadTorso};
use super::knee::knee_hyperextension;
use super::summary::EvalSummary;
use super::triangles::{OffRing, RestTriangles, TurnedOverCount};
use crate::db::Character;
use crate::deform::TurnedOver;
use crate::embed::Embedding;
use crate::embed::regress::Regressor;
use crate::mesh::Mesh;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// How far a result may leave the reference before it is warned about.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Head-to-torso p95 above the reference's p95 (degrees). Default: 3.
    pub head_margin_deg: f64,
    /// Head-to-torso p95 when there is no reference (degrees). Default: 10.
    pub head_deg: f64,
    /// Largest penetration above the reference's largest (cm). Default: 2.
    pub penetration_margin_cm: f64,
    /// Median floating above the reference's p95 (or above the floor,
    /// without a reference) (cm). Default: 3.
    pub floating_margin_cm: f64,
    /// Largest knee hyper-extension above the reference's (degrees). Default: 5.
    pub knee_margin_deg: f64,
    /// Mean sliding per contact frame above the reference's (cm). Default: 0.5.
    pub sliding_margin_cm: f64,
    /// Triangles turned over against the rest frame in one frame above the
    /// reference's most in a frame (the rest frame's none, without a
    /// reference), as a share of the mesh's triangles. Default: 0 (any
    /// frame with more than the capture shows is warned about).
    pub turned_over_margin: f64,
    /// A vertex's distance from the centroid of its one-ring above the
    /// reference's largest (the rest frame's, without a reference), in its
    /// mean rest edge lengths ([`OffRing`]). Default: 4 (the real samba
    /// capture reads up to 1.6 and results retargeted onto it up to 4.1;
    /// the single-vertex spikes a faulty repair made read 9.5 to 98).
    pub off_ring_margin: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            head_margin_deg: 3.0,
            head_deg: 10.0,
            penetration_margin_cm: 2.0,
            floating_margin_cm: 3.0,
            knee_margin_deg: 5.0,
            sliding_margin_cm: 0.5,
            turned_over_margin: 0.0,
            off_ring_margin: 4.0,
        }
    }
}

/// Options of a [`Checker`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PlausibilityOptions {
    /// The head-to-torso vertex sets.
    pub head: HeadOptions,
    /// Soles and contact.
    pub feet: FootOptions,
    /// Warning limits.
    pub limits: Limits,
}

/// The checks on the character's own frames (a database's captured frames,
/// or a scan's rest frame).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Baseline {
    /// What was measured (e.g. "database 'samba' (175 frames)").
    pub source: String,
    /// Frames measured.
    pub frames: usize,
    /// |head-to-torso angle| (degrees).
    pub head_torso_deg: EvalSummary,
    /// Foot sliding.
    pub foot_sliding: Sliding,
    /// Penetration and floating (cm).
    pub ground: Ground,
    /// Knee hyper-extension (degrees).
    pub knee_hyperextension_deg: EvalSummary,
    /// Triangles turned over against the rest frame in the captured frames
    /// (a captured fold; none on a scan's rest frame).
    pub turned_over: TurnedOverCount,
    /// The vertex farthest off its one-ring in the captured frames (frames
    /// counted across the sequences).
    pub off_ring: OffRing,
}

/// The old name of [`Baseline`] (before session 40).
#[deprecated(note = "renamed Baseline (old name Reference)")]
pub type Reference = Baseline; // old name

/// Bump when a check's measure changes: the database's cached reference
/// (`cache/plausibility-reference.json`) is then measured again.
pub(crate) const REFERENCE_VERSION: u32 = 1;

/// The database's floor and reference as cached beside its frames.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct CachedReference {
    key: u64,
    floor: f64,
    reference: Baseline,
}

/// The reference cache of the database `dir`.
pub fn reference_path(dir: &std::path::Path) -> std::path::PathBuf {
    crate::db::cache::cache_dir(dir).join("plausibility-reference.json")
}

/// The cached floor and reference when the file is there, well formed and
/// of `key`; `None` otherwise (a file that cannot be used is said in the
/// log and measured again).
fn read_reference(path: &std::path::Path, key: u64) -> Option<CachedReference> {
    let text = match crate::util::fsutil::read_text(path) {
        Ok(t) => t,
        Err(e) if e.source.kind() == std::io::ErrorKind::NotFound => return None,
        Err(e) => {
            tracing::warn!("{e}; measuring the plausibility reference again");
            return None;
        }
    };
    match serde_json::from_str::<CachedReference>(&text) {
        Ok(c) if c.key == key => Some(c),
        Ok(_) => None,
        Err(e) => {
            tracing::warn!(
                "{}: {e}; measuring the plausibility reference again",
                path.display()
            );
            None
        }
    }
}

/// The key the reference cache of the loaded character `ch` must carry
/// for a retarget (its checker, default options) to read it: what
/// `inspect` judges `cache/plausibility-reference.json` by.
pub(crate) fn reference_key_for(ch: &Character) -> Result<u64, EvalError> {
    let neutral = crate::pose::retarget::character_neutral(ch.rest_pose(), ch.poses());
    let c = Checker::unmeasured(ch, &neutral, PlausibilityOptions::default())?;
    Ok(c.reference_key(ch, &neutral))
}

/// The reference cache file `path` read strictly (`inspect`): its key,
/// floor (metres) and reference, or why it cannot be read.
pub(crate) fn read_reference_file(path: &std::path::Path) -> Result<(u64, f64, Baseline), String> {
    let text = crate::util::fsutil::read_text(path).map_err(|e| e.to_string())?;
    let c: CachedReference = serde_json::from_str(&text)
        .map_err(|e| format!("{}: not a plausibility reference ({e})", path.display()))?;
    Ok((c.key, c.floor, c.reference))
}

fn write_reference(
    path: &std::path::Path,
    c: &CachedReference,
) -> Result<(), crate::util::fsutil::FsError> {
    let text = serde_json::to_string(c).map_err(|e| crate::util::fsutil::FsError {
        path: path.to_path_buf(),
        source: std::io::Error::other(e),
    })?;
    crate::util::fsutil::write_bytes_atomic(path, text.as_bytes())
}

/// The plausibility of one result sequence.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Plausibility {
    /// Frames measured.
    pub frames: usize,
    /// |head-to-torso angle| relative to rest (degrees; see [`HeadTorso`]).
    pub head_torso_deg: EvalSummary,
    /// The rest frame's `∠(chin→crown, hips→chin)` (degrees).
    pub head_torso_rest_deg: f64,
    /// Foot sliding during contact.
    pub foot_sliding: Sliding,
    /// Penetration and floating (cm).
    pub ground: Ground,
    /// The floor height along up (metres).
    pub floor_m: f64,
    /// Knee hyper-extension of the skeleton extracted from each frame (degrees).
    pub knee_hyperextension_deg: EvalSummary,
    /// Triangles turned over against the character's rest frame
    /// ([`super::triangles`]), with what the deformation's repair left
    /// (`retarget` only) in its `deformation`.
    pub turned_over: TurnedOverCount,
    /// The vertex farthest off its one-ring ([`OffRing`]): a single vertex
    /// shot off the surface.
    pub off_ring: OffRing,
    /// The same checks on the character's own frames.
    pub reference: Option<Baseline>,
    /// |head-to-trunk angle| of the driving clip on its own skeleton,
    /// relative to its neutral carriage (degrees;
    /// [`crate::pose::retarget::clip_head_trunk_deg`]), when known. A clip
    /// whose head moves further than the database's does (a bow, a kick)
    /// is held to its own range: the head line is the larger p95 + margin.
    pub clip_head_torso_deg: Option<EvalSummary>,
    /// The driving clip's own foot glide while touching its ground, scaled
    /// to the character (cm per touching foot-frame;
    /// [`crate::pose::retarget::clip_foot_glide_cm`]), when known: a walk's
    /// feet pass through the touching band at heel strike and toe-off, so
    /// the result is warned about only when it glides more than its clip.
    pub clip_foot_glide_cm_per_frame: Option<f64>,
    /// Whether floating and penetration are measured from the driving
    /// clip's own ground under each foot (its floor raised under each
    /// footfall on a step, [`crate::pose::retarget::foot_ground_offsets`])
    /// rather than the floor.
    pub on_clip_ground: bool,
    /// Where the result leaves the reference (or the absolute limits).
    pub warnings: Vec<String>,
    /// Signed head-to-torso angle per frame (degrees).
    pub head_torso_per_frame: Vec<f64>,
    /// The character has no head ([`crate::embed::Embedding::absent`]):
    /// the head-to-torso angle is not measured (0) and not warned about,
    /// said once in [`Plausibility::text`]. Not written when false.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub headless: bool,
}

/// Per-frame series of one sequence, pooled to make a [`Baseline`].
struct Series {
    head: Vec<f64>,
    lowest: Vec<f64>,
    knee: Vec<f64>,
    sliding: Sliding,
    turned: Vec<usize>,
    off_ring: Vec<(f64, u32, f64)>,
}

/// Everything a character's checks need, chosen once on its rest frame.
#[derive(Debug, Clone)]
pub struct Checker {
    /// Head-to-torso vertex sets.
    pub head: HeadTorso,
    /// Soles.
    pub feet: Feet,
    /// Joint regressors of the rig (for the knees).
    pub regressors: Vec<Regressor>,
    /// The rest frame the triangles are compared with.
    pub triangles: RestTriangles,
    /// Up in the measured frames.
    pub up: DVec3,
    /// Floor height along `up` (units of the measured frames).
    pub floor: f64,
    /// Metres per unit of the measured frames (1 for databases, which are
    /// measured in metres). Default: 1.
    pub metres_per_unit: f64,
    /// Frame rate of the measured frames.
    pub fps: f64,
    /// Options.
    pub opts: PlausibilityOptions,
    /// The character's own figures, when known.
    pub reference: Option<Baseline>,
    /// The character has no head: [`Checker::head`] has no vertices and
    /// the head checks are skipped.
    pub headless: bool,
}

impl Checker {
    /// A checker for frames in metres along `up`, with the vertex sets
    /// chosen on `rest` (in the rig's space, the rig's `up`), whose
    /// triangles are compared with the result's. The floor is `floor`,
    /// else the rest frame's lowest point along `up`.
    pub fn new(
        rest_mesh: &Mesh,
        rig: &Embedding,
        up: DVec3,
        floor: Option<f64>,
        fps: f64,
        opts: PlausibilityOptions,
    ) -> Result<Checker, EvalError> {
        let rest = rest_mesh.positions();
        let rig_up = DVec3::from_array(rig.up);
        let pelvis = rig
            .joints
            .get(crate::rig::Canonical::Pelvis.index())
            .map(|j| DVec3::from_array(*j));
        let headless = rig.absent.iter().any(|a| a == "head");
        let head = if headless {
            HeadTorso::absent(rest.len())
        } else {
            HeadTorso::with_pelvis(rest, &rig.labels, rig_up, pelvis, &opts.head)?
        };
        let feet = Feet::new(rest, &rig.labels, rig_up, &opts.feet)?;
        let floor = floor.unwrap_or_else(|| {
            lowest_heights(rest, rest.len(), up)
                .first()
                .copied()
                .unwrap_or(0.0)
        });
        let triangles = RestTriangles::new(rest, rest_mesh.triangles())?;
        Ok(Checker {
            head,
            feet,
            regressors: rig.regressors.clone(),
            triangles,
            up: up.normalize_or(DVec3::Y),
            floor,
            metres_per_unit: 1.0,
            fps,
            opts,
            reference: None,
            headless,
        })
    }

    /// The checker of a database character, for frames in metres, Y-up (as
    /// `retarget` writes them), with the database's floor (median lowest
    /// point of its frames) and its own figures as the reference.
    pub fn for_character(ch: &Character, opts: PlausibilityOptions) -> Result<Checker, EvalError> {
        let neutral = crate::pose::retarget::character_neutral(ch.rest_pose(), ch.poses());
        Checker::for_character_with(ch, &neutral, opts)
    }

    /// [`Checker::for_character`] with the character's neutral pose
    /// (`pose::retarget::character_neutral`) found already: a prepared
    /// character holds it (`drive::Prepared::neutral`), so a job finds it
    /// once (issue 40).
    pub fn for_character_with(
        ch: &Character,
        neutral: &crate::pose::retarget::CharacterNeutral,
        opts: PlausibilityOptions,
    ) -> Result<Checker, EvalError> {
        let mut c = Checker::unmeasured(ch, neutral, opts)?;
        // The floor and the reference are read from the database's cache
        // when current (issue 43: measuring them reads every frame, 2.4 GB
        // at 10⁴ frames), else measured and cached.
        let path = reference_path(ch.dir());
        let key = c.reference_key(ch, neutral);
        if let Some(cached) = read_reference(&path, key) {
            c.floor = cached.floor;
            c.reference = Some(cached.reference);
            return Ok(c);
        }
        let (floor, reference) = c.measure_database(ch);
        c.floor = floor;
        let cached = CachedReference {
            key,
            floor,
            reference,
        };
        if let Err(e) = write_reference(&path, &cached) {
            tracing::warn!("the plausibility reference is not cached: {e}");
        }
        c.reference = Some(cached.reference);
        Ok(c)
    }

    /// [`Checker::for_character_with`] before the floor and the reference
    /// are read or measured.
    fn unmeasured(
        ch: &Character,
        neutral: &crate::pose::retarget::CharacterNeutral,
        opts: PlausibilityOptions,
    ) -> Result<Checker, EvalError> {
        let mut c = Checker::new(
            ch.topology(),
            ch.rig(),
            DVec3::Y,
            Some(0.0),
            ch.manifest().fps,
            opts,
        )?;
        // The triangles against the rest frame in the frames' own metres
        // (a rigid alignment relates axes, not units).
        let rest = ch.topology_metres();
        c.triangles = RestTriangles::new(rest.positions(), rest.triangles())?;
        // The head's zero is the character's neutral: its rest frame when
        // that stands upright, else the database frame nearest neutral
        // (`pose::retarget::character_neutral`), the attitude a clip standing
        // neutrally is retargeted onto. Measured from a bent rest frame (a
        // stride, a bow) every frame would read its difference from that
        // pose.
        if let crate::pose::retarget::NeutralSource::Frame(i) = neutral.source
            && i < ch.frame_count()
        {
            c.head.rest_deg = c
                .head
                .raw_deg(ch.frame(crate::graph::FlatFrame::from_index(i)));
        }
        Ok(c)
    }

    /// The floor (median lowest point of the database's frames) and the
    /// checks on every sequence, read from the mapped frames one sequence
    /// at a time (no copy of the frames; each sequence's pages released
    /// after use): the same values, in the same order, as when every frame
    /// was copied out first.
    fn measure_database(&mut self, ch: &Character) -> (f64, Baseline) {
        let n = ch.n();
        let store = ch.frame_store();
        let all = store.all();
        let seq = |q: &crate::similarity::Span| -> &[[f64; 3]] {
            all.get(q.start * n..(q.start + q.len) * n).unwrap_or(&[])
        };
        let sequences = ch.graph().sequences();
        let mut lowest = Vec::with_capacity(ch.frame_count());
        for q in sequences {
            lowest.extend(lowest_heights(seq(q), n, DVec3::Y));
            store.release(q.start, q.len);
        }
        self.floor = floor_height(&lowest);
        let series: Vec<Series> = sequences
            .iter()
            .map(|q| {
                let s = self.series(seq(q), n);
                store.release(q.start, q.len);
                s
            })
            .collect();
        let reference = self.pool(
            &format!(
                "database '{}' ({} frames)",
                ch.manifest().name,
                lowest.len()
            ),
            &series,
        );
        (self.floor, reference)
    }

    /// The key of the cached reference: the character's frames, rig and
    /// skeletons ([`Character::cache_key`]), the rig's labels and
    /// regressors, the options, the head's zero and
    /// [`REFERENCE_VERSION`].
    fn reference_key(
        &self,
        ch: &Character,
        neutral: &crate::pose::retarget::CharacterNeutral,
    ) -> u64 {
        let mut h = crate::db::cache::KeyHasher::default();
        h.text("plausibility reference", &REFERENCE_VERSION.to_string());
        h.text("character", &ch.cache_key().to_string());
        h.text("options", &format!("{:?}", self.opts));
        h.text("neutral", &format!("{:?}", neutral.source));
        h.text("head zero", &self.head.rest_deg.to_bits().to_string());
        h.text("fps", &self.fps.to_bits().to_string());
        let rig = ch.rig();
        h.text("labels", &format!("{:?}", rig.labels));
        h.text("regressors", &format!("{:?}", rig.regressors));
        h.finish()
    }

    /// Sets the reference to the checks on `sequences` (each frame-major,
    /// metres along `up`), e.g. a synthetic database's sequences.
    pub fn set_reference(&mut self, source: &str, sequences: &[&[[f64; 3]]], n: usize) {
        let series: Vec<Series> = sequences.iter().map(|f| self.series(f, n)).collect();
        self.reference = Some(self.pool(source, &series));
    }

    fn series(&self, frames: &[[f64; 3]], n: usize) -> Series {
        self.series_on(frames, n, [&[], &[]])
    }

    /// The series of `frames` with the ground under foot `f` (left,
    /// right) raised by `raised[f][t]` metres at frame `t`. The lowest
    /// height of a frame is that of whichever is nearest its ground (or
    /// deepest below it): each foot's lowest sole vertex above its own
    /// ground, and the lowest vertex of the body above the lower of the
    /// two. Penetration is then any foot below the ground under it (or
    /// the body below the lower), floating the foot nearest its ground
    /// above it. One ground per frame cannot be right for both: CMU 03_02
    /// stands one foot on a block while the other is in the air over the
    /// floor beside it, and measured from the floor the foot on the block
    /// read as floating (the floating median rose 0.1 → 0.9 cm on samba),
    /// measured from the block's top the foot over the floor as sunk
    /// through it.
    fn series_on(&self, frames: &[[f64; 3]], n: usize, raised: [&[f64]; 2]) -> Series {
        let knee = frames
            .chunks_exact(n.max(1))
            .map(|f| {
                let p = std::array::from_fn(|j| {
                    self.regressors.get(j).map_or(DVec3::ZERO, |r| r.apply(f))
                });
                let k = knee_hyperextension(&p);
                k[0].max(k[1])
            })
            .collect();
        Series {
            head: self.head.series(frames, n),
            lowest: self.nearest_ground(frames, n, raised),
            knee,
            sliding: self.feet.sliding_on(
                frames,
                n,
                self.up,
                self.floor,
                raised,
                self.fps,
                self.metres_per_unit,
                &self.opts.feet,
            ),
            turned: self.triangles.per_frame(frames),
            off_ring: self.triangles.off_ring_per_frame(frames),
        }
    }

    /// Per frame, the height (metres) above the floor, less its ground's
    /// raise, of whichever of the two feet and the body is nearest its
    /// ground (see [`Checker::series_on`]); the lowest vertex's height
    /// when nothing is raised.
    fn nearest_ground(&self, frames: &[[f64; 3]], n: usize, raised: [&[f64]; 2]) -> Vec<f64> {
        let m = self.metres_per_unit;
        let at = |r: &[f64], t: usize| r.get(t).copied().unwrap_or(0.0);
        lowest_heights(frames, n, self.up)
            .into_iter()
            .zip(frames.chunks_exact(n.max(1)))
            .enumerate()
            .map(|(t, (h, f))| {
                let g = [at(raised[0], t), at(raised[1], t)];
                let feet = self.feet.soles.iter().zip(g).map(|(sole, g)| {
                    sole.iter()
                        .filter_map(|&v| f.get(v as usize))
                        .map(|p| DVec3::from_array(*p).dot(self.up))
                        .fold(f64::INFINITY, f64::min)
                        * m
                        - g
                });
                feet.fold(h * m - g[0].min(g[1]), f64::min)
            })
            .collect()
    }

    fn pool(&self, source: &str, series: &[Series]) -> Baseline {
        let cat = |f: fn(&Series) -> &Vec<f64>| -> Vec<f64> {
            series.iter().flat_map(|s| f(s).iter().copied()).collect()
        };
        let mut sliding = Sliding::default();
        for s in series {
            sliding.contact_frames += s.sliding.contact_frames;
            sliding.total_cm += s.sliding.total_cm;
            sliding.max_cm_per_frame = sliding.max_cm_per_frame.max(s.sliding.max_cm_per_frame);
        }
        sliding.mean_cm_per_frame = sliding.total_cm / sliding.contact_frames.max(1) as f64;
        let touching: f64 = series
            .iter()
            .map(|s| s.sliding.touching_mean_cm_per_frame * s.sliding.touching_frames as f64)
            .sum();
        sliding.touching_frames = series.iter().map(|s| s.sliding.touching_frames).sum();
        sliding.touching_mean_cm_per_frame = touching / sliding.touching_frames.max(1) as f64;
        let head = cat(|s| &s.head);
        Baseline {
            source: source.to_string(),
            frames: head.len(),
            head_torso_deg: HeadTorso::summary(&head),
            foot_sliding: sliding,
            ground: ground(&cat(|s| &s.lowest), self.floor * self.metres_per_unit),
            knee_hyperextension_deg: EvalSummary::of(&cat(|s| &s.knee)),
            turned_over: TurnedOverCount::of(
                &series
                    .iter()
                    .flat_map(|s| s.turned.iter().copied())
                    .collect::<Vec<_>>(),
                self.triangles.triangle_count(),
            ),
            off_ring: self.off_ring_of(
                &series
                    .iter()
                    .flat_map(|s| s.off_ring.iter().copied())
                    .collect::<Vec<_>>(),
            ),
        }
    }

    fn off_ring_of(&self, per_frame: &[(f64, u32, f64)]) -> OffRing {
        OffRing::of(per_frame, self.metres_per_unit, &self.triangles)
    }

    /// The plausibility of `frames` (frame-major, `n` vertices each, metres
    /// along `up`), with warnings against the reference (or the absolute
    /// limits). Nothing is logged here: the caller adds the driving clip's
    /// own ranges ([`Plausibility::with_clip_head`],
    /// [`Plausibility::with_clip_glide`]), which can withdraw a warning,
    /// and then logs the final ones ([`Plausibility::logged`]).
    pub fn measure(
        &self,
        frames: &[[f64; 3]],
        n: usize,
        turned_over: Option<TurnedOver>,
    ) -> Result<Plausibility, EvalError> {
        self.measure_on(frames, n, turned_over, None)
    }

    /// [`Checker::measure`] with floating, penetration and foot contact
    /// measured from the ground under each foot (left, right) raised by
    /// `raised[f][t]` metres above the floor at frame `t` (the driving
    /// clip's own ground under that foot,
    /// [`crate::pose::retarget::foot_ground_offsets`]), when given.
    pub fn measure_on(
        &self,
        frames: &[[f64; 3]],
        n: usize,
        turned_over: Option<TurnedOver>,
        raised: Option<&[Vec<f64>; 2]>,
    ) -> Result<Plausibility, EvalError> {
        if n != self.head.vertex_count() {
            return Err(EvalError::VertexCount {
                have: n,
                want: self.head.vertex_count(),
            });
        }
        let s = match raised {
            Some([l, r]) => self.series_on(frames, n, [l, r]),
            None => self.series_on(frames, n, [&[], &[]]),
        };
        let mut p = Plausibility {
            frames: s.head.len(),
            head_torso_deg: HeadTorso::summary(&s.head),
            head_torso_rest_deg: self.head.rest_deg,
            foot_sliding: s.sliding,
            ground: ground(&s.lowest, self.floor * self.metres_per_unit),
            floor_m: self.floor * self.metres_per_unit,
            knee_hyperextension_deg: EvalSummary::of(&s.knee),
            turned_over: TurnedOverCount {
                deformation: turned_over,
                ..TurnedOverCount::of(&s.turned, self.triangles.triangle_count())
            },
            off_ring: self.off_ring_of(&s.off_ring),
            reference: self.reference.clone(),
            clip_head_torso_deg: None,
            clip_foot_glide_cm_per_frame: None,
            on_clip_ground: raised.is_some(),
            warnings: Vec::new(),
            head_torso_per_frame: s.head,
            headless: self.headless,
        };
        p.warnings = warnings(&p, &self.opts.limits);
        Ok(p)
    }
}

/// Where `p` leaves its reference (or, without one, the absolute limits).
pub fn warnings(p: &Plausibility, l: &Limits) -> Vec<String> {
    let mut w = Vec::new();
    let h = p.head_torso_deg.p95;
    let clip = p.clip_head_torso_deg.map(|c| c.p95);
    match &p.reference {
        Some(r) => {
            let captured = r.head_torso_deg.p95;
            match clip {
                _ if p.headless => {}
                Some(c) if c > captured => {
                    if h > c + l.head_margin_deg {
                        w.push(format!(
                            "head-to-torso angle p95 {h:.1}° exceeds the clip's own p95 {c:.1}° + {:.0}° (median {:.1}°, max {:.1}°)",
                            l.head_margin_deg, p.head_torso_deg.median, p.head_torso_deg.max
                        ));
                    }
                }
                _ => {
                    if h > captured + l.head_margin_deg {
                        w.push(format!(
                            "head-to-torso angle p95 {h:.1}° exceeds the captured p95 {captured:.1}° + {:.0}° (median {:.1}°, max {:.1}°)",
                            l.head_margin_deg, p.head_torso_deg.median, p.head_torso_deg.max
                        ));
                    }
                }
            }
            let pen = p.ground.penetration_cm.max;
            if pen > r.ground.penetration_cm.max + l.penetration_margin_cm {
                w.push(format!(
                    "ground penetration up to {pen:.1} cm (captured: up to {:.1} cm)",
                    r.ground.penetration_cm.max
                ));
            }
            let fl = p.ground.floating_cm.median;
            if fl > r.ground.floating_cm.p95 + l.floating_margin_cm {
                w.push(format!(
                    "floating: median {fl:.1} cm above the floor (captured p95 {:.1} cm)",
                    r.ground.floating_cm.p95
                ));
            }
            let k = p.knee_hyperextension_deg.max;
            if k > r.knee_hyperextension_deg.max + l.knee_margin_deg {
                w.push(format!(
                    "knee hyper-extension up to {k:.1}° (captured: up to {:.1}°)",
                    r.knee_hyperextension_deg.max
                ));
            }
            let gl = p.foot_sliding.touching_mean_cm_per_frame;
            let captured = r.foot_sliding.touching_mean_cm_per_frame;
            match p.clip_foot_glide_cm_per_frame {
                // The clip's own glide, scaled: a walk's feet pass through
                // the touching band at heel strike and toe-off.
                Some(c) if c > captured => {
                    if gl > c + 2.0 * l.sliding_margin_cm {
                        w.push(format!(
                            "feet glide {gl:.2} cm per frame while touching the floor (the clip's own, scaled: {c:.2}; captured {captured:.2})"
                        ));
                    }
                }
                _ => {
                    if gl > captured + 2.0 * l.sliding_margin_cm {
                        w.push(format!(
                            "feet glide {gl:.2} cm per frame while touching the floor (captured {captured:.2})"
                        ));
                    }
                }
            }
            let sl = p.foot_sliding.mean_cm_per_frame;
            if sl > r.foot_sliding.mean_cm_per_frame + l.sliding_margin_cm {
                w.push(format!(
                    "foot sliding {sl:.2} cm per contact frame (captured {:.2})",
                    r.foot_sliding.mean_cm_per_frame
                ));
            }
        }
        None => {
            let line = clip.map_or(l.head_deg, |c| {
                c.max(l.head_deg - l.head_margin_deg) + l.head_margin_deg
            });
            if h > line && !p.headless {
                w.push(format!(
                    "head-to-torso angle p95 {h:.1}° from rest exceeds {line:.0}°"
                ));
            }
            if p.ground.penetration_cm.max > l.penetration_margin_cm {
                w.push(format!(
                    "ground penetration up to {:.1} cm",
                    p.ground.penetration_cm.max
                ));
            }
            if p.ground.floating_cm.median > l.floating_margin_cm {
                w.push(format!(
                    "floating: median {:.1} cm above the floor",
                    p.ground.floating_cm.median
                ));
            }
        }
    }
    if let Some(t) = p.turned_over.deformation
        && t.after > 0
    {
        w.push(format!("{} triangle-frames stay turned over", t.after));
    }
    if let Some(t) = turned_over_warning(p, l) {
        w.push(t);
    }
    if let Some(t) = off_ring_warning(p, l) {
        w.push(t);
    }
    w
}

/// The warning of a result with a vertex farther off its one-ring than the
/// captured frames show (the rest frame without a reference) +
/// [`Limits::off_ring_margin`].
fn off_ring_warning(p: &Plausibility, l: &Limits) -> Option<String> {
    let o = &p.off_ring;
    let captured = p.reference.as_ref().map(|r| r.off_ring.max_edge_lengths);
    let base = captured.unwrap_or(o.rest_edge_lengths);
    (o.max_edge_lengths > base + l.off_ring_margin).then(|| {
        format!(
            "vertex {} leaves its one-ring by {:.1} cm ({:.1} edge lengths) in frame {} ({}: up to {base:.1})",
            o.vertex,
            o.max_cm,
            o.max_edge_lengths,
            o.frame,
            if captured.is_some() {
                "captured"
            } else {
                "the rest frame"
            }
        )
    })
}

/// The warning of a result with more triangles turned over against the
/// rest frame in one frame than the captured frames show (the rest frame's
/// none without a reference) + [`Limits::turned_over_margin`].
fn turned_over_warning(p: &Plausibility, l: &Limits) -> Option<String> {
    let t = &p.turned_over;
    let captured = p.reference.as_ref().map(|r| r.turned_over.max_in_a_frame);
    let line = captured.unwrap_or(0) as f64 + l.turned_over_margin * t.triangles as f64;
    (t.max_in_a_frame as f64 > line).then(|| {
        format!(
            "{} of {} triangles turned over against the rest frame in frame {} ({} triangle-frames, {:.3} %, in {} of {} frames; {})",
            t.max_in_a_frame,
            t.triangles,
            t.worst_frame,
            t.triangle_frames,
            100.0 * t.fraction,
            t.frames_with_any,
            t.frames,
            match captured {
                Some(c) => format!("captured: up to {c} in a frame"),
                None => "the rest frame has none".into(),
            }
        )
    })
}

impl Plausibility {
    /// [`Plausibility::text`] of a headless character: the head line
    /// replaced by the note that its checks are skipped.
    fn text_headless(&self) -> String {
        let whole = Plausibility {
            headless: false,
            ..self.clone()
        }
        .text();
        let mut lines: Vec<&str> = whole.lines().collect();
        if let Some(l) = lines.iter_mut().find(|l| l.starts_with("  head-to-torso:")) {
            *l = "  no head: head checks skipped";
        }
        lines.join("\n") + if whole.ends_with('\n') { "\n" } else { "" }
    }

    /// Sets the driving clip's own head-to-trunk angles (`series`, per
    /// frame, degrees; [`crate::pose::retarget::clip_head_trunk_deg`]) and
    /// recomputes the warnings with `limits`: the head is then held to the
    /// larger of the captured range and the clip's own.
    pub(crate) fn with_clip_head(mut self, series: &[f64], limits: &Limits) -> Self {
        self.clip_head_torso_deg = Some(HeadTorso::summary(series));
        self.warnings = warnings(&self, limits);
        self
    }

    /// Sets the driving clip's own foot glide while touching its ground
    /// (cm per foot-frame, scaled to the character;
    /// [`crate::pose::retarget::clip_foot_glide_cm`]) and recomputes the
    /// warnings with `limits`: the feet are then warned about only when
    /// they glide more than the larger of the captured glide and the clip's.
    pub(crate) fn with_clip_glide(mut self, cm_per_frame: f64, limits: &Limits) -> Self {
        self.clip_foot_glide_cm_per_frame = cm_per_frame.is_finite().then_some(cm_per_frame);
        self.warnings = warnings(&self, limits);
        self
    }

    /// Logs each final warning with `tracing::warn!` (`SURFMOTION_LOG`)
    /// and returns the report: called once the clip's own ranges are set,
    /// so the log says what the report says (it once logged "feet glide
    /// 3.28 … (captured 1.02)" for CMU 02_02 on samba, whose report,
    /// against the clip's own glide, had no warning).
    pub fn logged(self) -> Self {
        for w in &self.warnings {
            tracing::warn!("{w}");
        }
        self
    }

    /// A short text block (a few lines) for the command line.
    pub fn text(&self) -> String {
        let r = self.reference.as_ref();
        let refd = |f: &dyn Fn(&Baseline) -> String| {
            r.map(|r| format!(" [captured {}]", f(r)))
                .unwrap_or_default()
        };
        if self.headless {
            return self.text_headless();
        }
        let mut s = format!(
            "plausibility over {} frames:\n  head-to-torso: median {:.1}°, p95 {:.1}°, max {:.1}°{}\n",
            self.frames,
            self.head_torso_deg.median,
            self.head_torso_deg.p95,
            self.head_torso_deg.max,
            refd(&|r| format!(
                "median {:.1}°, p95 {:.1}°",
                r.head_torso_deg.median, r.head_torso_deg.p95
            ))
        );
        if let Some(c) = self.clip_head_torso_deg {
            s += &format!(
                "  the clip's own head-to-trunk: median {:.1}°, p95 {:.1}°\n",
                c.median, c.p95
            );
        }
        s += &format!(
            "  feet: {:.2} cm sliding per contact frame ({} contact foot-frames), {:.2} cm/frame while touching{}\n",
            self.foot_sliding.mean_cm_per_frame,
            self.foot_sliding.contact_frames,
            self.foot_sliding.touching_mean_cm_per_frame,
            refd(&|r| format!(
                "{:.2}, {:.2}",
                r.foot_sliding.mean_cm_per_frame, r.foot_sliding.touching_mean_cm_per_frame
            ))
        );
        if let Some(c) = self.clip_foot_glide_cm_per_frame {
            s += &format!("  the clip's own foot glide while touching, scaled: {c:.2} cm/frame\n");
        }
        if self.on_clip_ground {
            s += "  ground: measured from the clip's own ground (raised on its steps)\n";
        }
        s += &format!(
            "  ground: penetration max {:.1} cm, floating median {:.1} cm; knees: hyper-extension max {:.1}°{}\n",
            self.ground.penetration_cm.max,
            self.ground.floating_cm.median,
            self.knee_hyperextension_deg.max,
            refd(&|r| format!(
                "{:.1} cm, {:.1} cm; {:.1}°",
                r.ground.penetration_cm.max,
                r.ground.floating_cm.median,
                r.knee_hyperextension_deg.max
            ))
        );
        let t = &self.turned_over;
        s += &format!(
            "  triangles turned over against the rest frame (not the retrieved frames the repair counts against): {}{}\n",
            t.describe(),
            refd(&|r| format!(
                "{} triangle-frames, up to {} in a frame",
                r.turned_over.triangle_frames, r.turned_over.max_in_a_frame
            ))
        );
        s += &format!(
            "  vertices off their one-ring: {}{}\n",
            self.off_ring.describe(),
            refd(&|r| format!("up to {:.1}", r.off_ring.max_edge_lengths))
        );
        if let Some(d) = t.deformation {
            s += &format!(
                "  the deformation's repair: {} triangle-frames turned over against the retrieved frames after the solve, {} after the repair\n",
                d.before, d.after
            );
        }
        for w in &self.warnings {
            s += &format!("  warning: {w}\n");
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(p95: f64) -> EvalSummary {
        EvalSummary {
            median: p95 / 2.0,
            p95,
            max: p95,
        }
    }

    fn sliding(touching_mean_cm_per_frame: f64) -> Sliding {
        Sliding {
            touching_mean_cm_per_frame,
            ..Sliding::default()
        }
    }

    /// A 10-frame result with head-to-torso p95 `head` (degrees) and feet
    /// gliding `glide` cm/frame when they touch, against a database whose
    /// head p95 is 7.7° and whose feet glide `db_glide`.
    fn result(head: f64, glide: f64, db_glide: f64) -> Plausibility {
        let reference = Baseline {
            source: "db".into(),
            frames: 10,
            head_torso_deg: summary(7.7),
            foot_sliding: sliding(db_glide),
            ground: Ground::default(),
            knee_hyperextension_deg: EvalSummary::default(),
            turned_over: TurnedOverCount::default(),
            off_ring: OffRing::default(),
        };
        Plausibility {
            frames: 10,
            head_torso_deg: summary(head),
            head_torso_rest_deg: 0.0,
            foot_sliding: sliding(glide),
            ground: Ground::default(),
            floor_m: 0.0,
            knee_hyperextension_deg: EvalSummary::default(),
            turned_over: TurnedOverCount::default(),
            off_ring: OffRing::default(),
            reference: Some(reference),
            clip_head_torso_deg: None,
            clip_foot_glide_cm_per_frame: None,
            on_clip_ground: false,
            warnings: Vec::new(),
            head_torso_per_frame: Vec::new(),
            headless: false,
        }
    }

    #[test]
    fn a_clip_whose_head_moves_more_than_the_database_is_held_to_its_own_range() {
        let p = result(20.0, 0.0, 0.0);
        let l = Limits::default();
        let head = |p: &Plausibility| p.warnings.iter().any(|w| w.contains("head-to-torso"));
        // Against the database alone: 20° > 7.7° + 3°.
        assert!(head(&p.clone().with_clip_head(&[0.0; 5], &l)));
        // A clip whose own head moves 18° (p95): within its range + 3°.
        let own = [18.0; 20];
        assert!(!head(&p.clone().with_clip_head(&own, &l)));
        // ... but not past it.
        assert!(head(&p.with_clip_head(&[12.0; 20], &l)));
    }

    #[test]
    fn feet_are_warned_about_only_when_they_glide_more_than_their_clip() {
        let p = result(2.0, 3.3, 1.0);
        let l = Limits::default();
        let glide = |p: &Plausibility| p.warnings.iter().any(|w| w.contains("glide"));
        // A walk (3.3 cm/frame) against a mostly planted dance (1.0): warned
        // without the clip's own figure...
        assert!(glide(&Plausibility {
            warnings: warnings(&p, &l),
            ..p.clone()
        }));
        // ... not when its clip glides as much (3.0, scaled) ...
        assert!(!glide(&p.clone().with_clip_glide(3.0, &l)));
        // ... and again when the result glides more than its clip.
        assert!(glide(&p.with_clip_glide(1.5, &l)));
    }
}
