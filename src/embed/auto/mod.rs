//! A character's rig from its capture alone (issue 41): which vertices
//! move together ([`decompose`], a rigid skinning decomposition after Le &
//! Deng 2012/2014), the joints where the parts meet ([`joints`]), and the
//! canonical humanoid read off the parts and the surface ([`humanoid`]).
//!
//! The result is a set of landmarks on the rest frame ([`AutoRig::landmarks`],
//! written by `db init` as `auto.landmarks.json` beside the manifest):
//! the existing pipeline ([`crate::embed::Embedding::new`]: joints from
//! landmarks, bone heat, parts, regressors) then runs unchanged, a user
//! can look at and edit the file as an override, and every check the
//! landmarks get (`Landmarks::validate`) applies to the automatic ones.
//! Writing a `JointEstimate` directly would have skipped those checks and
//! left nothing to edit.

pub mod decompose;
pub mod humanoid;
pub mod joints;

use super::landmarks::{Landmark, Landmarks, Mark};
use crate::mesh::Mesh;
use decompose::{DecomposeOptions, decompose};
use glam::DVec3;
use humanoid::{Crossing, Placed, along, crossings, extremities, geodesic, match_joints};
use serde::Serialize;

/// Settings of [`auto_rig`]. The defaults are `db init`'s.
#[derive(Debug, Clone, Copy)]
pub struct AutoOptions {
    /// The frame of the capture the parts are found in (its positions are
    /// the decomposition's rest); the landmarks are written on the
    /// topology mesh whatever the frame. Default `None`: the topology mesh
    /// itself (the capture's frame 0). `embed::rest::choose_rest_frame`
    /// will choose it.
    pub rest_frame: Option<usize>,
    /// Frames of the capture used, evenly spread. Default 40.
    pub max_frames: usize,
    /// The decomposition's settings.
    pub decompose: DecomposeOptions,
}

impl Default for AutoOptions {
    fn default() -> Self {
        AutoOptions {
            rest_frame: None,
            max_frames: 40,
            decompose: DecomposeOptions::default(),
        }
    }
}

/// Why a capture cannot be rigged automatically; each a one-line reason.
#[derive(Debug, thiserror::Error)]
pub enum AutoError {
    /// Fewer than two frames.
    #[error(
        "automatic rigging: the capture has {0} frame(s); the rig is learnt from how the body moves: give a sequence of several frames, or landmarks"
    )]
    TooFewFrames(usize),
    /// A frame with another vertex count than the mesh.
    #[error(
        "automatic rigging: frame {frame} has {have} vertices, the mesh {want}: every frame must be the mesh's vertices in its order"
    )]
    VertexCount {
        /// The frame.
        frame: usize,
        /// Its vertex count.
        have: usize,
        /// The mesh's.
        want: usize,
    },
    /// The rest frame asked for is not in the capture.
    #[error("automatic rigging: rest frame {frame} is past the capture's {frames} frames")]
    RestFrame {
        /// Asked.
        frame: usize,
        /// Frames.
        frames: usize,
    },
    /// The capture is not a standing humanoid; the reason says what was
    /// found.
    #[error("automatic rigging: not a humanoid: {0}; give landmarks")]
    NotHumanoid(String),
}

/// A joint the automatic rig found.
#[derive(Debug, Clone, Serialize)]
pub struct FoundJoint {
    /// Landmark name (`l_knee`...; `l_hip`/`r_hip` for the hips, which are
    /// no landmarks but set the groin).
    pub name: String,
    /// Position on the topology mesh.
    pub position: [f64; 3],
    /// Found from the motion (else placed by proportion).
    pub by_motion: bool,
    /// How much it bends in the capture (degrees).
    pub articulation_deg: f64,
}

/// The automatic rig of a capture.
#[derive(Debug, Clone, Serialize)]
pub struct AutoRig {
    /// Landmarks on the topology mesh (points).
    #[serde(skip)]
    pub landmarks: Landmarks,
    /// Up, facing and left (unit, the files' coordinates).
    pub up: [f64; 3],
    /// Facing.
    pub facing: [f64; 3],
    /// The character's left.
    pub left: [f64; 3],
    /// Height along up of the rest frame.
    pub height: f64,
    /// The rest frame the parts were found in (`None`: the topology mesh).
    pub rest_frame: Option<usize>,
    /// Frames of the capture used.
    pub frames_used: usize,
    /// Rigid parts found.
    pub parts: usize,
    /// Rigid part of each vertex.
    #[serde(skip)]
    pub labels: Vec<u32>,
    /// Limb joints, by motion or by proportion.
    pub joints: Vec<FoundJoint>,
    /// 0-1: the share of the twelve limb joints the motion showed, times
    /// the left/right agreement of the limbs' lengths.
    pub confidence: f64,
    /// What was found and assumed, one line each.
    pub notes: Vec<String>,
}

impl AutoRig {
    /// The landmarks as the JSON a landmarks file holds (points, with the
    /// mesh's vertex count).
    pub fn landmarks_json(&self, vertex_count: usize) -> String {
        let r = |x: f64| (x * 1e5).round() / 1e5;
        let mut lines = vec![format!("  \"vertex_count\": {vertex_count}")];
        for (l, mark) in &self.landmarks.marks {
            if let Mark::Point(p) = mark {
                lines.push(format!(
                    "  \"{}\": [{}, {}, {}]",
                    l.name(),
                    r(p[0]),
                    r(p[1]),
                    r(p[2])
                ));
            }
        }
        format!("{{\n{}\n}}\n", lines.join(",\n"))
    }

    /// One line for `db init`: the confidence and what was found.
    pub fn summary(&self) -> String {
        let by_motion = self.joints.iter().filter(|j| j.by_motion).count();
        let guessed: Vec<&str> = self
            .joints
            .iter()
            .filter(|j| !j.by_motion)
            .map(|j| j.name.as_str())
            .collect();
        format!(
            "automatic rig: confidence {:.2}; {} rigid parts in {} frames; {by_motion} of {} limb joints found by the motion{}; up {}, facing {}",
            self.confidence,
            self.parts,
            self.frames_used,
            self.joints.len(),
            if guessed.is_empty() {
                String::new()
            } else {
                format!(" (by proportion: {})", guessed.join(", "))
            },
            axis_name(DVec3::from_array(self.up)),
            axis_name(DVec3::from_array(self.facing)),
        )
    }
}

/// "+Y", or the direction's coordinates when off the axes.
fn axis_name(v: DVec3) -> String {
    let a = crate::embed::axes::nearest_axis(v);
    if a.dot(v) > 0.95 {
        let k = if a.x != 0.0 {
            "X"
        } else if a.y != 0.0 {
            "Y"
        } else {
            "Z"
        };
        format!("{}{k}", if a.dot(DVec3::ONE) > 0.0 { "+" } else { "-" })
    } else {
        format!("({:.2}, {:.2}, {:.2})", v.x, v.y, v.z)
    }
}

/// A limb: its tip, its path to the trunk (vertex, distance from the
/// tip), and its three joints where the motion showed them.
type Limb = (u32, Vec<(u32, f64)>, Vec<Option<Crossing>>);

/// Expected distances from the tip (fractions of the height) of a leg's
/// ankle, knee and hip, and of an arm's wrist, elbow and shoulder, along
/// the surface.
const LEG: [f64; 3] = [0.12, 0.37, 0.6];
const ARM: [f64; 3] = [0.10, 0.25, 0.42];
/// A joint must bend this much (RMS, degrees) in the capture.
const MIN_BEND_DEG: f64 = 6.0;

/// Rigs `mesh` (the topology; its positions are the capture's frame 0
/// unless `opts.rest_frame` says another) from the capture's `frames`
/// (each the mesh's vertices in order).
pub fn auto_rig(
    mesh: &Mesh,
    frames: &[&[[f64; 3]]],
    opts: &AutoOptions,
) -> Result<AutoRig, AutoError> {
    let n = mesh.vertex_count();
    if let Some((f, fr)) = frames.iter().enumerate().find(|(_, f)| f.len() != n) {
        return Err(AutoError::VertexCount {
            frame: f,
            have: fr.len(),
            want: n,
        });
    }
    if frames.len() < 2 {
        return Err(AutoError::TooFewFrames(frames.len()));
    }
    if let Some(r) = opts.rest_frame
        && r >= frames.len()
    {
        return Err(AutoError::RestFrame {
            frame: r,
            frames: frames.len(),
        });
    }
    let topo = mesh.positions();
    let rest: &[[f64; 3]] = opts.rest_frame.map_or(topo, |r| frames[r]);
    // Frame 0 of the fit is the topology mesh (so that rest points map
    // back onto it), then up to `max_frames` evenly spread.
    let k = opts.max_frames.clamp(2, frames.len().max(2));
    let mut used: Vec<&[[f64; 3]]> = vec![topo];
    for i in 0..k {
        let f = (i * (frames.len() - 1)) / (k - 1).max(1);
        used.push(frames[f]);
    }
    let nb = crate::embed::parts::neighbours(n, mesh.triangles());

    // Up: two extremities (the feet) on a floor, over the frames.
    let centre = rest.iter().map(|q| DVec3::from_array(*q)).sum::<DVec3>() / n as f64;
    let seed = (0..n)
        .min_by(|&a, &b| {
            DVec3::from_array(rest[a])
                .distance_squared(centre)
                .total_cmp(&DVec3::from_array(rest[b]).distance_squared(centre))
        })
        .unwrap_or(0) as u32;
    let tips = extremities(rest, &nb, seed, 6);
    if tips.len() < 6 {
        return Err(AutoError::NotHumanoid(
            "the surface has fewer than five extremities".into(),
        ));
    }
    let (up, floor_note) = find_up(rest, &used, &tips[..5])?;
    let hs = |q: [f64; 3]| DVec3::from_array(q).dot(up);
    let (lo, hi) = rest
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), q| {
            (a.min(hs(*q)), b.max(hs(*q)))
        });
    let height = hi - lo;
    if !(height > 0.0 && height.is_finite()) {
        return Err(AutoError::NotHumanoid("the rest frame is flat".into()));
    }
    let mut notes = vec![floor_note];
    if tips[5].1 > 0.75 * tips[4].1 {
        return Err(AutoError::NotHumanoid(format!(
            "a sixth extremity (vertex {}) reaches {:.0}% as far from the trunk as the fifth: a tail or another limb",
            tips[5].0,
            100.0 * tips[5].1 / tips[4].1
        )));
    }

    // The parts and their motion.
    let dec = decompose(rest, &used, &nb, height, &opts.decompose);
    if dec.count < 5 {
        return Err(AutoError::NotHumanoid(format!(
            "the capture moves as {} rigid piece(s), not an articulated body",
            dec.count
        )));
    }

    // The five chains: feet the two lowest tips, head the highest other.
    let mut five: Vec<u32> = tips[..5].iter().map(|t| t.0).collect();
    five.sort_by(|&a, &b| hs(rest[a as usize]).total_cmp(&hs(rest[b as usize])));
    let (feet, head, hands) = ([five[0], five[1]], five[4], [five[2], five[3]]);
    // Paths from each tip to a seed in the trunk: the vertex nearest the
    // body's axis at 65 % of its height (the belly or the back).
    let axis_at = centre + up * (lo + 0.65 * height - centre.dot(up));
    let trunk_seed = (0..n)
        .min_by(|&a, &b| {
            let d = |v: usize| {
                let q = DVec3::from_array(rest[v]) - axis_at;
                (q - up * q.dot(up)).length_squared() + 4.0 * q.dot(up).powi(2)
            };
            d(a).total_cmp(&d(b))
        })
        .unwrap_or(0) as u32;
    let (_, prev) = geodesic(rest, &nb, &[trunk_seed]);
    let path = |tip: u32| humanoid::path_to_source(rest, &prev, tip);
    // The trunk's parts: those on the paths of two limbs or more, and the
    // seed's (`rig::structure` reads the trunk of a joint tree the same
    // way: where the branches meet).
    let mut reached = vec![0usize; dec.count];
    for &tip in &five {
        let mut on: Vec<u32> = path(tip).iter().map(|x| dec.labels[x.0 as usize]).collect();
        on.sort_unstable();
        on.dedup();
        for l in on {
            reached[l as usize] += 1;
        }
    }
    let mut trunk: Vec<bool> = reached.iter().map(|&r| r >= 2).collect();
    trunk[dec.labels[trunk_seed as usize] as usize] = true;
    let limb = |tip: u32, exp: &[f64; 3], tol: f64| {
        let p = path(tip);
        let c = crossings(rest, &nb, &dec, &p, 0.05);
        debug_chain("limb", &c, height);
        // Up to the limb's entry into the trunk.
        let end = c
            .iter()
            .position(|x| trunk[x.proximal as usize])
            .map_or(c.len(), |i| i + 1);
        let c = &c[..end];
        let entry = (end > 0 && trunk[c[end - 1].proximal as usize]).then(|| c[end - 1]);
        let mut m = match_joints(c, &exp[..2], height, MIN_BEND_DEG, tol);
        let used = m
            .iter()
            .flatten()
            .any(|x| Some(x.from_tip) == entry.map(|e| e.from_tip));
        let root = entry.filter(|e| {
            !used
                && (e.from_tip - exp[2] * height).abs() <= 0.15 * height
                && m.iter().flatten().all(|x| x.from_tip < e.from_tip)
        });
        m.push(root);
        (tip, p, m)
    };
    let v3 = |q: [f64; 3]| DVec3::from_array(q);
    let mut legs = vec![limb(feet[0], &LEG, 0.1), limb(feet[1], &LEG, 0.1)];
    let knee = |l: &Limb| {
        l.2[1]
            .map(|c| c.joint.position)
            .unwrap_or_else(|| along(rest, &l.1, LEG[1] * height))
    };
    // Facing: square to the line through the hips (or knees), on the side
    // the toe tips point to from the knees.
    let flat = |d: DVec3| d - up * d.dot(up);
    let hips_found = legs.iter().all(|l| l.2[2].is_some());
    let side_point = |l: &Limb| match l.2[2] {
        Some(c) if hips_found => c.joint.position,
        _ => knee(l),
    };
    let across = flat(side_point(&legs[0]) - side_point(&legs[1]));
    let mut toes = DVec3::ZERO;
    for l in &legs {
        toes += flat(v3(rest[l.0 as usize]) - knee(l)).normalize_or_zero();
    }
    let square = up.cross(across).normalize_or_zero();
    let facing = if square == DVec3::ZERO {
        toes.normalize_or_zero()
    } else if square.dot(toes) >= 0.0 {
        square
    } else {
        -square
    };
    if facing == DVec3::ZERO {
        return Err(AutoError::NotHumanoid(
            "the feet point nowhere: no facing".into(),
        ));
    }
    let left = up.cross(facing).normalize();
    // Sides: the limb whose root (or knee, elbow) lies more to the left is
    // the left one.
    if side_point(&legs[0]).dot(left) < side_point(&legs[1]).dot(left) {
        legs.swap(0, 1);
    }
    let mut arms = vec![limb(hands[0], &ARM, 0.08), limb(hands[1], &ARM, 0.08)];
    let arm_point = |l: &Limb| {
        l.2[2]
            .or(l.2[1])
            .map(|c| c.joint.position)
            .unwrap_or_else(|| along(rest, &l.1, ARM[1] * height))
    };
    if arm_point(&arms[0]).dot(left) < arm_point(&arms[1]).dot(left) {
        arms.swap(0, 1);
    }

    // Joints, by motion or by proportion.
    let mut found: Vec<(String, Placed)> = Vec::new();
    let place = |m: Option<Crossing>, p: &[(u32, f64)], d: f64| match m {
        Some(c) => Placed {
            position: c.joint.position,
            by_motion: true,
            articulation_deg: c.joint.articulation_deg,
        },
        None => Placed {
            position: along(rest, p, d),
            by_motion: false,
            articulation_deg: 0.0,
        },
    };
    for (side, (_, p, m)) in ["l", "r"].iter().zip(&legs) {
        for (k, name) in ["ankle", "knee", "hip"].iter().enumerate() {
            found.push((format!("{side}_{name}"), place(m[k], p, LEG[k] * height)));
        }
    }
    for (side, (_, p, m)) in ["l", "r"].iter().zip(&arms) {
        // The wrist by proportion from the elbow when the hand does not bend.
        let elbow_d = m[1].map_or(ARM[1] * height, |c| c.from_tip);
        let dw = [elbow_d * 0.43, ARM[1] * height, ARM[2] * height];
        for (k, name) in ["wrist", "elbow", "shoulder"].iter().enumerate() {
            found.push((format!("{side}_{name}"), place(m[k], p, dw[k])));
        }
    }
    let get = |name: &str| {
        found
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, p)| *p)
            .unwrap_or(Placed {
                position: DVec3::ZERO,
                by_motion: false,
                articulation_deg: 0.0,
            })
    };

    // Symmetry of the limbs: tip to root lengths left against right.
    let len = |tip: u32, root: &str| v3(rest[tip as usize]).distance(get(root).position);
    let ratio = |a: f64, b: f64| a.min(b) / a.max(b).max(1e-12);
    let sym = ratio(len(legs[0].0, "l_hip"), len(legs[1].0, "r_hip")).min(ratio(
        len(arms[0].0, "l_shoulder"),
        len(arms[1].0, "r_shoulder"),
    ));
    let by_motion = found.iter().filter(|(_, p)| p.by_motion).count();
    let confidence = by_motion as f64 / found.len() as f64 * sym;

    // Landmarks (rest-frame points, mapped onto the topology below).
    let mut marks: Vec<(Landmark, DVec3)> = Vec::new();
    for (l, name) in [
        (Landmark::LWrist, "l_wrist"),
        (Landmark::RWrist, "r_wrist"),
        (Landmark::LElbow, "l_elbow"),
        (Landmark::RElbow, "r_elbow"),
        (Landmark::LKnee, "l_knee"),
        (Landmark::RKnee, "r_knee"),
        (Landmark::LShoulder, "l_shoulder"),
        (Landmark::RShoulder, "r_shoulder"),
        (Landmark::LAnkle, "l_ankle"),
        (Landmark::RAnkle, "r_ankle"),
    ] {
        let p = get(name);
        // Optional landmarks the motion did not show are left to the
        // embedding's own defaults.
        let optional = matches!(
            l,
            Landmark::LShoulder | Landmark::RShoulder | Landmark::LAnkle | Landmark::RAnkle
        );
        if p.by_motion || !optional {
            marks.push((l, p.position));
        }
    }
    // The groin: below the hips' midpoint by the embedding's hip offset
    // (`place_joints` puts the hips 3.5 % of the height above the groin).
    let groin = if get("l_hip").by_motion && get("r_hip").by_motion {
        (get("l_hip").position + get("r_hip").position) * 0.5 - up * (0.035 * height)
    } else {
        // Between the knees, at a usual crotch height (47 % of the height).
        notes.push("groin: the hips do not show in the motion (clothing?); placed between the knees at 47% of the height".into());
        let mid = (get("l_knee").position + get("r_knee").position) * 0.5;
        mid + up * (lo + 0.47 * height - mid.dot(up))
    };
    marks.push((Landmark::Groin, groin));
    // The chin: 12.5 % of the height below the top of the head, ahead of
    // its axis by `place_joints`'s chin offset.
    let top = v3(rest[head as usize]);
    marks.push((
        Landmark::Chin,
        top - up * (0.125 * height) + facing * (0.04 * height),
    ));
    marks.push((Landmark::HeadTop, top));

    // Onto the topology: by the motion of the part of the nearest vertex.
    let to_topo = |q: DVec3| -> [f64; 3] {
        if opts.rest_frame.is_none() {
            return q.to_array();
        }
        let v = (0..n)
            .min_by(|&a, &b| {
                v3(rest[a])
                    .distance_squared(q)
                    .total_cmp(&v3(rest[b]).distance_squared(q))
            })
            .unwrap_or(0);
        dec.motions[dec.labels[v] as usize].apply(0, q).to_array()
    };
    let mut landmarks = Landmarks::default();
    for (l, q) in &marks {
        landmarks.marks.insert(*l, Mark::Point(to_topo(*q)));
    }
    let guessed: Vec<&str> = found
        .iter()
        .filter(|(_, p)| !p.by_motion)
        .map(|(n, _)| n.as_str())
        .collect();
    if !guessed.is_empty() {
        notes.push(format!(
            "placed by proportion along the limb (the capture does not bend there): {}",
            guessed.join(", ")
        ));
    }
    notes.push(format!(
        "limbs: left/right lengths agree to {:.0}%",
        100.0 * sym
    ));
    let rotate = |d: DVec3| -> [f64; 3] {
        match opts.rest_frame {
            None => d.to_array(),
            Some(_) => {
                let v = seed as usize;
                (dec.motions[dec.labels[v] as usize].r[0] * d).to_array()
            }
        }
    };
    Ok(AutoRig {
        landmarks,
        up: rotate(up),
        facing: rotate(facing),
        left: rotate(left),
        height,
        rest_frame: opts.rest_frame,
        frames_used: used.len() - 1,
        parts: dec.count,
        labels: dec.labels.clone(),
        joints: found
            .iter()
            .map(|(name, p)| FoundJoint {
                name: name.clone(),
                position: to_topo(p.position),
                by_motion: p.by_motion,
                articulation_deg: p.articulation_deg,
            })
            .collect(),
        confidence,
        notes,
    })
}

/// Up: among ±X, ±Y, ±Z, the directions along which two of the five
/// extremities are at the bottom of the rest frame and the third clearly
/// higher, the one whose lowest point over the frames (the floor) varies
/// least. Returns it with a note.
fn find_up(
    rest: &[[f64; 3]],
    frames: &[&[[f64; 3]]],
    tips: &[(u32, f64)],
) -> Result<(DVec3, String), AutoError> {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for q in rest {
        lo = lo.min(DVec3::from_array(*q));
        hi = hi.max(DVec3::from_array(*q));
    }
    let mut best: Option<(f64, DVec3)> = None;
    for u in [
        DVec3::Y,
        DVec3::Z,
        DVec3::X,
        DVec3::NEG_Y,
        DVec3::NEG_Z,
        DVec3::NEG_X,
    ] {
        let ext = (hi - lo).dot(u.abs());
        let mut h: Vec<f64> = tips
            .iter()
            .map(|t| DVec3::from_array(rest[t.0 as usize]).dot(u))
            .collect();
        h.sort_by(f64::total_cmp);
        let bottom = rest
            .iter()
            .map(|q| DVec3::from_array(*q).dot(u))
            .fold(f64::INFINITY, f64::min);
        if !(h[1] - bottom < 0.12 * ext && h[2] - h[1] > 0.25 * ext) {
            continue;
        }
        let floors: Vec<f64> = frames
            .iter()
            .map(|f| {
                f.iter()
                    .map(|q| DVec3::from_array(*q).dot(u))
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        let mean = floors.iter().sum::<f64>() / floors.len() as f64;
        let sd = (floors.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / floors.len() as f64)
            .sqrt()
            / ext;
        if best.is_none_or(|b| sd < b.0) {
            best = Some((sd, u));
        }
    }
    match best {
        Some((sd, u)) => Ok((
            u,
            format!(
                "up {}: two extremities (the feet) at the bottom, the floor steady to {:.1}% of the height over the frames",
                axis_name(u),
                100.0 * sd
            ),
        )),
        None => Err(AutoError::NotHumanoid(
            "along no axis do two extremities (feet) rest at the bottom with the others clearly above".into(),
        )),
    }
}

/// Logs a limb's crossings (tracing, debug level).
fn debug_chain(what: &str, c: &[Crossing], h: f64) {
    let parts: Vec<String> = c
        .iter()
        .map(|c| {
            format!(
                "{}>{} at {:.2}h bends {:.0}° mis {:.1}%",
                c.distal,
                c.proximal,
                c.from_tip / h,
                c.joint.articulation_deg,
                100.0 * c.joint.mismatch / h
            )
        })
        .collect();
    tracing::debug!("automatic rig, {what} from its tip: {}", parts.join("; "));
}
