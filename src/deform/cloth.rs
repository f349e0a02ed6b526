//! The cloth stitched as one piece after the part solves' blend (issue 42).
//!
//! A skirt belongs to the regions of the pelvis and of both thighs
//! ([`super::regions`]). Each region's solve turns the retrieved frame's
//! Laplacian coordinates by each vertex's skin-blended turn (the bones'
//! turns mixed by skin weight), which for cloth hanging between two
//! thighs is not the turn the cloth makes; integrated, those coordinates
//! crumple the hem into facets. Measured per stage on CMU 02_01 onto the
//! real samba capture (mean absolute bend of the skirt's edges over the
//! clip; the capture's own frames: median 9.18°, most 10.11°): retrieved
//! frames 9.20°, skinning alone 13.58°, the part solves 11.25°, each
//! region's own result as crumpled as their blend, the fold repair
//! 11.21°. Fitting each vertex's turn to the solved surface is what
//! smooths it (README, issue 42).
//!
//! The stitch solves the cloth vertices (softness above 0,
//! [`super::soft::softness`]) once more, as one piece, with the vertices
//! around them held where the blend left them:
//!
//! `min_x Σᵢ ‖(L x)ᵢ − Rᵢ δᵢ‖² + w² Σᵢ ‖xᵢ − bᵢ‖²`
//!
//! over the cloth vertices `i`, with `L` the mesh's uniform Laplacian,
//! `δᵢ` the retrieved frame's Laplacian coordinate (its captured cloth
//! detail, as Huang et al. 2015 Eq. 32 keeps it), `Rᵢ` the vertex's turn
//! (the skin's blend of its bones' turns, then `steps` rotations fitted to
//! the solved one-ring as in as-rigid-as-possible modelling, Sorkine &
//! Alexa 2007 Eq. 6) and `bᵢ` the blend. The blend sets the cloth's place
//! at the scale of the skirt; detail a few edges across comes from the
//! capture, so a step between two solves' results is not kept. `w`
//! ([`super::DeformOptions::cloth_stitch`]) sets the scale: a displacement
//! that repeats every `λ` edges follows the blend where the Laplacian's
//! eigenvalue there, about `(2π/λ)²`, is below `w`.
//!
//! The fold repair ([`super::unflip`]) runs after the stitch. Reading the
//! cloth with the skin's turns, it flags triangles the stitch turned the
//! way the cloth turns and rebuilds them as the thighs turn, crumpling the
//! hem again; so it reads and rebuilds the cloth with the rotations the
//! stitch fitted ([`ClothStitch::fitted_turns`],
//! [`super::DeformOptions::cloth_turns`]). A frame whose stitched repair
//! still leaves triangles facing against their own neighbourhoods is
//! repaired again from the unstitched blend, and the result that leaves
//! fewer kept ([`super::DeformOptions::cloth_fallback`]). Measured (session
//! 30, README, issue 42): onto the real samba capture the skirt's mean
//! bend 12.84° → 11.02° on CMU 131_01 (the stitch with the skin's turns
//! 11.52°), 11.21° → 10.00° on 02_01.
//!
//! Cost: one factorisation per character (`LᵀL + w² I` on the cloth, its
//! outer ring held); per frame `steps + 1` prefactored 3-column solves and
//! the rotation fits. No allocation per frame.

use super::DeformOptions;
use crate::mesh::solver::{FixedSolver, SolveError, Workspace};
use glam::{DQuat, DVec3};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion};
use rayon::prelude::*;

/// Iterations of the rotation extraction per fit (as [`super::arap`]).
const EXTRACT_ITERATIONS: usize = 8;

/// The fewest cloth vertices a thread fits at a time
/// ([`ClothStitch::fit_rotations`]).
const FIT_CHUNK: usize = 256;

/// A character's prefactored cloth stitch.
pub struct ClothStitch {
    /// Global id of each local unknown: the cloth vertices (`cloth` of
    /// them), then their outer ring (held at the blend).
    global: Vec<u32>,
    cloth: usize,
    /// Each cloth vertex's one-ring (local ids).
    rings: Vec<Vec<u32>>,
    weight: f64,
    steps: usize,
    solver: FixedSolver,
}

/// Scratch of [`ClothStitch::stitch`], one per thread.
pub struct StitchWorkspace {
    lsrc: Vec<DVec3>,
    rots: Vec<DQuat>,
    rhs: Vec<[f64; 3]>,
    x: Vec<[f64; 3]>,
    held: Vec<[f64; 3]>,
    ws: Workspace,
}

impl ClothStitch {
    /// Prefactors the stitch of the vertices `cloth` marks (one per vertex)
    /// in a mesh with `triangles`, pulled towards the blend with `weight`
    /// (`w` above) and `steps` rotation fits a frame. `None` when no vertex
    /// is marked (a character without loose cloth) or `weight` is not
    /// positive.
    pub fn new(
        triangles: &[[u32; 3]],
        cloth: &[bool],
        weight: f64,
        steps: usize,
    ) -> Result<Option<ClothStitch>, SolveError> {
        let n = cloth.len();
        let rings_of = one_rings(triangles, n);
        let mut local = vec![u32::MAX; n];
        let mut global: Vec<u32> = Vec::new();
        for v in (0..n).filter(|&v| cloth[v] && !rings_of[v].is_empty()) {
            local[v] = global.len() as u32;
            global.push(v as u32);
        }
        let count = global.len();
        if count == 0 || weight.is_nan() || weight <= 0.0 {
            return Ok(None);
        }
        for i in 0..count {
            for &w in &rings_of[global[i] as usize] {
                if local[w as usize] == u32::MAX {
                    local[w as usize] = global.len() as u32;
                    global.push(w);
                }
            }
        }
        let rings: Vec<Vec<u32>> = global[..count]
            .iter()
            .map(|&v| {
                rings_of[v as usize]
                    .iter()
                    .map(|&w| local[w as usize])
                    .collect()
            })
            .collect();
        let mut trip = Vec::new();
        for (i, ring) in rings.iter().enumerate() {
            let k = 1.0 / ring.len() as f64;
            let row = std::iter::once((i as u32, 1.0)).chain(ring.iter().map(|&j| (j, -k)));
            for (a, wa) in row.clone() {
                for (b, wb) in row.clone() {
                    trip.push((a, b, wa * wb));
                }
            }
            trip.push((i as u32, i as u32, weight * weight));
        }
        let fixed: Vec<u32> = (count as u32..global.len() as u32).collect();
        let solver = if fixed.is_empty() {
            FixedSolver::definite(global.len(), trip)?
        } else {
            FixedSolver::new(global.len(), trip, &fixed)?
        };
        Ok(Some(ClothStitch {
            global,
            cloth: count,
            rings,
            weight,
            steps,
            solver,
        }))
    }

    /// How many vertices are stitched.
    pub fn len(&self) -> usize {
        self.cloth
    }

    /// Whether none is (never: [`ClothStitch::new`] gives `None` then).
    pub fn is_empty(&self) -> bool {
        self.cloth == 0
    }

    /// Scratch space.
    pub fn workspace(&self) -> StitchWorkspace {
        let m = self.global.len();
        StitchWorkspace {
            lsrc: vec![DVec3::ZERO; self.cloth],
            rots: vec![DQuat::IDENTITY; self.cloth],
            rhs: vec![[0.0; 3]; m],
            x: vec![[0.0; 3]; m],
            held: vec![[0.0; 3]; m - self.cloth],
            ws: self.solver.workspace(3),
        }
    }

    /// Stitches `out` (the blend of the part solves, world coordinates)
    /// in place from the retrieved frame `source`, each vertex's turn
    /// starting at `turn` (one per vertex: the skin's blend).
    pub fn stitch(
        &self,
        source: &[[f64; 3]],
        turn: &[DQuat],
        out: &mut [[f64; 3]],
        ws: &mut StitchWorkspace,
    ) {
        let g = |l: u32| self.global[l as usize] as usize;
        for (i, ring) in self.rings.iter().enumerate() {
            let s: DVec3 = ring.iter().map(|&j| DVec3::from_array(source[g(j)])).sum();
            ws.lsrc[i] = DVec3::from_array(source[g(i as u32)]) - s / ring.len() as f64;
            ws.rots[i] = turn[g(i as u32)];
        }
        for (h, &v) in ws.held.iter_mut().zip(&self.global[self.cloth..]) {
            *h = out[v as usize];
        }
        for step in 0..=self.steps {
            if step > 0 {
                self.fit_rotations(source, ws);
            }
            self.solve(out, ws);
        }
        for (i, x) in ws.x[..self.cloth].iter().enumerate() {
            out[g(i as u32)] = *x;
        }
    }

    /// The rotations the last [`ClothStitch::stitch`] with `ws` fitted,
    /// written into `turn` (one per vertex) at the cloth's vertices; the
    /// others are left as they are.
    pub(crate) fn fitted_turns(&self, ws: &StitchWorkspace, turn: &mut [DQuat]) {
        for (&v, q) in self.global[..self.cloth].iter().zip(&ws.rots) {
            if let Some(t) = turn.get_mut(v as usize) {
                *t = *q;
            }
        }
    }

    /// One solve with the current rotations: `rhs = Σᵢ lᵢᵀ Rᵢ δᵢ + w² b`.
    fn solve(&self, out: &[[f64; 3]], ws: &mut StitchWorkspace) {
        let w2 = self.weight * self.weight;
        ws.rhs.fill([0.0; 3]);
        for (i, ring) in self.rings.iter().enumerate() {
            let d = (ws.rots[i] * ws.lsrc[i]).to_array();
            let k = 1.0 / ring.len() as f64;
            let b = out[self.global[i] as usize];
            for c in 0..3 {
                ws.rhs[i][c] += d[c] + w2 * b[c];
            }
            for &j in ring {
                for (r, dc) in ws.rhs[j as usize].iter_mut().zip(d) {
                    *r -= k * dc;
                }
            }
        }
        self.solver
            .solve::<3>(&ws.rhs, &ws.held, &mut ws.x, &mut ws.ws);
    }

    /// Each cloth vertex's rotation from the source's one-ring to the
    /// solved one (`ws.x`), the extraction started from the last. Each
    /// vertex's fit reads only the solve and its own last rotation, so the
    /// vertices are split over the threads (the same bits on any number).
    fn fit_rotations(&self, source: &[[f64; 3]], ws: &mut StitchWorkspace) {
        let g = |l: u32| self.global[l as usize] as usize;
        let x = &ws.x;
        self.rings
            .par_iter()
            .zip(ws.rots.par_iter_mut())
            .enumerate()
            .with_min_len(FIT_CHUNK)
            .for_each(|(i, (ring, q))| {
                let si = DVec3::from_array(source[g(i as u32)]);
                let yi = DVec3::from_array(x[i]);
                let mut cov = Matrix3::<f64>::zeros();
                for &j in ring {
                    let e = si - DVec3::from_array(source[g(j)]);
                    let f = yi - DVec3::from_array(x[j as usize]);
                    for a in 0..3 {
                        for b in 0..3 {
                            cov[(a, b)] += f[a] * e[b];
                        }
                    }
                }
                let guess = Rotation3::from(UnitQuaternion::from_quaternion(
                    nalgebra::Quaternion::new(q.w, q.x, q.y, q.z),
                ));
                let r = Rotation3::from_matrix_eps(&cov, 1e-9, EXTRACT_ITERATIONS, guess);
                let u = UnitQuaternion::from_rotation_matrix(&r);
                let nq = DQuat::from_xyzw(u.i, u.j, u.k, u.w);
                if nq.is_finite() {
                    *q = nq.normalize();
                }
            });
    }
}

/// The environment variable whose `name=value` pairs override the cloth
/// stitch's options (measurements of issue 42; [`with_overrides`]), e.g.
/// `SURFMOTION_CLOTH=stitch=0` for the deformation without the stitch.
pub(crate) const CLOTH_ENV: &str = "SURFMOTION_CLOTH";

/// `opts` with [`CLOTH_ENV`]'s overrides (a warning, and none taken, when
/// they cannot be read).
pub(crate) fn with_env(opts: &DeformOptions) -> DeformOptions {
    super::options::with_env_overrides(opts, CLOTH_ENV, "cloth", with_overrides)
}

/// `opts` with the comma-separated `name=value` pairs of `text`:
/// `stitch` (the weight, [`DeformOptions::cloth_stitch`], 0 turns it off),
/// `steps` ([`DeformOptions::cloth_steps`]), `rings`
/// ([`DeformOptions::cloth_rings`]), `joints`
/// ([`DeformOptions::stitch_joints`]), `apart`
/// ([`DeformOptions::stitch_apart`]), `turns` and `fallback`
/// ([`DeformOptions::cloth_turns`], [`DeformOptions::cloth_fallback`]:
/// `on`/`off`). An error names the pair it could not read and every name
/// accepted.
pub fn with_overrides(opts: &DeformOptions, text: &str) -> Result<DeformOptions, String> {
    const NAMES: &str = "stitch=W, steps=N, rings=N, joints=none|knees|limbs, apart=N, turns=on|off, fallback=on|off";
    let mut o = *opts;
    for p in super::overrides::pairs(text, NAMES) {
        let p = p?;
        match p.name {
            "stitch" => {
                o.cloth_stitch = p
                    .value
                    .parse::<f64>()
                    .ok()
                    .filter(|w| w.is_finite() && *w >= 0.0)
                    .ok_or_else(|| p.bad("the value is not a weight of 0 or more"))?;
            }
            "steps" => o.cloth_steps = p.count()?,
            "rings" => o.cloth_rings = p.count()?,
            "joints" => {
                use super::cloth_reach::StitchJoints as J;
                o.stitch_joints = match p.value {
                    "none" => J::None,
                    "knees" => J::Knees,
                    "limbs" => J::Limbs,
                    _ => return Err(p.bad("the value is not none, knees or limbs")),
                };
            }
            "apart" => o.stitch_apart = p.count()?,
            "turns" => o.cloth_turns = p.switch()?,
            "fallback" => o.cloth_fallback = p.switch()?,
            _ => return p.unknown(),
        }
    }
    Ok(o)
}

/// Each vertex's neighbours (sorted) in a mesh of `n` vertices.
fn one_rings(triangles: &[[u32; 3]], n: usize) -> Vec<Vec<u32>> {
    let mut nb: Vec<Vec<u32>> = vec![Vec::new(); n];
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if (a as usize) < n && (b as usize) < n {
                nb[a as usize].push(b);
                nb[b as usize].push(a);
            }
        }
    }
    for v in &mut nb {
        v.sort_unstable();
        v.dedup();
    }
    nb
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid `k × k` in the plane z = 0, two triangles per cell.
    fn grid(k: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let pos = (0..k * k)
            .map(|i| [(i % k) as f64, (i / k) as f64, 0.0])
            .collect();
        let mut tris = Vec::new();
        for y in 0..k - 1 {
            for x in 0..k - 1 {
                let v = (y * k + x) as u32;
                let k = k as u32;
                tris.push([v, v + 1, v + k + 1]);
                tris.push([v, v + k + 1, v + k]);
            }
        }
        (pos, tris)
    }

    /// A rigidly moved frame is left where it is (its Laplacian coordinates
    /// turned are the moved ones), and a crumple — every other inner vertex
    /// pushed up and down — is smoothed towards the source's flat sheet.
    #[test]
    fn a_rigid_motion_is_kept_and_a_crumple_is_smoothed() {
        let k = 12;
        let (src, tris) = grid(k);
        let cloth: Vec<bool> = (0..k * k)
            .map(|i| (2..k - 2).contains(&(i % k)) && (2..k - 2).contains(&(i / k)))
            .collect();
        let st = ClothStitch::new(&tris, &cloth, 0.5, 1).unwrap().unwrap();
        let mut ws = st.workspace();
        let q = DQuat::from_axis_angle(DVec3::new(0.3, 1.0, 0.2).normalize(), 0.7);
        let moved: Vec<[f64; 3]> = src
            .iter()
            .map(|p| (q * DVec3::from_array(*p) + DVec3::new(1.0, -2.0, 0.5)).to_array())
            .collect();
        let turn = vec![q; k * k];
        let mut out = moved.clone();
        st.stitch(&src, &turn, &mut out, &mut ws);
        for (a, b) in out.iter().zip(&moved) {
            assert!((DVec3::from_array(*a) - DVec3::from_array(*b)).length() < 1e-8);
        }
        let mut crumpled = src.clone();
        for (i, p) in crumpled.iter_mut().enumerate() {
            if cloth[i] {
                p[2] = if (i % k + i / k) % 2 == 0 { 0.2 } else { -0.2 };
            }
        }
        let ident = vec![DQuat::IDENTITY; k * k];
        let mut out = crumpled.clone();
        st.stitch(&src, &ident, &mut out, &mut ws);
        let most = |f: &[[f64; 3]]| f.iter().map(|p| p[2].abs()).fold(0.0, f64::max);
        assert!(most(&out) < 0.25 * most(&crumpled), "{}", most(&out));
        // The vertices outside the cloth are not moved.
        for (i, (a, b)) in out.iter().zip(&crumpled).enumerate() {
            if !cloth[i] {
                assert_eq!(a, b);
            }
        }
    }

    /// The stitch's rotations are the ones it fitted: on a rigidly moved
    /// sheet, the motion's turn at every cloth vertex (a band across the
    /// sheet), and nothing written elsewhere.
    #[test]
    fn the_fitted_turns_are_the_motion_s() {
        let k = 8;
        let (src, tris) = grid(k);
        let cloth: Vec<bool> = (0..k * k).map(|i| (2..k - 2).contains(&(i % k))).collect();
        let st = ClothStitch::new(&tris, &cloth, 0.5, 2).unwrap().unwrap();
        let mut ws = st.workspace();
        let q = DQuat::from_axis_angle(DVec3::new(1.0, 0.2, -0.4).normalize(), 1.1);
        let mut out: Vec<[f64; 3]> = src
            .iter()
            .map(|p| (q * DVec3::from_array(*p)).to_array())
            .collect();
        st.stitch(&src, &vec![q; k * k], &mut out, &mut ws);
        let mut turn = vec![DQuat::IDENTITY; k * k];
        st.fitted_turns(&ws, &mut turn);
        for (v, t) in turn.iter().enumerate() {
            let want = if cloth[v] { q } else { DQuat::IDENTITY };
            assert!(t.dot(want).abs() > 1.0 - 1e-6, "vertex {v}: {t:?}");
        }
    }

    #[test]
    fn the_overrides_are_read_and_bad_ones_named() {
        let d = DeformOptions::default();
        let o = with_overrides(
            &d,
            "stitch=0.3, steps=1,rings=3,joints=knees,apart=2,turns=off,fallback=off",
        )
        .unwrap();
        assert_eq!(
            (o.stitch_joints, o.stitch_apart),
            (crate::deform::cloth_reach::StitchJoints::Knees, 2)
        );
        assert_eq!(
            (
                o.cloth_stitch,
                o.cloth_steps,
                o.cloth_rings,
                o.cloth_turns,
                o.cloth_fallback
            ),
            (0.3, 1, 3, false, false)
        );
        assert_eq!(with_overrides(&d, "").unwrap(), d);
        for bad in [
            "stitch=-1",
            "stitch=nan",
            "steps=x",
            "rings=-1",
            "joints=toes",
            "apart=x",
            "turns=maybe",
            "colour=1",
            "stitch",
        ] {
            let e = with_overrides(&d, bad).unwrap_err();
            assert!(e.contains(bad) && e.contains("fallback=on|off"), "{e}");
        }
    }

    #[test]
    fn no_cloth_no_stitch() {
        let (_, tris) = grid(4);
        assert!(
            ClothStitch::new(&tris, &[false; 16], 0.5, 1)
                .unwrap()
                .is_none()
        );
        assert!(
            ClothStitch::new(&tris, &[true; 16], 0.0, 1)
                .unwrap()
                .is_none()
        );
    }
}
