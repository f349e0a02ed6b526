//! A rig taken from a rigged glTF instead of landmarks: the skin of a glTF
//! whose vertices match the character's rest frame by position (the same
//! character exported from a DCC tool, possibly re-ordered or split at UV
//! seams). Joints are the skin's bind-pose joint positions (inverse bind
//! matrices), mapped to the canonical skeleton as clips are (a known
//! convention's names, else the skin's structure: hierarchy and bind pose;
//! or a rig map); each vertex
//! takes the skin weights of the glTF vertex at its position, a joint the
//! map leaves out handing its weight to its nearest mapped ancestor. Part
//! labels, regions and regressors then follow as for landmarks.

use super::joints::JointEstimate;
use super::{EmbedError, Embedding};
use crate::mesh::Mesh;
use crate::mesh::io::gltf::GltfAsset;
use crate::rig::{Canonical, RigMap};
use glam::{DVec3, Mat4};
use std::collections::HashMap;
use std::path::Path;

/// Side confidence (0-1) below which a skin mapped by structure alone is
/// refused: its left and right would be a guess.
pub const MIN_SIDE_CONFIDENCE: f64 = 0.6;

/// Embeds the rig of `asset`'s skin in `mesh`. `map` overrides name
/// detection; `path` names the glTF in errors. Every vertex must lie
/// within 1e-4 of the bounding-box diagonal of a glTF vertex, in the bind
/// pose or in the rest pose in world space.
pub fn from_skin(
    mesh: &Mesh,
    asset: &GltfAsset,
    map: Option<&RigMap>,
    path: &Path,
) -> Result<Embedding, EmbedError> {
    let bad = |reason: String| EmbedError::File {
        path: path.to_path_buf(),
        reason,
    };
    let skin = asset
        .skin
        .as_ref()
        .ok_or_else(|| bad("the glTF has no skin".into()))?;
    let names = &skin.joint_names;
    let map = match map {
        Some(m) => m.clone(),
        None => {
            // Names when a convention matches, else the skin's structure
            // (hierarchy and bind pose), as for BVH and ASF clips.
            let d = crate::rig::load::detect_skin(asset).map_err(|e| bad(e.to_string()))?;
            if !d.missing.is_empty() {
                let miss: Vec<&str> = d.missing.iter().map(|c| c.name()).collect();
                return Err(bad(format!(
                    "the skin's joints ({}) give no joint for {}; pass a rig map",
                    d.map.convention,
                    miss.join(", ")
                )));
            }
            // A rig whose left and right the geometry cannot tell apart
            // would be mirrored as often as not: ask for a map instead.
            if let Some(c) = d.side_confidence.filter(|&c| c < MIN_SIDE_CONFIDENCE) {
                return Err(bad(format!(
                    "the skin's joints have no known names and its geometry does not tell \
                     left from right (confidence {c:.2}, below {MIN_SIDE_CONFIDENCE}); pass a rig map"
                )));
            }
            d.map
        }
    };
    // Canonical joint of each skin joint (or of its nearest mapped
    // ancestor); canonical joints the map derives (a head from the neck's
    // end, toes from the feet) own no skin joint.
    let mut canon: Vec<Option<Canonical>> = vec![None; names.len()];
    for c in Canonical::ALL {
        let Some(name) = map.joints.get(&c) else {
            if map.derived.contains_key(&c) {
                continue;
            }
            return Err(bad(format!("the rig map has no joint for {}", c.name())));
        };
        let i = names.iter().position(|n| n == name).ok_or_else(|| {
            bad(format!(
                "the rig map names {name:?} for {}, which is not a skin joint",
                c.name()
            ))
        })?;
        canon[i] = Some(c);
    }
    let owner: Vec<Canonical> = (0..names.len())
        .map(|i| {
            let mut k = Some(i as u32);
            let mut steps = 0;
            while let Some(j) = k {
                if let Some(c) = canon[j as usize] {
                    return c;
                }
                k = skin.parents.get(j as usize).copied().flatten();
                steps += 1;
                if steps > names.len() {
                    break;
                }
            }
            Canonical::Pelvis
        })
        .collect();
    let bind: Vec<DVec3> = skin
        .inverse_bind
        .iter()
        .map(|m| {
            let t = Mat4::from_cols_array_2d(m).inverse().w_axis;
            DVec3::new(t.x as f64, t.y as f64, t.z as f64)
        })
        .collect();
    // The mesh may match the glTF in its bind space (vertices as stored,
    // joints from the inverse bind matrices) or in its rest pose in world
    // space (node transforms applied, as exported from most tools).
    let (matched, joint_pos) = match match_positions(mesh.positions(), asset.mesh.positions()) {
        Ok(m) => (m, bind),
        Err((v, d)) => {
            let (verts, world_joints) = asset.rest_pose().unwrap_or_default();
            match match_positions(mesh.positions(), &verts) {
                Ok(m) => (m, world_joints),
                Err((_, d2)) => {
                    return Err(bad(format!(
                        "vertex {v} of the mesh is {:.3e} from the nearest glTF vertex (bind pose) and {:.3e} (rest pose in world space): the glTF is not this mesh",
                        d, d2
                    )));
                }
            }
        }
    };
    // Canonical positions (derived ones by their rules) from the skin as a
    // one-frame clip at the matched joint positions.
    if let Some(i) = joint_pos.iter().position(|p| !p.is_finite()) {
        return Err(bad(format!("joint {}: no usable transform", names[i])));
    }
    let (clip, _) = asset.skin_clip(&joint_pos, false).map_err(bad)?;
    let joints = map.rest_pose(&clip).map_err(|e| bad(e.to_string()))?;
    let mut w = vec![[0.0f64; Canonical::COUNT]; mesh.vertex_count()];
    for (row, &g) in w.iter_mut().zip(&matched) {
        let (js, ws) = (skin.joints[g as usize], skin.weights[g as usize]);
        for (j, x) in js.iter().zip(ws) {
            if let Some(c) = owner.get(*j as usize) {
                row[c.index()] += x as f64;
            }
        }
        let s: f64 = row.iter().sum();
        if s > 0.0 {
            row.iter_mut().for_each(|x| *x /= s);
        } else {
            row[Canonical::Pelvis.index()] = 1.0;
        }
    }
    let est = frame_of(mesh.positions(), &w, joints, &map.convention);
    Embedding::assemble(mesh, est, &w, None)
}

/// For each of `p`, the index of the point of `src` at the same place
/// (within 1e-4 of the diagonal); `Err((vertex, distance))` otherwise.
fn match_positions(p: &[[f64; 3]], src: &[[f64; 3]]) -> Result<Vec<u32>, (usize, f64)> {
    let diag = crate::mesh::Bounds::of(src).diagonal().max(1e-300);
    let tol = 1e-4 * diag;
    let cell = |q: &[f64; 3]| q.map(|x| (x / tol).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
    for (i, q) in src.iter().enumerate() {
        grid.entry(cell(q)).or_default().push(i as u32);
    }
    p.iter()
        .enumerate()
        .map(|(v, q)| {
            let c = cell(q);
            let mut best = (f64::INFINITY, u32::MAX);
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                            continue;
                        };
                        for &i in list {
                            let d = (DVec3::from_array(src[i as usize]) - DVec3::from_array(*q))
                                .length();
                            if d < best.0 {
                                best = (d, i);
                            }
                        }
                    }
                }
            }
            if best.0 <= tol {
                Ok(best.1)
            } else {
                let d = src
                    .iter()
                    .map(|s| (DVec3::from_array(*s) - DVec3::from_array(*q)).length())
                    .fold(f64::INFINITY, f64::min);
                Err((v, d))
            }
        })
        .collect()
}

/// The body frame and the end points of a skinned rest mesh: up from the
/// pelvis to the head (the vertical when close to it), left from the hips
/// and shoulders, and the tips of head, hands and feet as the farthest
/// vertices each end joint moves.
fn frame_of(
    p: &[[f64; 3]],
    w: &[[f64; Canonical::COUNT]],
    joints: [DVec3; Canonical::COUNT],
    convention: &str,
) -> JointEstimate {
    use Canonical as C;
    let j = |c: C| joints[c.index()];
    let up = super::axes::body_up(j(C::Head) - j(C::Pelvis));
    let side = (j(C::LHip) - j(C::RHip)) + (j(C::LShoulder) - j(C::RShoulder));
    let left = (side - up * side.dot(up)).normalize_or(up.any_orthonormal_vector());
    let facing = left.cross(up);
    let hs = p.iter().map(|q| DVec3::from_array(*q).dot(up));
    let (lo, hi) = hs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    let heaviest = |row: &[f64; Canonical::COUNT]| {
        (0..Canonical::COUNT)
            .max_by(|&a, &b| row[a].total_cmp(&row[b]))
            .unwrap_or(0)
    };
    // The farthest reach along `dir` from `from` of the vertices moved
    // mostly by one of `by`; half the parent bone if there are none.
    let tip = |from: C, by: &[C], dir: DVec3, fallback: f64| {
        let reach = p
            .iter()
            .zip(w)
            .filter(|(_, row)| by.iter().any(|c| c.index() == heaviest(row)))
            .map(|(q, _)| (DVec3::from_array(*q) - j(from)).dot(dir))
            .fold(f64::NEG_INFINITY, f64::max);
        j(from) + dir * if reach > 0.0 { reach } else { fallback }
    };
    let bone = |a: C, b: C| (j(b) - j(a)).length();
    let hand = |wr: C, el: C| {
        let d = (j(wr) - j(el)).normalize_or(up);
        tip(wr, &[wr], d, 0.5 * bone(el, wr))
    };
    let toe = |t: C, an: C| {
        let d = (j(t) - j(an)).normalize_or(facing);
        tip(t, &[t], d, 0.5 * bone(an, t))
    };
    JointEstimate {
        joints,
        head_top: tip(
            C::Head,
            &[C::Head, C::Neck],
            up,
            0.5 * bone(C::Neck, C::Head),
        ),
        hand_tips: [hand(C::LWrist, C::LElbow), hand(C::RWrist, C::RElbow)],
        toe_tips: [toe(C::LToe, C::LAnkle), toe(C::RToe, C::RAnkle)],
        up,
        facing,
        left,
        height: (hi - lo).max(1e-9),
        // The skin's own joints say where the middle is: the plane through
        // its pelvis.
        mid_plane: super::midplane::MidPlane::median_of(left, &[j(C::Pelvis)]),
        notes: vec![format!(
            "joints and skin weights from a glTF skin ({convention})"
        )],
    }
}
