//! Motion spaces and the parametric model of a database (Casas et al.
//! 2013, Sec. 3): each `[[space]]` of the manifest aligned
//! ([`super::align`]), its hybrid blend precomputed ([`super::hybrid`]),
//! its root motion and parameters measured ([`super::params`]), and the
//! reference similarities between every pair of spaces
//! ([`super::transition`]).

use super::ParamError;
use super::align::{Alignment, align, features};
use super::hybrid::{HybridBlend, HybridOptions};
use super::local::{RootTrack, local_frame, root_track, rotate};
pub use super::motion_space::{MotionSpace, SpaceParts};
use super::params::{ParamMap, Parameter, RootSteps, WEIGHT_STEP, measure};
use super::transition::{RefFeatures, SimilarityTable, TransitionOptions};
use crate::db::{MANIFEST, Manifest, SpaceEntry};
use crate::mesh::Mesh;
use crate::mesh::blend::Blender;
use crate::similarity::y_up;
use glam::DVec2;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Options of the model.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct MotionOptions {
    /// Bisection options (a space's `epsilon_mm` overrides `epsilon`).
    pub hybrid: HybridOptions,
    /// Transition search options.
    pub transition: TransitionOptions,
}

/// The parametric model of a database: its spaces and the similarity
/// tables between them.
#[derive(Debug, Clone)]
pub struct Motion {
    /// Frames per second (the database's).
    pub fps: f64,
    /// The topology in metres, Y-up (for output meshes).
    pub topology: Mesh,
    /// The spaces, in manifest order.
    pub spaces: Vec<MotionSpace>,
    /// `tables[s * S + t]`: reference similarities from space `s` to `t`
    /// (empty for `s = t`).
    pub tables: Vec<SimilarityTable>,
    /// Options it was built with.
    pub options: MotionOptions,
}

/// A sequence in metres, Y-up, with its root track.
struct Loaded {
    frames: Vec<[f64; 3]>,
    track: RootTrack,
}

/// Root steps of sequence `i` of an alignment (see [`RootSteps`]).
fn root_steps(al: &Alignment, i: usize, track: &RootTrack) -> RootSteps {
    let k = al.grid;
    let t = &al.times[i];
    let per_frame = |f: usize| -> [f64; 3] {
        let g = (f + 1).min(track.centre.len() - 1);
        let d = rotate(track.centre[g] - track.centre[f], -track.heading[f]);
        [d.x, d.y, track.heading[g] - track.heading[f]]
    };
    let mut step = Vec::with_capacity(k);
    let mut duration = Vec::with_capacity(k);
    for j in 0..k {
        let (ta, tb) = (t[j], t[j + 1].max(t[j]));
        let mut acc = [0.0; 3];
        let mut x = ta;
        while x < tb - 1e-9 {
            let (f, _, fr) = al.wrapped(i, x);
            // Always forward: a wrapped fraction a rounding short of 1
            // made `x + (1 - fr)` round to `x` itself, and the loop never
            // ended (`db build` of the README's gaits spaces spun for good).
            let end = tb.min((x + (1.0 - fr)).max(x + 1e-9));
            let w = (end - x).max(1e-9);
            let d = per_frame(f);
            for c in 0..3 {
                acc[c] += d[c] * w;
            }
            x = end;
        }
        step.push(acc);
        duration.push((tb - ta).max(1e-6));
    }
    RootSteps { step, duration }
}

/// What every space of [`Motion::build`] reads: the database, its units
/// and topology.
struct BuildCtx<'a> {
    dir: &'a Path,
    m: &'a Manifest,
    /// The manifest, named in errors.
    path: std::path::PathBuf,
    /// Metres per unit of the database.
    mpu: f64,
    z_up: bool,
    topo_file: &'a Mesh,
    /// Vertices of the topology.
    n: usize,
    fps: f64,
}

impl BuildCtx<'_> {
    fn space_err(&self, space: &str, msg: String) -> ParamError {
        ParamError::Space {
            path: self.path.clone(),
            space: space.to_string(),
            msg,
        }
    }

    /// A database position in metres, Y up.
    fn conv(&self, p: &[f64; 3]) -> [f64; 3] {
        (y_up(*p, self.z_up) * self.mpu).to_array()
    }

    /// Step 1 of [`Motion::build`], per space: loads the sequences of `sp`
    /// not yet in `loaded` (at the database's rate, its connectivity, at
    /// least 2 frames each), in metres, with their root tracks.
    fn load_sequences(
        &self,
        sp: &SpaceEntry,
        loaded: &mut std::collections::HashMap<String, Loaded>,
    ) -> Result<(), ParamError> {
        for q in &sp.sequences {
            if loaded.contains_key(q) {
                continue;
            }
            let entry = self
                .m
                .sequences
                .iter()
                .find(|s| &s.name == q)
                .ok_or_else(|| self.space_err(&sp.name, format!("no sequence '{q}'")))?;
            if let Some(f) = entry.fps
                && (f - self.fps).abs() > 1e-6 * self.fps
            {
                return Err(self.space_err(
                    &sp.name,
                    format!(
                        "sequence '{q}' is at {f} fps, the database at {}: a space's sequences play at the database's rate",
                        self.fps
                    ),
                ));
            }
            let seq = self.m.load_sequence(self.dir, entry)?;
            if seq.mesh().vertex_count() != self.n
                || seq.mesh().triangles() != self.topo_file.triangles()
            {
                return Err(self.space_err(
                    &sp.name,
                    format!("sequence '{q}': its connectivity differs from the topology"),
                ));
            }
            if seq.frame_count() < 2 {
                return Err(self.space_err(
                    &sp.name,
                    format!(
                        "sequence '{q}' has {} frame(s); a space needs at least 2 per sequence",
                        seq.frame_count()
                    ),
                ));
            }
            let frames: Vec<[f64; 3]> = seq.all_positions().iter().map(|p| self.conv(p)).collect();
            let track = root_track(&frames, self.n, self.fps);
            loaded.insert(q.clone(), Loaded { frames, track });
        }
        Ok(())
    }
}

/// Step 2 of [`Motion::build`]: the space `sp` from its `loaded` sequences:
/// phase alignment, the reference blocks on the aligned grid, root steps,
/// the hybrid blend (the blender factored once), the parameter map and the
/// measured parameters.
fn build_space(
    ctx: &BuildCtx,
    sp: &SpaceEntry,
    loaded: &std::collections::HashMap<String, Loaded>,
    blender: &Blender,
    opts: &MotionOptions,
) -> Result<MotionSpace, ParamError> {
    let (n, fps) = (ctx.n, ctx.fps);
    let seqs: Vec<&Loaded> = sp.sequences.iter().map(|q| &loaded[q]).collect();
    let feats: Vec<_> = seqs
        .iter()
        .map(|l| features(&l.frames, n, &l.track))
        .collect();
    let alignment = align(&feats, fps);
    let k = alignment.grid;
    let mut buf0 = vec![[0.0; 3]; n];
    let mut buf1 = vec![[0.0; 3]; n];
    let originals: Vec<Vec<f32>> = seqs
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let mut block = Vec::with_capacity(k * n * 3);
            for j in 0..k {
                let (f0, f1, fr) = alignment.wrapped(i, alignment.times[i][j]);
                let f1 = f1.min(l.track.centre.len() - 1);
                local_frame(&l.frames, n, &l.track, f0, &mut buf0);
                local_frame(&l.frames, n, &l.track, f1, &mut buf1);
                for (a, b) in buf0.iter().zip(&buf1) {
                    for c in 0..3 {
                        block.push((a[c] + (b[c] - a[c]) * fr) as f32);
                    }
                }
            }
            block
        })
        .collect();
    let steps: Vec<RootSteps> = seqs
        .iter()
        .enumerate()
        .map(|(i, l)| root_steps(&alignment, i, &l.track))
        .collect();
    let epsilon = sp.epsilon_mm.map_or(opts.hybrid.epsilon, |e| e * 1e-3);
    let hopts = HybridOptions {
        epsilon,
        ..opts.hybrid
    };
    let blend = HybridBlend::build(originals, n, k, blender, &hopts);
    let parameters: Vec<Parameter> = sp
        .parameters
        .iter()
        .filter_map(|p| Parameter::parse(p))
        .collect();
    let axis = match parameters.first() {
        Some(&p) => Some(ParamMap::fit(p, &steps, fps).map_err(|e| ctx.space_err(&sp.name, e))?),
        None => None,
    };
    let per = (1.0 / WEIGHT_STEP).round() as usize;
    let measured = (0..=(sp.sequences.len() - 1) * per)
        .map(|i| {
            let u = i as f64 / per as f64;
            let [s, t] = measure(&steps, u, fps);
            [u, s, t]
        })
        .collect();
    let parts = SpaceParts {
        name: sp.name.clone(),
        sequences: sp.sequences.clone(),
        parameters,
        alignment,
        pairs: blend.pairs.clone(),
        steps,
        axis,
        measured,
        epsilon,
    };
    MotionSpace::new(parts, blend).map_err(|e| ctx.space_err(&sp.name, e))
}

/// Step 3 of [`Motion::build`]: the reference similarity tables between
/// every ordered pair of spaces (empty on the diagonal).
fn similarity_tables(spaces: &[MotionSpace], fps: f64) -> Vec<SimilarityTable> {
    let feats: Vec<RefFeatures> = spaces.iter().map(|s| s.ref_features(fps)).collect();
    let count = spaces.len();
    let mut tables = Vec::with_capacity(count * count);
    for s in 0..count {
        for t in 0..count {
            tables.push(if s == t {
                SimilarityTable {
                    ks: 0,
                    kt: 0,
                    us: Vec::new(),
                    ut: Vec::new(),
                    sim: Vec::new(),
                }
            } else {
                SimilarityTable::new(&feats[s], &feats[t])
            });
        }
    }
    tables
}

impl Motion {
    /// Builds the model of the database in `dir` from its manifest's
    /// `[[space]]` entries (factoring the blender once for all spaces).
    pub fn build(dir: &Path, m: &Manifest, opts: &MotionOptions) -> Result<Motion, ParamError> {
        let path = dir.join(MANIFEST);
        let mpu = crate::mocap::units::parse_unit(&m.units)
            .map(|u| u.metres_per_unit)
            .unwrap_or(1.0);
        let z_up = m.up.eq_ignore_ascii_case("z");
        let topo_file = m.load_topology(dir)?;
        let mut ctx = BuildCtx {
            dir,
            m,
            path,
            mpu,
            z_up,
            topo_file: &topo_file,
            n: 0,
            fps: m.fps,
        };
        let topology = topo_file
            .with_positions(
                &topo_file
                    .positions()
                    .iter()
                    .map(|p| ctx.conv(p))
                    .collect::<Vec<_>>(),
            )
            .map_err(crate::mesh::MeshError::from)
            .map_err(crate::db::DbError::from)?;
        ctx.n = topology.vertex_count();
        let blender = Blender::new(&topology)?;
        let fps = m.fps;
        let mut loaded: std::collections::HashMap<String, Loaded> = Default::default();
        let mut spaces = Vec::new();
        for sp in &m.spaces {
            ctx.load_sequences(sp, &mut loaded)?;
            spaces.push(build_space(&ctx, sp, &loaded, &blender, opts)?);
        }
        let tables = similarity_tables(&spaces, fps);
        Ok(Motion {
            fps,
            topology,
            spaces,
            tables,
            options: *opts,
        })
    }

    /// The index of the space called `name`.
    pub fn space_index(&self, name: &str) -> Option<usize> {
        self.spaces.iter().position(|s| s.name() == name)
    }

    /// The similarity table from space `s` to space `t`.
    pub fn table(&self, s: usize, t: usize) -> &SimilarityTable {
        &self.tables[s * self.spaces.len() + t]
    }

    /// What was built, per space (for `db build` and `play` reports).
    pub fn summary(&self) -> Vec<SpaceSummary> {
        self.spaces
            .iter()
            .map(|s| SpaceSummary {
                name: s.name().to_owned(),
                sequences: s.sequences().to_owned(),
                cycles: s.alignment().cycles.iter().map(|c| c.period).collect(),
                cyclic: s.alignment().cycles.iter().map(|c| c.cyclic).collect(),
                alignment_rms_m: s.alignment().cost.clone(),
                phase_samples: s.grid(),
                references: s.blend().pairs.iter().map(|p| p.weights.clone()).collect(),
                hybrid_max_error_mm: s
                    .blend()
                    .pairs
                    .iter()
                    .map(|p| p.max_error * 1e3)
                    .fold(0.0, f64::max),
                epsilon_mm: s.epsilon() * 1e3,
                correction_bytes: s.blend().correction_bytes(),
                ranges: s
                    .parameters()
                    .iter()
                    .enumerate()
                    .map(|(i, p)| {
                        let idx = if *p == Parameter::Speed { 1 } else { 2 };
                        let (lo, hi) = match (&s.axis(), i) {
                            (Some(a), 0) => (a.range[0], a.range[1]),
                            _ => s
                                .measured()
                                .iter()
                                .map(|m| m[idx])
                                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                                    (a.min(x), b.max(x))
                                }),
                        };
                        ParamRange {
                            parameter: *p,
                            blended: i == 0,
                            min: lo,
                            max: hi,
                            fit: s.axis().filter(|_| i == 0).map(|a| a.fit),
                            roundtrip_error: s.axis().filter(|_| i == 0).map(|a| match a.fit {
                                super::params::FitKind::Quadratic => a.error_quadratic,
                                super::params::FitKind::Table => a.error_table,
                            }),
                            quadratic_error: s
                                .axis()
                                .as_ref()
                                .filter(|_| i == 0)
                                .map(|a| a.error_quadratic),
                        }
                    })
                    .collect(),
            })
            .collect()
    }
}

/// The valid range of one parameter of a space.
#[derive(Debug, Clone, Serialize)]
pub struct ParamRange {
    /// The parameter.
    pub parameter: Parameter,
    /// True for the blended (first) parameter; false: a steering `turn`
    /// (any value; the range shown is the blend's own turning).
    pub blended: bool,
    /// Lowest value.
    pub min: f64,
    /// Highest value.
    pub max: f64,
    /// The inverse map used.
    pub fit: Option<super::params::FitKind>,
    /// Its largest round-trip error (parameter units).
    pub roundtrip_error: Option<f64>,
    /// The quadratic's (the paper's) round-trip error.
    pub quadratic_error: Option<f64>,
}

/// What a space holds (reports).
#[derive(Debug, Clone, Serialize)]
pub struct SpaceSummary {
    /// Name.
    pub name: String,
    /// Sequences.
    pub sequences: Vec<String>,
    /// Cycle length of each sequence (frames, fractional).
    pub cycles: Vec<f64>,
    /// Whether each sequence repeats (else its whole length loops).
    pub cyclic: Vec<bool>,
    /// RMS vertex distance along each sequence's warping path (metres).
    pub alignment_rms_m: Vec<f64>,
    /// Phase samples per cycle.
    pub phase_samples: usize,
    /// ClipNeutral weights per pair of neighbouring sequences.
    pub references: Vec<Vec<f64>>,
    /// Largest tested hybrid error (mm).
    pub hybrid_max_error_mm: f64,
    /// The tolerance (mm).
    pub epsilon_mm: f64,
    /// Bytes of the stored non-linear references.
    pub correction_bytes: usize,
    /// Parameter ranges.
    pub ranges: Vec<ParamRange>,
}

/// Places a body frame in the world: turned to `heading` about the
/// vertical and moved to the horizontal `root` (`out[i] = R_y(θ) p_i + root`).
pub fn place(local: &[[f64; 3]], root: DVec2, heading: f64, out: &mut [[f64; 3]]) {
    let (s, c) = heading.sin_cos();
    for (o, p) in out.iter_mut().zip(local) {
        *o = [
            p[0] * c + p[2] * s + root.x,
            p[1],
            -p[0] * s + p[2] * c + root.y,
        ];
    }
}
