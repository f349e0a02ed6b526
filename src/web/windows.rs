//! The transition windows' non-linear blend for the export (Huang et al.
//! 2015, Sec. 4.4, the paper's fixed transitions; the blend `G` of Casas
//! et al. 2013, Eqs. 1-2, as [`crate::mesh::blend::Blender`] computes it).
//!
//! Frame `i ∈ 0..=2L` of a window is `G(from[m−L+i], A·to[n−L+i], i / 2L)`
//! with `A` the transition's ground-plane alignment. Computed frame by frame,
//! every window frame decomposes two database frames (a polar decomposition
//! per triangle, most of the cost), although windows share database frames:
//! the samba capture six times has 3,264 decompositions over 588 distinct
//! frames. Here each database frame is decomposed once and reused by every
//! window that touches it, and the alignment is applied to the decomposition
//! analytically: `A` is a rotation `R_y` about +Y and a translation, so the
//! aligned frame's deformation gradients are `R_y D = (R_y R) S` — the
//! rotation quaternion is premultiplied by `R_y`, the stretch is unchanged
//! and the centroid is moved by `A`. The Poisson system is factored once
//! (one [`Blender`]); each window frame is one sequential 3-column solve,
//! frames in parallel (rayon), scratch reused (no allocation per frame).
//!
//! Windows are processed in batches of whole connected groups (windows that
//! share database frames), so the cached decompositions stay within a
//! memory budget ([`WindowOptions::cache_bytes`]).

use super::codec::Geometry;
use super::site::{SiteTransition, WebError};
use crate::mesh::blend::{Blender, FrameGradients, sym3};
use crate::mesh::frames::{RestFrames, polar};
use glam::{DMat3, DQuat, DVec3};
use rayon::prelude::*;

/// Options of [`blend_windows`].
#[derive(Debug, Clone, Copy)]
pub struct WindowOptions {
    /// Upper bound of the bytes the cached decompositions of one batch take
    /// (80 bytes per triangle and frame); a batch always holds at least one
    /// window. Default 256 MiB.
    pub cache_bytes: usize,
}

impl Default for WindowOptions {
    fn default() -> Self {
        WindowOptions {
            cache_bytes: 256 << 20,
        }
    }
}

/// One database frame: sequence and frame index (clamped into the sequence).
type Key = (usize, usize);

/// The database frames of window frame `i` of transition `t`: source,
/// target and blend weight. Frames past a sequence's ends are clamped, as
/// the page's linear blend does.
fn window_frame(g: &Geometry, t: &SiteTransition, i: usize) -> (Key, Key, f64) {
    let frames = |s: usize| g.sequences[s].len() / g.vertices.max(1);
    let l = t.window as isize;
    let clamp = |s: usize, f: isize| f.clamp(0, frames(s) as isize - 1) as usize;
    let a = (t.from, clamp(t.from, t.m as isize - l + i as isize));
    let b = (t.to, clamp(t.to, t.n as isize - l + i as isize));
    let alpha = if l == 0 {
        1.0
    } else {
        i as f64 / (2 * t.window) as f64
    };
    (a, b, alpha)
}

/// Union-find root with path halving.
fn root(parent: &mut [usize], mut x: usize) -> usize {
    while parent[x] != x {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    x
}

/// The transitions' windows blended non-linearly, in the source's
/// coordinates: the same frames as [`blend_windows_per_frame`]
/// (up to rounding), each database frame decomposed once.
pub fn blend_windows(
    g: &Geometry,
    table: &[SiteTransition],
    opts: &WindowOptions,
) -> Result<Vec<Vec<[f32; 3]>>, WebError> {
    let n = g.vertices;
    if table.is_empty() || n == 0 {
        return Ok(vec![Vec::new(); table.len()]);
    }
    let blender = window_blender(g)?;
    let reference: Vec<[f64; 3]> = g.sequences[0][..n]
        .iter()
        .map(|q| q.map(f64::from))
        .collect();
    let rest = RestFrames::new(&reference, &g.triangles);
    // Flat ids of database frames, and the groups of windows sharing frames.
    let mut offset = Vec::with_capacity(g.sequences.len() + 1);
    offset.push(0usize);
    for s in &g.sequences {
        offset.push(offset.last().copied().unwrap_or(0) + s.len() / n);
    }
    let flat = |k: Key| offset[k.0] + k.1;
    let total = offset.last().copied().unwrap_or(0);
    let mut parent: Vec<usize> = (0..total).collect();
    for t in table {
        let (a0, _, _) = window_frame(g, t, 0);
        for i in 0..=2 * t.window {
            let (a, b, _) = window_frame(g, t, i);
            for k in [a, b] {
                let (x, y) = (root(&mut parent, flat(a0)), root(&mut parent, flat(k)));
                parent[x] = y;
            }
        }
    }
    let mut order: Vec<usize> = (0..table.len()).collect();
    order.sort_by_key(|&w| {
        let (a0, _, _) = window_frame(g, &table[w], 0);
        (root(&mut parent, flat(a0)), w)
    });
    // Batches of whole groups where the budget allows (a group larger than
    // the budget is split between windows).
    let per_frame = 80 * g.triangles.len().max(1);
    let budget = (opts.cache_bytes / per_frame).max(1);
    let keys_of = |w: usize| -> Vec<usize> {
        let t = &table[w];
        let mut k: Vec<usize> = (0..=2 * t.window)
            .flat_map(|i| {
                let (a, b, _) = window_frame(g, t, i);
                [flat(a), flat(b)]
            })
            .collect();
        k.sort_unstable();
        k.dedup();
        k
    };
    let mut out: Vec<Vec<[f32; 3]>> = table
        .iter()
        .map(|t| vec![[0.0f32; 3]; (2 * t.window + 1) * n])
        .collect();
    let mut cache: Vec<FrameGradients> = Vec::new();
    let mut start = 0;
    while start < order.len() {
        let mut keys: Vec<usize> = keys_of(order[start]);
        let mut end = start + 1;
        while end < order.len() {
            let mut k = keys.clone();
            k.extend(keys_of(order[end]));
            k.sort_unstable();
            k.dedup();
            if k.len() > budget {
                break;
            }
            keys = k;
            end += 1;
        }
        blend_batch(
            g,
            table,
            &blender,
            &rest,
            &order[start..end],
            &keys,
            &offset,
            &mut cache,
            &mut out,
        );
        start = end;
    }
    Ok(out)
}

/// Decomposes the batch's database frames `keys` (flat ids) into `cache`,
/// then blends every frame of the batch's windows into `out`.
#[allow(clippy::too_many_arguments)]
fn blend_batch(
    g: &Geometry,
    table: &[SiteTransition],
    blender: &Blender,
    rest: &RestFrames,
    windows: &[usize],
    keys: &[usize],
    offset: &[usize],
    cache: &mut Vec<FrameGradients>,
    out: &mut [Vec<[f32; 3]>],
) {
    let n = g.vertices;
    let position = |flat: usize| -> &[[f32; 3]] {
        let s = offset.partition_point(|&o| o <= flat) - 1;
        let f = flat - offset[s];
        &g.sequences[s][f * n..(f + 1) * n]
    };
    cache.resize_with(keys.len(), FrameGradients::default);
    cache[..keys.len()].par_iter_mut().zip(keys).for_each_init(
        || (Vec::new(), vec![[0.0f64; 3]; n]),
        |(grads, p), (c, &k)| {
            for (q, v) in p.iter_mut().zip(position(k)) {
                *q = v.map(f64::from);
            }
            decompose(rest, &g.triangles, p, grads, c);
        },
    );
    let cached = |k: Key| -> &FrameGradients {
        let f = offset[k.0] + k.1;
        &cache[keys.partition_point(|&x| x < f)]
    };
    // Every (window, frame) of the batch with its output rows.
    let mut tasks: Vec<(usize, usize, &mut [[f32; 3]])> = Vec::new();
    let mut chosen = vec![false; out.len()];
    for &w in windows {
        chosen[w] = true;
    }
    for (w, o) in out.iter_mut().enumerate() {
        if chosen[w] {
            for (i, rows) in o.chunks_exact_mut(n).enumerate() {
                tasks.push((w, i, rows));
            }
        }
    }
    tasks.into_par_iter().for_each_init(
        || {
            (
                blender.workspace(),
                FrameGradients::default(),
                vec![[0.0f64; 3]; n],
            )
        },
        |(ws, aligned, x), (w, i, rows)| {
            let t = &table[w];
            let (a, b, alpha) = window_frame(g, t, i);
            align_into(cached(b), t.align, aligned);
            blender.blend(cached(a), aligned, alpha, x, ws);
            for (r, p) in rows.iter_mut().zip(x.iter()) {
                *r = [p[0] as f32, p[1] as f32, p[2] as f32];
            }
        },
    );
}

/// The decomposition of `A·frame` from that of `frame`, for the ground-plane
/// alignment `A = [cos θ, sin θ, tx, tz]` (`x' = x cos θ + z sin θ + tx`,
/// `z' = −x sin θ + z cos θ + tz`: the rotation `R_y(θ)` about +Y, then a
/// translation). Deformation gradients are `R_y D`, so rotations become
/// `R_y R` and stretches are unchanged.
fn align_into(src: &FrameGradients, align: [f64; 4], out: &mut FrameGradients) {
    let [c, s, tx, tz] = align;
    let ry = DQuat::from_rotation_y(s.atan2(c));
    out.rotation.clear();
    out.rotation.extend(src.rotation.iter().map(|&q| ry * q));
    out.stretch.clone_from(&src.stretch);
    let p = src.centroid;
    out.centroid = DVec3::new(c * p.x + s * p.z + tx, p.y, -s * p.x + c * p.z + tz);
}

/// Lanes of the polar decomposition: four triangles' 3×3 matrices are
/// iterated together, element by element on `[f64; LANES]` arrays, which
/// the compiler maps onto SIMD registers (the scalar iteration is bound by
/// the latency of its square roots and divisions).
const LANES: usize = 4;
type Lane = [f64; LANES];

/// A database frame's rotations, stretches and centroid, as
/// [`Blender::decompose_into`] gives them: deformation gradients from the
/// blender's reference frames ([`RestFrames`], the same reference), split by
/// [`polar`]'s scaled Newton iteration (Higham 1986), here four triangles at
/// a time ([`newton_lanes`]); a group of four holding an inverted or
/// non-finite gradient, or one that does not converge, goes through
/// [`polar`] itself.
pub(crate) fn decompose(
    rest: &RestFrames,
    triangles: &[[u32; 3]],
    positions: &[[f64; 3]],
    gradients: &mut Vec<DMat3>,
    out: &mut FrameGradients,
) {
    gradients.resize(triangles.len(), DMat3::IDENTITY);
    rest.gradients_into(positions, triangles, gradients);
    out.rotation.resize(triangles.len(), DQuat::IDENTITY);
    out.stretch
        .resize(triangles.len(), [1.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
    for (c, chunk) in gradients.chunks(LANES).enumerate() {
        let newton = chunk.len() == LANES
            && chunk
                .iter()
                .all(|m| m.determinant() > 1e-300 && m.is_finite());
        let rot = if newton {
            newton_dispatch(chunk.try_into().unwrap_or([DMat3::IDENTITY; LANES]))
        } else {
            None
        };
        for (l, m) in chunk.iter().enumerate() {
            let (q, s) = match rot {
                Some(r) => {
                    let s = r[l].transpose() * *m;
                    (
                        DQuat::from_mat3(&r[l]).normalize(),
                        (s + s.transpose()) * 0.5,
                    )
                }
                None => polar(*m),
            };
            out.rotation[c * LANES + l] = q;
            out.stretch[c * LANES + l] = sym3(s);
        }
    }
    let s: DVec3 = positions.iter().map(|p| DVec3::from_array(*p)).sum();
    out.centroid = s / positions.len().max(1) as f64;
}

/// [`newton_lanes`] in an AVX2 build where the CPU has it.
fn newton_dispatch(m: [DMat3; LANES]) -> Option<[DMat3; LANES]> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has the feature the function is compiled for.
        return unsafe { newton_avx2(m) };
    }
    newton_lanes(m)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn newton_avx2(m: [DMat3; LANES]) -> Option<[DMat3; LANES]> {
    newton_lanes(m)
}

/// The rotation factor of four matrices by the scaled Newton iteration
/// `X ← (γ X + X⁻ᵀ / γ) / 2`, `γ = (‖X⁻¹‖_F / ‖X‖_F)^½` (Higham 1986), each
/// lane stopping when its step is within `1e-13 ‖X‖_F`, as [`polar`] does;
/// `None` when a lane has not converged in 30 steps.
#[inline(always)]
fn newton_lanes(m: [DMat3; LANES]) -> Option<[DMat3; LANES]> {
    // x[col][row][lane]
    let mut x: [[Lane; 3]; 3] =
        std::array::from_fn(|c| std::array::from_fn(|r| std::array::from_fn(|k| m[k].col(c)[r])));
    let mut done = [false; LANES];
    for _ in 0..30 {
        let cross = |a: &[Lane; 3], b: &[Lane; 3]| -> [Lane; 3] {
            [
                l(|k| a[1][k] * b[2][k] - a[2][k] * b[1][k]),
                l(|k| a[2][k] * b[0][k] - a[0][k] * b[2][k]),
                l(|k| a[0][k] * b[1][k] - a[1][k] * b[0][k]),
            ]
        };
        // X⁻ᵀ = [x1 × x2, x2 × x0, x0 × x1] / det X.
        let cof = [
            cross(&x[1], &x[2]),
            cross(&x[2], &x[0]),
            cross(&x[0], &x[1]),
        ];
        let det = l(|k| {
            x[0][0][k] * cof[0][0][k] + x[0][1][k] * cof[0][1][k] + x[0][2][k] * cof[0][2][k]
        });
        let inv_det = l(|k| 1.0 / det[k]);
        let frob2 = |a: &[[Lane; 3]; 3]| -> Lane {
            l(|k| {
                let mut s = 0.0;
                for c in a {
                    for r in c {
                        s += r[k] * r[k];
                    }
                }
                s
            })
        };
        let (fx, fc) = (frob2(&x), frob2(&cof));
        let nx = l(|k| fx[k].sqrt());
        let ni = l(|k| fc[k].sqrt() * inv_det[k].abs());
        let g = l(|k| (ni[k] / nx[k]).sqrt());
        let (a, b) = (l(|k| 0.5 * g[k]), l(|k| 0.5 * inv_det[k] / g[k]));
        let next: [[Lane; 3]; 3] = std::array::from_fn(|c| {
            std::array::from_fn(|r| l(|k| x[c][r][k] * a[k] + cof[c][r][k] * b[k]))
        });
        let diff: [[Lane; 3]; 3] =
            std::array::from_fn(|c| std::array::from_fn(|r| l(|k| next[c][r][k] - x[c][r][k])));
        let (fd, fnx) = (frob2(&diff), frob2(&next));
        let delta = l(|k| fd[k].sqrt());
        let size = l(|k| fnx[k].sqrt());
        for k in 0..LANES {
            if !done[k] {
                for c in 0..3 {
                    for r in 0..3 {
                        x[c][r][k] = next[c][r][k];
                    }
                }
                done[k] = delta[k] <= 1e-13 * size[k];
            }
        }
        if done.iter().all(|&d| d) {
            return Some(std::array::from_fn(|k| {
                DMat3::from_cols_array_2d(&std::array::from_fn(|c| {
                    std::array::from_fn(|r| x[c][r][k])
                }))
            }));
        }
    }
    None
}

#[inline(always)]
fn l(f: impl FnMut(usize) -> f64) -> Lane {
    std::array::from_fn(f)
}

/// Frame `f` of geometry sequence `s`.
pub(crate) fn frame(g: &Geometry, s: usize, f: usize) -> &[[f32; 3]] {
    &g.sequences[s][f * g.vertices..(f + 1) * g.vertices]
}

/// The reference mesh of the transition blend (the database's first frame,
/// with the topology's triangles) and its prefactored [`Blender`].
pub(crate) fn window_blender(g: &Geometry) -> Result<Blender, WebError> {
    let reference = crate::mesh::Mesh::new(
        frame(g, 0, 0).iter().map(|q| q.map(f64::from)).collect(),
        g.triangles.clone(),
    )
    .map_err(crate::mesh::MeshError::from)?;
    Ok(Blender::new(&reference).map_err(crate::parametric::ParamError::from)?)
}

/// The transitions' windows blended non-linearly frame by frame (Huang et
/// al. 2015, Sec. 4.4, the paper's fixed transitions): frame `i ∈ 0..=2L` is
/// `G(from[m−L+i], align·to[n−L+i], i / 2L)` with `G` the gradient-domain
/// blend of [`Blender`] (slerped rotations, lerped stretches,
/// Poisson-stitched), in the source's coordinates. Frames past a sequence's
/// ends are clamped, as the page's linear blend does.
///
/// Every window frame decomposes both its inputs anew: the reference that
/// [`blend_windows`] (the export's path, each database frame
/// decomposed once) is checked against.
pub fn blend_windows_per_frame(
    g: &Geometry,
    table: &[SiteTransition],
) -> Result<Vec<Vec<[f32; 3]>>, WebError> {
    use rayon::prelude::*;
    let n = g.vertices;
    let f64s = |p: &[[f32; 3]]| -> Vec<[f64; 3]> {
        p.iter()
            .map(|q| [q[0] as f64, q[1] as f64, q[2] as f64])
            .collect()
    };
    let blender = window_blender(g)?;
    let frames = |s: usize| g.sequences[s].len() / n;
    Ok(table
        .par_iter()
        .map_init(
            || (blender.workspace(), vec![[0.0f64; 3]; n]),
            |(ws, out), t| {
                let l = t.window as isize;
                let clamp = |s: usize, f: isize| f.clamp(0, frames(s) as isize - 1) as usize;
                let [c, si, tx, tz] = t.align;
                let mut w = Vec::with_capacity((2 * t.window + 1) * n);
                for i in 0..=2 * l {
                    let a = f64s(frame(g, t.from, clamp(t.from, t.m as isize - l + i)));
                    let b: Vec<[f64; 3]> = frame(g, t.to, clamp(t.to, t.n as isize - l + i))
                        .iter()
                        .map(|q| {
                            let (x, z) = (q[0] as f64, q[2] as f64);
                            [c * x + si * z + tx, q[1] as f64, -si * x + c * z + tz]
                        })
                        .collect();
                    let alpha = if l == 0 {
                        1.0
                    } else {
                        i as f64 / (2 * l) as f64
                    };
                    let ga = blender.decompose(&a, ws);
                    let gb = blender.decompose(&b, ws);
                    blender.blend(&ga, &gb, alpha, out, ws);
                    w.extend(out.iter().map(|p| [p[0] as f32, p[1] as f32, p[2] as f32]));
                }
                w
            },
        )
        .collect())
}
