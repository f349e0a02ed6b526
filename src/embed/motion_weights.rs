//! Skin weights from motion (issue 41): bone heat on one frame
//! ([`super::heat`]) gives a vertex weight on every bone near it in that
//! frame, so forearms lying on the belly heat the belly and every deformed
//! frame carries a ridge where they lay. Over a sequence, a belly vertex
//! follows the torso in every frame, not the forearm that touched it once.
//!
//! The weight step of a skinning decomposition (Le & Deng 2012, SSDR; Dem
//! Bones 2014), at the level of bone heat's segments (one per
//! [`Canonical`] joint: the pelvis, spine and chest of the torso apart):
//! each segment's rigid motion from the rest frame to each frame
//! ([`super::rigidity::robust_motion`] of the vertices bone heat gives it
//! most weight, or of its part's when it has few), then per vertex the
//! joint weights `w` (non-negative, summing to one) over the joints bone
//! heat gives it weight on (and its segment's parent) that are the
//! *anchor* — the one whose motion alone follows the vertex best — or its
//! parent or a child in the skeleton, minimising
//!
//! `Σ_f ‖Σ_j w_j T_jf(r) − x_f‖² + μ ‖w − w_heat‖²`
//!
//! (`r` the vertex at rest, `x_f` in frame f, `T_jf` segment j's motion,
//! `w_heat` bone heat on those joints renormalised), `μ = F (τ h)²` for F
//! frames and the height h: leaving the heat weights by 1 must lower the
//! vertex's RMS distance to its trajectory by more than `τ h`, and a fit
//! that does not (per unit of its largest weight change) leaves bone heat
//! as it was. Near a joint, where the segments' motions barely differ,
//! the heat weights stay; a vertex that follows one part and not another
//! moves its weight to the one it follows, never to a joint far along the
//! skeleton. The part labels follow the fit only where it takes a vertex
//! off its part ([`motion_labels`]).

use super::heat::Weights;
use super::parts::{Part, part_weights};
use super::rigidity::{Rigid, robust_motion};
use crate::rig::Canonical;
use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

/// How [`refine`] fits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct MotionWeightOptions {
    /// τ: the RMS distance (fraction of the height) a unit change of the
    /// weights must save to be taken. Default 0.02.
    pub tolerance: f64,
    /// Parts with a heat weight below this are no candidates (the parent of
    /// the vertex's heaviest part always is). Default 0.005.
    pub min_heat: f64,
    /// The most frames used (evenly spread over those given). Default 120.
    pub max_frames: usize,
    /// A vertex keeps bone heat's part label while its fitted weight on
    /// that part is at least this ([`motion_labels`]). Default 0.25.
    pub keep_label: f64,
}

impl Default for MotionWeightOptions {
    fn default() -> Self {
        MotionWeightOptions {
            tolerance: 0.02,
            min_heat: 0.005,
            max_frames: 120,
            keep_label: 0.25,
        }
    }
}

/// What [`refine`] changed.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub(crate) struct MotionWeightReport {
    /// Frames fitted.
    pub frames: usize,
    /// Vertices whose part weights moved by more than 0.1 (largest part).
    pub changed: usize,
    /// The largest change of one part weight.
    pub largest_change: f64,
    /// Vertices whose heaviest part changed.
    pub relabelled: usize,
}

impl MotionWeightReport {
    /// One line for the embedding's notes.
    pub fn note(&self) -> String {
        format!(
            "skin weights fitted to the motion of {} frames: {} vertices' part weights moved by more than 0.1 (largest {:.2}), {} changed heaviest part",
            self.frames, self.changed, self.largest_change, self.relabelled
        )
    }
}

/// A segment with fewer vertices than this takes its part's motion.
const MIN_SEGMENT: usize = 12;

/// `w` (bone heat on `rest`, labelled `labels`) refitted to the motion of
/// `frames` (each one position per vertex of `rest`); `height` scales the
/// tolerance. Frames of another vertex count are skipped; with no frame,
/// `w` is unchanged.
///
/// The fit is per segment (a [`Canonical`] joint's bones: bone heat's
/// unit), not per part: the torso part holds three segments (pelvis,
/// spine, chest) and bends, so one rigid motion of the whole torso misses
/// the pelvis ring and the base of the neck whenever the spine bends, and
/// the fit handed them to the thighs and the head (on the crane capture
/// 370 torso vertices went to the thighs, the torso's slab at the pelvis
/// shrank from 271 to 59 vertices, and differently from another rest
/// frame: the head measure's drift between rest frames).
pub(crate) fn refine(
    rest: &[[f64; 3]],
    w: &mut Weights,
    labels: &[u8],
    frames: &[&[[f64; 3]]],
    height: f64,
    opts: &MotionWeightOptions,
) -> MotionWeightReport {
    let n = rest.len();
    let usable: Vec<&[[f64; 3]]> = frames.iter().copied().filter(|f| f.len() == n).collect();
    let step = usable.len().div_ceil(opts.max_frames.max(1)).max(1);
    let used: Vec<&[[f64; 3]]> = usable.into_iter().step_by(step).collect();
    if used.is_empty() || w.len() != n || labels.len() != n {
        return MotionWeightReport::default();
    }
    let segments = segment_labels(w, labels);
    let motions = segment_motions(rest, labels, &segments, &used);
    let mu = used.len() as f64 * (opts.tolerance * height).powi(2);
    let heat = part_weights(w);
    let fitted: Vec<Option<[f64; Canonical::COUNT]>> = (0..n)
        .into_par_iter()
        .map(|v| {
            let s = Canonical::ALL[segments[v] as usize];
            fit_vertex(v, rest, &used, &motions, &w[v], s, mu, opts.min_heat)
        })
        .collect();
    let mut report = MotionWeightReport {
        frames: used.len(),
        ..Default::default()
    };
    for (v, new) in fitted.into_iter().enumerate() {
        let Some(new) = new else { continue };
        let new_parts = part_row(&new);
        let old = &heat[v];
        let change = (0..Part::COUNT)
            .map(|p| (new_parts[p] - old[p]).abs())
            .fold(0.0, f64::max);
        report.largest_change = report.largest_change.max(change);
        if change > 0.1 {
            report.changed += 1;
        }
        if heaviest(old) != heaviest(&new_parts) {
            report.relabelled += 1;
        }
        w[v] = new;
    }
    report
}

/// The part labels after the fit: bone heat's label `heat_labels[v]`
/// while the fitted weights `w` keep at least `keep` on that part, else
/// the fitted weights' heaviest part. Where two parts blend across a joint
/// the fit moves some weight from one to the other and the heaviest part
/// flips on a fraction of a blend zone's vertices, differently from each
/// rest frame (on the crane capture 532 and 820 vertices from its upright
/// and bent rest frames, nearly all keeping 0.3-0.5 on the heat part):
/// the part boundaries would wander along the blend zones, and with them
/// everything read off the labels (the regressors, the head and feet
/// checks' vertex sets). A vertex the fit takes off a part (a belly that
/// touched the forearm in the rest frame: 0.89 → 0.01) is relabelled. The
/// skin weights keep the whole fit.
pub(crate) fn motion_labels(heat_labels: &[u8], w: &Weights, keep: f64) -> Vec<u8> {
    heat_labels
        .iter()
        .zip(w)
        .map(|(&l, row)| {
            let p = part_row(row);
            if p[l as usize] >= keep {
                l
            } else {
                heaviest(&p) as u8
            }
        })
        .collect()
}

/// A joint row's part weights.
fn part_row(row: &[f64; Canonical::COUNT]) -> [f64; Part::COUNT] {
    let mut p = [0.0; Part::COUNT];
    for j in Canonical::ALL {
        p[Part::of_joint(j).index()] += row[j.index()];
    }
    p
}

/// The index of the largest entry.
fn heaviest<const N: usize>(row: &[f64; N]) -> usize {
    (0..N)
        .max_by(|&a, &b| row[a].total_cmp(&row[b]))
        .unwrap_or(0)
}

/// Each vertex's segment: its heaviest joint among its part's joints
/// (the part's first joint when bone heat gave none of them weight).
fn segment_labels(w: &Weights, labels: &[u8]) -> Vec<u8> {
    w.iter()
        .zip(labels)
        .map(|(row, &l)| {
            Canonical::ALL
                .iter()
                .filter(|j| Part::of_joint(**j).index() == l as usize)
                .max_by(|a, b| row[a.index()].total_cmp(&row[b.index()]))
                .map_or(0, |j| j.index() as u8)
        })
        .collect()
}

/// Each segment's rigid motion from `rest` to each frame,
/// `[frame][joint]`: fitted to the segment's vertices, or to its part's
/// when the segment has fewer than [`MIN_SEGMENT`] (`None` when the part
/// has fewer than three).
fn segment_motions(
    rest: &[[f64; 3]],
    labels: &[u8],
    segments: &[u8],
    frames: &[&[[f64; 3]]],
) -> Vec<Vec<Option<Rigid>>> {
    let of = |ls: &[u8], k: usize| -> Vec<u32> {
        (0..ls.len() as u32)
            .filter(|&v| ls[v as usize] as usize == k)
            .collect()
    };
    let members: Vec<Vec<u32>> = Canonical::ALL
        .iter()
        .map(|j| {
            let own = of(segments, j.index());
            if own.len() >= MIN_SEGMENT {
                own
            } else {
                of(labels, Part::of_joint(*j).index())
            }
        })
        .collect();
    frames
        .par_iter()
        .map(|f| members.iter().map(|m| robust_motion(rest, f, m)).collect())
        .collect()
}

/// The joint weights of vertex `v` (bone heat `heat`, segment `seg`)
/// fitted to its trajectory; `None` (bone heat stays) when it has a single
/// candidate, a candidate without a motion, or when the fit does not
/// explain the trajectory better than bone heat by `τ h` per unit of
/// weight moved ([`explains_better`]).
///
/// The candidates are bone heat's joints (and the segment's parent), cut
/// to the *anchor* (the candidate whose motion alone follows the vertex
/// best) and its parent and children in the skeleton; the fit is held to
/// bone heat on those, renormalised. Two defects of the unrestricted fit,
/// measured on samba: weight on a joint far along the skeleton (the back
/// of the left knee took 0.105 on the right hip, whose motion alone misses
/// it by 17 cm, for 0.09 cm of residual: in a retarget the legs part more
/// than in the capture and the vertex left its one-ring by 7-9 cm); and,
/// where contact weights were dropped (a belly under the hands: 0.45 on
/// the wrists), the held-to-heat term spread the dropped weight evenly
/// over the other candidates (spine 0.04 → 0.13, left hip 0.08 → 0.21),
/// a fit worse than the pelvis's motion alone (3.5 vs 1.4 cm rms) and a
/// thigh region whose edge cut through the waist (a shard torn out of it).
#[allow(clippy::too_many_arguments)]
fn fit_vertex(
    v: usize,
    rest: &[[f64; 3]],
    frames: &[&[[f64; 3]]],
    motions: &[Vec<Option<Rigid>>],
    heat: &[f64; Canonical::COUNT],
    seg: Canonical,
    mu: f64,
    min_heat: f64,
) -> Option<[f64; Canonical::COUNT]> {
    let moves = |j: usize| motions.iter().all(|m| m[j].is_some());
    let mut cand: Vec<usize> = (0..Canonical::COUNT)
        .filter(|&j| heat[j] >= min_heat)
        .collect();
    if let Some(parent) = seg.parent()
        && !cand.contains(&parent.index())
        && moves(parent.index())
    {
        cand.push(parent.index());
    }
    if cand.len() < 2 || !cand.iter().all(|&j| moves(j)) {
        return None;
    }
    let r = DVec3::from_array(rest[v]);
    let offsets = |f: usize, js: &[usize]| -> Option<Vec<DVec3>> {
        let x = DVec3::from_array(frames[f][v]);
        js.iter()
            .map(|&j| motions[f][j].map(|m| m.apply(r) - x))
            .collect()
    };
    let near = near_anchor(&cand, frames.len(), &offsets)?;
    let k = near.len();
    let mut out = [0.0; Canonical::COUNT];
    if k == 1 {
        out[near[0]] = 1.0;
    } else {
        // D_pq = Σ_f (T_pf r − x_f)·(T_qf r − x_f): the residual of w is
        // wᵀDw when Σ w = 1.
        let mut d = vec![0.0; k * k];
        for f in 0..frames.len() {
            let e = offsets(f, &near)?;
            for i in 0..k {
                for j in i..k {
                    d[i * k + j] += e[i].dot(e[j]);
                }
            }
        }
        for i in 0..k {
            for j in 0..i {
                d[i * k + j] = d[j * k + i];
            }
            d[i * k + i] += mu;
        }
        // min wᵀDw − 2μ w·w0 subject to Σw = 1, w ≥ 0: the
        // equality-constrained solve, dropping the most negative weight
        // until none is. w0: bone heat on the joints kept, renormalised.
        let sum: f64 = near.iter().map(|&j| heat[j]).sum();
        let w0: Vec<f64> = near
            .iter()
            .enumerate()
            .map(|(i, &j)| {
                if sum > 0.0 {
                    heat[j] / sum
                } else {
                    (i == 0) as u8 as f64
                }
            })
            .collect();
        let w = simplex_qp(&d, &w0, mu, k)?;
        for (i, &j) in near.iter().enumerate() {
            out[j] = w[i];
        }
    }
    let tau_h = (mu / frames.len() as f64).sqrt();
    explains_better(&out, heat, min_heat, tau_h, frames.len(), &offsets).then_some(out)
}

/// `(frame, joints)` → each joint's motion of the vertex at rest minus
/// its position in that frame (`None` if a joint has no motion there).
type Offsets<'a> = dyn Fn(usize, &[usize]) -> Option<Vec<DVec3>> + 'a;

/// The candidates `cand` kept: the anchor (the one whose motion alone has
/// the least residual over the `nf` frames, first in the result) and its
/// parent and children among them.
fn near_anchor(cand: &[usize], nf: usize, offsets: &Offsets) -> Option<Vec<usize>> {
    let mut alone = vec![0.0; cand.len()];
    for f in 0..nf {
        for (a, e) in alone.iter_mut().zip(offsets(f, cand)?) {
            *a += e.length_squared();
        }
    }
    let best = (0..cand.len()).min_by(|&a, &b| alone[a].total_cmp(&alone[b]))?;
    let anchor = Canonical::ALL[cand[best]];
    let adjacent = |j: Canonical| j.parent() == Some(anchor) || anchor.parent() == Some(j);
    let mut near = vec![anchor.index()];
    near.extend(
        cand.iter()
            .copied()
            .filter(|&j| adjacent(Canonical::ALL[j])),
    );
    Some(near)
}

/// Whether the fitted row `fit` explains the vertex's trajectory better
/// than bone heat (its joints of at least `min_heat`, renormalised) by
/// more than `tau_h` times the largest change of one joint weight: the
/// tolerance's meaning ([`MotionWeightOptions::tolerance`]) held per
/// vertex, so a change that buys less than it stays bone heat.
fn explains_better(
    fit: &[f64; Canonical::COUNT],
    heat: &[f64; Canonical::COUNT],
    min_heat: f64,
    tau_h: f64,
    nf: usize,
    offsets: &Offsets,
) -> bool {
    let rms = |row: &[f64; Canonical::COUNT], floor: f64| -> Option<f64> {
        let js: Vec<usize> = (0..Canonical::COUNT)
            .filter(|&j| row[j] >= floor && row[j] > 0.0)
            .collect();
        let sum: f64 = js.iter().map(|&j| row[j]).sum();
        let mut e = 0.0;
        for f in 0..nf {
            let o = offsets(f, &js)?;
            let p: DVec3 = js.iter().zip(o).map(|(&j, d)| d * (row[j] / sum)).sum();
            e += p.length_squared();
        }
        Some((e / nf.max(1) as f64).sqrt())
    };
    let change = (0..Canonical::COUNT)
        .map(|j| (fit[j] - heat[j]).abs())
        .fold(0.0, f64::max);
    match (rms(heat, min_heat), rms(fit, 0.0)) {
        (Some(h), Some(f)) => h - f > tau_h * change,
        _ => false,
    }
}

/// `argmin wᵀDw − 2μ w·w0` over `Σw = 1`, `w ≥ 0` (`D` k×k, row-major,
/// positive definite): active set, the most negative weight fixed at 0
/// until none is negative. `None` if a system is singular.
fn simplex_qp(d: &[f64], w0: &[f64], mu: f64, k: usize) -> Option<Vec<f64>> {
    let mut free: Vec<usize> = (0..k).collect();
    loop {
        let m = free.len();
        // KKT: [D_FF 1; 1ᵀ 0] [w; λ] = [μ w0_F; 1].
        let s = m + 1;
        let mut a = vec![0.0; s * s];
        let mut b = vec![0.0; s];
        for (i, &fi) in free.iter().enumerate() {
            for (j, &fj) in free.iter().enumerate() {
                a[i * s + j] = d[fi * k + fj];
            }
            a[i * s + m] = 1.0;
            a[m * s + i] = 1.0;
            b[i] = mu * w0[fi];
        }
        b[m] = 1.0;
        let x = solve_dense(&mut a, &mut b, s)?;
        let worst = (0..m)
            .filter(|&i| x[i] < 0.0)
            .min_by(|&i, &j| x[i].total_cmp(&x[j]));
        match worst {
            Some(i) if m > 1 => {
                free.remove(i);
            }
            _ => {
                let mut w = vec![0.0; k];
                for (i, &fi) in free.iter().enumerate() {
                    w[fi] = x[i].max(0.0);
                }
                let sum: f64 = w.iter().sum();
                if sum <= 0.0 {
                    return None;
                }
                w.iter_mut().for_each(|x| *x /= sum);
                return Some(w);
            }
        }
    }
}

/// Gaussian elimination with partial pivoting of the `s`×`s` system.
fn solve_dense(a: &mut [f64], b: &mut [f64], s: usize) -> Option<Vec<f64>> {
    for c in 0..s {
        let piv = (c..s).max_by(|&i, &j| a[i * s + c].abs().total_cmp(&a[j * s + c].abs()))?;
        if a[piv * s + c].abs() < 1e-300 {
            return None;
        }
        if piv != c {
            for j in 0..s {
                a.swap(piv * s + j, c * s + j);
            }
            b.swap(piv, c);
        }
        for i in c + 1..s {
            let f = a[i * s + c] / a[c * s + c];
            if f != 0.0 {
                for j in c..s {
                    a[i * s + j] -= f * a[c * s + j];
                }
                b[i] -= f * b[c];
            }
        }
    }
    let mut x = vec![0.0; s];
    for i in (0..s).rev() {
        let mut t = b[i];
        for j in i + 1..s {
            t -= a[i * s + j] * x[j];
        }
        x[i] = t / a[i * s + i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    /// Two parts: the torso standing still, the left forearm swinging
    /// about the origin; a vertex on the torso that bone heat gave half to
    /// the forearm goes back to the torso, one that swings with the
    /// forearm goes to it.
    #[test]
    fn a_vertex_goes_to_the_part_it_follows() {
        let t = Part::Torso.index() as u8;
        let a = Part::LForearm.index() as u8;
        let mut rest = Vec::new();
        let mut labels = Vec::new();
        for i in 0..10 {
            rest.push([0.0, i as f64 * 0.1, 0.0]);
            labels.push(t);
            rest.push([0.5 + i as f64 * 0.05, 0.0, 0.1]);
            labels.push(a);
        }
        // Vertex 20: on the torso, heated half by the forearm; 21 on the
        // forearm, heated half by the torso. Vertex 20 sits 45 cm from the
        // forearm's pivot: nearer, the swing barely moves it and bone heat
        // stays (the fit must beat it by 2 % of the height per unit of
        // weight moved).
        rest.push([0.0, 0.45, 0.02]);
        labels.push(t);
        rest.push([0.6, 0.0, 0.12]);
        labels.push(a);
        let frames: Vec<Vec<[f64; 3]>> = (0..20)
            .map(|f| {
                let q = DQuat::from_rotation_z(f as f64 * 0.08);
                rest.iter()
                    .enumerate()
                    .map(|(v, p)| {
                        let moving = v == 21 || (v < 20 && v % 2 == 1);
                        if moving {
                            (q * DVec3::from_array(*p)).to_array()
                        } else {
                            *p
                        }
                    })
                    .collect()
            })
            .collect();
        let refs: Vec<&[[f64; 3]]> = frames.iter().map(|f| f.as_slice()).collect();
        let mut w: Weights = labels
            .iter()
            .map(|&l| {
                let mut r = [0.0; Canonical::COUNT];
                let j = if l == t {
                    Canonical::Chest
                } else {
                    Canonical::LElbow
                };
                r[j.index()] = 1.0;
                r
            })
            .collect();
        for v in [20, 21] {
            w[v] = [0.0; Canonical::COUNT];
            w[v][Canonical::Chest.index()] = 0.5;
            w[v][Canonical::LElbow.index()] = 0.5;
        }
        let rep = refine(
            &rest,
            &mut w,
            &labels,
            &refs,
            1.0,
            &MotionWeightOptions::default(),
        );
        assert_eq!(rep.frames, 20);
        assert!(w[20][Canonical::Chest.index()] > 0.95, "{:?}", w[20]);
        assert!(w[21][Canonical::LElbow.index()] > 0.95, "{:?}", w[21]);
        assert!(rep.changed >= 2, "{rep:?}");
        // Rows still sum to one.
        for row in &w {
            assert!((row.iter().sum::<f64>() - 1.0).abs() < 1e-9);
        }
        // No frames: unchanged.
        let before = w.clone();
        let rep = refine(
            &rest,
            &mut w,
            &labels,
            &[],
            1.0,
            &MotionWeightOptions::default(),
        );
        assert_eq!(rep, MotionWeightReport::default());
        assert_eq!(w, before);
    }
}
