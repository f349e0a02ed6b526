//! [`auto_rig`]: the steps in order — the input checked, the frames
//! sampled, the body's extremities, up and height, the rigid parts, the
//! five chains, the limbs sided, the joints placed (by the motion or by
//! proportion), the landmarks, and everything carried onto the topology.

use super::body::Body;
use super::branches::{body_tips, sixth_limit};
use super::decompose::decompose;
use super::humanoid::{Placed, along, get_joint};
use super::limbs::{ARM, Chains, Sided, knee_to_toe, side};
use super::neck::NeckReading;
use super::options::{AutoError, AutoOptions, FrameSample};
use super::report::{AutoRig, FoundJoint};
use super::up::find_up;
use crate::embed::landmarks::{Anchor, Landmark, Landmarks, Mark};
use crate::embed::pose_order;
use crate::mesh::Mesh;
use glam::DVec3;

/// The knees' distances to their toe tips may differ by this fraction of
/// the height before the rig warns (samba's, crane's: 2 %, 1 %).
const KNEE_TOLERANCE: f64 = 0.03;

/// A groin placed by proportion on a headless body stands this many times
/// the knees' height above the floor ([`landmark_points`]).
const GROIN_OVER_KNEES: f64 = 1.65;

/// Rigs `mesh` (the topology; its positions are the capture's frame 0
/// unless `opts.rest_frame` says another) from the capture's `frames`
/// (each the mesh's vertices in order).
///
/// Vertices in no triangle ([`crate::mesh::stray`]: a cut's leftovers)
/// take no part: the body is rigged without them (a leftover above the
/// head was its top, and a headless body with one had a sixth
/// extremity), and each takes its carrier's part.
pub fn auto_rig(
    mesh: &Mesh,
    frames: &[&[[f64; 3]]],
    opts: &AutoOptions,
) -> Result<AutoRig, AutoError> {
    check_input(mesh, frames, opts)?;
    let Some(c) = crate::embed::stray::Compact::of(mesh) else {
        return rig_checked(mesh, frames, opts);
    };
    let own = c.frames(frames);
    let frames: Vec<&[[f64; 3]]> = own.iter().map(Vec::as_slice).collect();
    let compact = c.mesh(mesh).map_err(AutoError::WithoutStray)?;
    let mut rig = rig_checked(&compact, &frames, opts)?;
    rig.landmarks = c.landmarks_back(std::mem::take(&mut rig.landmarks));
    rig.labels = c.spread(&rig.labels, 0);
    Ok(rig)
}

/// [`auto_rig`] of a mesh whose every vertex is in a triangle, its input
/// checked.
fn rig_checked(
    mesh: &Mesh,
    frames: &[&[[f64; 3]]],
    opts: &AutoOptions,
) -> Result<AutoRig, AutoError> {
    let n = mesh.vertex_count();
    let topo = mesh.positions();
    let rest: &[[f64; 3]] = opts.rest_frame.map_or(topo, |r| frames[r]);
    let used = match opts.frames {
        FrameSample::InOrder => sample_evenly(topo, frames, opts.max_frames),
        FrameSample::Farthest | FrameSample::PoseQuantiles => {
            sample_by_pose(rest, frames, opts.max_frames, opts.frames)
        }
        FrameSample::Spread | FrameSample::MedianQuantiles => {
            sample_by_motion(frames, opts.max_frames, opts.frames)
        }
    };
    let in_order = opts.frames == FrameSample::InOrder;
    let nb = crate::embed::parts::neighbours(n, mesh.triangles());
    let (mut body, tips, mut notes) = find_body(rest, mesh.triangles(), &used, &nb, opts)?;
    let mut chains = Chains::find(&body, &tips);
    if let Some(top) = tips.get(4).filter(|t| t.1 == 0.0) {
        // The stump `find_body` added (reach 0): the head's chain.
        chains.headed_by(top.0);
    } else if opts.head_axis {
        chains.head_nearest_axis(&body);
    }
    let sided = side(&body, &chains)?;
    for (what, [l, r]) in ["legs", "arms"].iter().zip(sided.lateral) {
        if l <= 0.0 || r >= 0.0 {
            notes.push(format!(
                "WARNING: the {what} lie {:.1}% and {:.1}% of the height to the left of the body's mid-plane over the capture (one of them across it): their sides may be swapped; look at the picture and correct the landmarks file, or give landmarks",
                100.0 * l / body.height,
                100.0 * r / body.height
            ));
        }
    }
    notes.extend(cut_ends_notes(&body, &sided));
    let neck = NeckReading::read(rest, &nb, body.up, body.height, chains.head);
    let cut = neck.cut().filter(|_| opts.read_head);
    notes.extend(super::floor::floor_under_cuts(
        &mut body,
        &sided,
        cut.is_none(),
    ));
    let mut found = place_joints(&body, &sided);
    super::hips::bound_hips(&body, &sided, &mut found, &mut notes);
    let (sym, confidence) = symmetry_and_confidence(rest, &body, &sided, &found, &mut notes);
    let v3 = |q: [f64; 3]| DVec3::from_array(q);
    if let Some(why) = &cut {
        notes.push(format!("no head: {why}; the landmarks say \"absent\": [\"head\"] (the embedding puts the chin at the top of the neck and skips the head checks: the head on the mid-plane, inside the body, the head part)"));
    }
    let marks = landmark_points(&body, &chains, &sided, &found, cut.is_none(), &mut notes);

    // Onto the topology: by the motion of the part of the nearest vertex
    // (each part's rigid fit from the rest frame onto the topology's
    // positions; the topology takes no part in the decomposition).
    let dec = &body.dec;
    // (Evenly spread, the topology is the fit's first frame: each part's
    // motion onto it is the fit's own.)
    let onto_topo = match (opts.rest_frame, in_order) {
        (None, _) => Vec::new(),
        (Some(_), false) => super::decompose::fit_onto(rest, topo, &dec.labels, dec.count),
        (Some(_), true) => dec.motions.iter().map(|m| (m.r[0], m.t[0])).collect(),
    };
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
        onto_topo
            .get(dec.labels[v] as usize)
            .map_or(q, |(r, t)| *r * q + *t)
            .to_array()
    };
    // Found on another frame than the topology's: fixed to the surface of
    // that frame (`Mark::Surface`), so that the embedding on it (`db
    // init`'s `[rig] rest`) gets them exactly where they were found.
    // Written as points carried to the topology they came back through
    // the topology's nearest triangles (`Landmarks::moved`): with a hand
    // on the hip there, a mark near the hand rode the hip, and samba
    // started at frame 130 was refused ("l_knee … above the groin").
    let mut landmarks = Landmarks::default();
    for (l, q) in &marks {
        let mark = match opts.rest_frame {
            None => Mark::Point(q.to_array()),
            Some(_) => anchored(*q, rest, mesh.triangles(), &dec.labels)
                .map_or_else(|| Mark::Point(to_topo(*q)), Mark::Surface),
        };
        landmarks.marks.insert(*l, mark);
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
                let v = body.seed as usize;
                onto_topo
                    .get(dec.labels[v] as usize)
                    .map_or(d, |(r, _)| *r * d)
                    .to_array()
            }
        }
    };
    Ok(AutoRig {
        landmarks,
        up: rotate(body.up),
        facing: rotate(sided.facing),
        left: rotate(sided.left),
        height: body.height,
        rest_frame: opts.rest_frame,
        frames_used: used.len() - usize::from(in_order),
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
        headless: cut.is_some(),
        trunk_depth: neck.trunk_depth,
        notes,
    })
}

/// The limbs' symmetry (tip-to-root lengths left against right, the
/// least of the legs' and the arms' ratios) and the rig's confidence: the
/// share of joints the motion showed times the symmetry, lowered in
/// proportion when the knees are not as far from their toes (a body's legs
/// have one length), which is also said loudly in `notes`.
fn symmetry_and_confidence(
    rest: &[[f64; 3]],
    body: &Body,
    sided: &Sided,
    found: &[(String, Placed)],
    notes: &mut Vec<String>,
) -> (f64, f64) {
    let get = |name: &str| get_joint(found, name);
    // Symmetry of the limbs: tip to root lengths left against right; a
    // pair with a limb on a cut ([`super::cut_ends`]) from its distal
    // joints (a cut limb's is the cut's centre), or one foot or hand cut
    // off would read as limbs of two lengths.
    let v3 = |q: [f64; 3]| DVec3::from_array(q);
    let cut = |pair: &[super::limbs::Limb]| pair.iter().any(|l| body.cut_at(l.0).is_some());
    let (legs, arms) = (&sided.legs, &sided.arms);
    let (legs_cut, arms_cut) = (cut(legs), cut(arms));
    let len =
        |limb: &super::limbs::Limb, side: &str, distal: &str, root: &str, from_joint: bool| {
            let root = get(&format!("{side}_{root}")).position;
            match from_joint {
                true => get(&format!("{side}_{distal}")).position.distance(root),
                false => v3(rest[limb.0 as usize]).distance(root),
            }
        };
    let ratio = |a: f64, b: f64| a.min(b) / a.max(b).max(1e-12);
    let sym = ratio(
        len(&legs[0], "l", "ankle", "hip", legs_cut),
        len(&legs[1], "r", "ankle", "hip", legs_cut),
    )
    .min(ratio(
        len(&arms[0], "l", "wrist", "shoulder", arms_cut),
        len(&arms[1], "r", "wrist", "shoulder", arms_cut),
    ));
    let by_motion = found.iter().filter(|(_, p)| p.by_motion).count();
    let mut confidence = by_motion as f64 / found.len() as f64 * sym;
    // The knees as far from the toes (the legs' one length): a check, said
    // loudly, and the confidence lowered in proportion; from the ankles
    // when a leg is on a cut.
    let (kl, kr, kd) = match legs_cut {
        false => knee_to_toe(body, sided),
        true => {
            let shin = |s: &str| {
                get(&format!("{s}_knee"))
                    .position
                    .distance(get(&format!("{s}_ankle")).position)
            };
            let (l, r) = (shin("l"), shin("r"));
            (l, r, (l - r).abs())
        }
    };
    if kd > KNEE_TOLERANCE * body.height {
        notes.push(format!(
            "WARNING: the knees are {kl:.3} and {kr:.3} from their {}, {:.1}% of the height apart (a body's legs have one length; tolerance {:.0}%): one knee is probably at a clothing edge; look at the picture (`InitSetup::png`) and correct l_knee/r_knee in the landmarks file, or give landmarks",
            if legs_cut { "ankles" } else { "toe tips" },
            100.0 * kd / body.height,
            100.0 * KNEE_TOLERANCE
        ));
        confidence *= (1.0 - kd / body.height / (4.0 * KNEE_TOLERANCE)).max(0.0);
    }
    (sym, confidence)
}

/// `q` fixed to its nearest triangle of `rest` among those of the part
/// (`labels`) of its nearest vertex (a joint inside the knee on the
/// knee's surface, not on a skirt's or a hand's nearby); among all
/// triangles when that part has none. `None` without triangles.
fn anchored(q: DVec3, rest: &[[f64; 3]], triangles: &[[u32; 3]], labels: &[u32]) -> Option<Anchor> {
    let d = |v: usize| DVec3::from_array(rest[v]).distance_squared(q);
    let v = (0..rest.len()).min_by(|&a, &b| d(a).total_cmp(&d(b)))?;
    let part = labels.get(v).copied();
    let own = |t: &&[u32; 3]| t.iter().all(|&i| labels.get(i as usize).copied() == part);
    Anchor::nearest(q.to_array(), rest, triangles.iter().filter(own))
        .or_else(|| Anchor::nearest(q.to_array(), rest, triangles))
}

/// Every frame the mesh's vertex count, two frames or more, the rest frame
/// among them.
fn check_input(mesh: &Mesh, frames: &[&[[f64; 3]]], opts: &AutoOptions) -> Result<(), AutoError> {
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
    Ok(())
}

/// The frames the decomposition fits, in the order it visits them: up to
/// `max_frames` (at least 2) chosen by their poses alone, seeded by the
/// rest frame's pose: farthest-point first
/// ([`pose_order::farthest_first`], [`FrameSample::Farthest`]) or at
/// evenly spaced ranks of the distance from it ([`pose_order::quantiles`],
/// [`FrameSample::PoseQuantiles`]), so that the same capture in any order,
/// started on any frame, is fitted on the same frames in the same order.
/// (They were spread evenly in the order given after the topology's
/// positions as the fit's first frame: samba started at a frame with the
/// hands on the hips rigged 1.4 % of the height and 8 % of the parts away
/// from its clear start on the same rest frame.)
fn sample_by_pose<'a>(
    rest: &[[f64; 3]],
    frames: &[&'a [[f64; 3]]],
    max_frames: usize,
    how: FrameSample,
) -> Vec<&'a [[f64; 3]]> {
    let picks = pose_order::descriptor_vertices(frames);
    let descs: Vec<Vec<f64>> = frames
        .iter()
        .map(|f| pose_order::descriptor_at(f, &picks))
        .collect();
    let seed = pose_order::descriptor_at(rest, &picks);
    let k = max_frames.max(2);
    let picked = match how {
        FrameSample::PoseQuantiles => pose_order::quantiles(&descs, &seed, k),
        _ => pose_order::farthest_first(&descs, &seed, k),
    };
    picked.into_iter().map(|f| frames[f]).collect()
}

/// The frames the decomposition fits chosen by the motion alone, neither
/// the rest frame nor either order playing a part: up to `max_frames`
/// (at least 2) from the median pose of all frames, farthest-point first
/// ([`FrameSample::Spread`]) or at evenly spaced ranks of the distance
/// from it ([`FrameSample::MedianQuantiles`]), the poses read on
/// [`pose_order::descriptor_vertices`]. (Seeded by the rest frame's pose,
/// samba's left elbow on the held rest rule was 2.7 % of the height from
/// the landmark rig's from rest frame 2 and 4.2 % from frame 4 of the
/// same still start, 1.9 % from frame 4 with frame 2's sample: session 28.)
fn sample_by_motion<'a>(
    frames: &[&'a [[f64; 3]]],
    max_frames: usize,
    how: FrameSample,
) -> Vec<&'a [[f64; 3]]> {
    let picks = pose_order::descriptor_vertices(frames);
    let descs: Vec<Vec<f64>> = frames
        .iter()
        .map(|f| pose_order::descriptor_at(f, &picks))
        .collect();
    let seed = pose_order::median(&descs);
    let k = max_frames.max(2);
    let picked = match how {
        FrameSample::MedianQuantiles => pose_order::quantiles(&descs, &seed, k),
        _ => pose_order::farthest_first(&descs, &seed, k),
    };
    picked.into_iter().map(|f| frames[f]).collect()
}

/// Frame 0 of the fit is the topology mesh (so that rest points map back
/// onto it), then up to `max_frames` evenly spread in the order given
/// ([`FrameSample::InOrder`]).
fn sample_evenly<'a>(
    topo: &'a [[f64; 3]],
    frames: &[&'a [[f64; 3]]],
    max_frames: usize,
) -> Vec<&'a [[f64; 3]]> {
    let k = max_frames.clamp(2, frames.len().max(2));
    let mut used: Vec<&[[f64; 3]]> = vec![topo];
    for i in 0..k {
        let f = (i * (frames.len() - 1)) / (k - 1).max(1);
        used.push(frames[f]);
    }
    used
}

/// The body, its five extremities (vertex, reach) and the notes.
type Found<'a> = (Body<'a>, Vec<(u32, f64)>, Vec<String>);

/// The body: its extremities (the tips of its first five branches,
/// [`super::branches`]), up (two of them, the feet, on a floor over the
/// frames), height, and rigid parts; refused when it is no humanoid (fewer
/// than five branches but a body cut at the neck's four and its top,
/// [`super::neck::headless_top`]; a sixth reaching [`sixth_limit`] of
/// them, no floor, fewer than five rigid parts). Returns it with its five extremities and the
/// notes so far.
fn find_body<'a>(
    rest: &'a [[f64; 3]],
    triangles: &[[u32; 3]],
    used: &'a [&'a [[f64; 3]]],
    nb: &'a [Vec<u32>],
    opts: &AutoOptions,
) -> Result<Found<'a>, AutoError> {
    let found = body_tips(rest, triangles, nb, sixth_limit, opts.tip_seed);
    for c in &found.candidates {
        tracing::debug!(
            "extremity candidate: vertex {} at {:?}, reach {:.4}, disc ratio {:.2}, detour {:.2}, branch {}",
            c.vertex,
            rest[c.vertex as usize],
            c.reach,
            c.sheet,
            c.detour,
            c.is_branch()
        );
    }
    let (seed, centre, mut tips) = (found.seed, found.centre, found.five);
    // Four branches: a body cut at the neck is topped by its stump.
    if tips.len() == 4
        && opts.read_head
        && let Some(top) = super::neck::headless_top(rest, nb, used, &tips)
    {
        tips.push((top, 0.0));
    }
    if tips.len() < 5 {
        return Err(AutoError::NotHumanoid(
            "the surface has fewer than five extremities".into(),
        ));
    }
    if let Some(six) = found.sixth {
        let reaches: Vec<f64> = tips.iter().map(|t| t.1).collect();
        return Err(AutoError::NotHumanoid(format!(
            "a sixth extremity (vertex {}) reaches {:.0}% as far from the trunk as the fifth (limit {:.0}%): a tail or another limb",
            six.vertex,
            100.0 * six.reach / tips[4].1,
            100.0 * sixth_limit(&reaches) / tips[4].1
        )));
    }
    let (up, floor_note) = find_up(rest, used, &tips[..5])?;
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
    notes.extend(found.guard.and_then(|g| g.why()));
    // The parts and their motion.
    let dec = decompose(rest, used, nb, height, &opts.decompose);
    if dec.count < 5 {
        // Two frames of a standing body (or a capture that holds still)
        // move as one piece too: say how many frames were read.
        return Err(AutoError::NotHumanoid(format!(
            "the capture moves as {} rigid piece(s) over the {} frame(s) read, not an articulated body (a body whose limbs bend in some of its frames shows five or more: too few frames, or a capture holding still?)",
            dec.count,
            used.len()
        )));
    }
    let body = Body {
        rest,
        frames: used,
        nb,
        dec,
        up,
        lo,
        height,
        seed,
        centre,
        thigh_hip: opts.thigh_hip,
        facing: opts.facing,
        split_knee: opts.split_knee,
        guard_pivots: opts.guard_pivots,
        rims: super::cut_ends::rims(rest, triangles),
    };
    Ok((body, tips, notes))
}

/// What `db init` says of limbs whose tips are on a cut
/// ([`super::cut_ends`]), one note per pair, if any.
fn cut_ends_notes(body: &Body, sided: &Sided) -> Vec<String> {
    let pairs = [
        ("foot", "leg", "ankle", &sided.legs),
        ("hand", "arm", "wrist", &sided.arms),
    ];
    let mut notes = Vec::new();
    for (end, limb, joint, limbs) in pairs {
        let cut: Vec<&str> = ["left", "right"]
            .into_iter()
            .zip(limbs.iter())
            .filter(|(_, a)| body.cut_at(a.0).is_some())
            .map(|(s, _)| s)
            .collect();
        if !cut.is_empty() {
            notes.push(format!(
                "no {end}: the {} {limb}'s tip is on a cut (an open boundary): its joints matched from the {joint}, placed at the cut's centre",
                cut.join(" and ")
            ));
        }
    }
    notes
}

/// The twelve limb joints, by motion or by proportion, left leg, right
/// leg, left arm, right arm, each distal first.
fn place_joints(body: &Body, sided: &Sided) -> Vec<(String, Placed)> {
    let (rest, height) = (body.rest, body.height);
    let mut found: Vec<(String, Placed)> = Vec::new();
    let place = |m: Option<super::humanoid::Crossing>, p: &[(u32, f64)], d: f64| match m {
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
    for (side, (tip, p, m)) in ["l", "r"].iter().zip(&sided.legs) {
        // A leg cut above the foot: its joints' distances from the cut,
        // its ankle at the cut's centre where the motion shows none.
        let cut = body.cut_at(*tip);
        let d = super::limbs::leg_distances(body, *tip);
        for (k, name) in ["ankle", "knee", "hip"].iter().enumerate() {
            let placed = match cut {
                Some(c) if k == 0 && m[0].is_none() => Placed {
                    position: c,
                    by_motion: true,
                    articulation_deg: 0.0,
                },
                _ => place(m[k], p, d[k] * height),
            };
            found.push((format!("{side}_{name}"), placed));
        }
    }
    for (side, (tip, p, m)) in ["l", "r"].iter().zip(&sided.arms) {
        // An arm cut at the wrist: its joints' distances from the cut.
        let cut = body.cut_at(*tip);
        let hand = if cut.is_some() { ARM[0] * height } else { 0.0 };
        // The wrist by proportion from the elbow when the hand does not bend.
        let elbow_d = m[1].map_or(ARM[1] * height - hand, |c| c.from_tip);
        let dw = [
            elbow_d * 0.43,
            ARM[1] * height - hand,
            ARM[2] * height - hand,
        ];
        for (k, name) in ["wrist", "elbow", "shoulder"].iter().enumerate() {
            let placed = match cut {
                // The cut's centre, where the motion shows no wrist.
                Some(c) if k == 0 && m[0].is_none() => Placed {
                    position: c,
                    by_motion: true,
                    articulation_deg: 0.0,
                },
                _ => place(m[k], p, dw[k]),
            };
            found.push((format!("{side}_{name}"), placed));
        }
    }
    found
}

/// The landmarks as rest-frame points: the limb joints (the ankles only
/// when the motion showed them), the groin, the chin and the head top
/// (with `head`; a body cut at the neck has neither: [`super::neck`]).
///
/// The shoulders are not written: the embedding places them as it does
/// for landmarks without shoulders (hand-made ones, samba's fixture): from
/// the neck by proportion, then along the upper arm's axis. The motion's
/// shoulder (the fixed point of the upper arm's part and the trunk's, a
/// ball joint read off a short band of the upper arm against a trunk whose
/// shoulder blade moves with the arm) put samba's right shoulder joint
/// 3.8 cm below the embedding's (on crane, arms raised as wings, 16 cm
/// below the other one), and CMU 03_02 retargeted through samba's
/// automatic rig held the head pitched: head-to-torso p95 6.3° with the
/// motion's shoulders, 5.1° without (the landmark rig's 3.5°; the head
/// measure's median 7.5° against its rest 3.8°); the boundary ring's
/// centre as the shoulder read 7.0°.
fn landmark_points(
    body: &Body,
    chains: &Chains,
    sided: &Sided,
    found: &[(String, Placed)],
    head: bool,
    notes: &mut Vec<String>,
) -> Vec<(Landmark, DVec3)> {
    let (up, lo, height) = (body.up, body.lo, body.height);
    let get = |name: &str| get_joint(found, name);
    let mut marks: Vec<(Landmark, DVec3)> = Vec::new();
    for (l, name) in [
        (Landmark::LWrist, "l_wrist"),
        (Landmark::RWrist, "r_wrist"),
        (Landmark::LElbow, "l_elbow"),
        (Landmark::RElbow, "r_elbow"),
        (Landmark::LKnee, "l_knee"),
        (Landmark::RKnee, "r_knee"),
        (Landmark::LAnkle, "l_ankle"),
        (Landmark::RAnkle, "r_ankle"),
    ] {
        let p = get(name);
        // Optional landmarks the motion did not show are left to the
        // embedding's own defaults.
        let optional = matches!(l, Landmark::LAnkle | Landmark::RAnkle);
        if p.by_motion || !optional {
            marks.push((l, p.position));
        }
    }
    // The groin: below the hips' midpoint by the embedding's hip offset
    // (`place_joints` puts the hips 3.5 % of the height above the groin).
    let groin = if get("l_hip").by_motion && get("r_hip").by_motion {
        let g = (get("l_hip").position + get("r_hip").position) * 0.5 - up * (0.035 * height);
        // Side to side, midway between the knees: the groin is on the
        // body's mid-plane, and a hip found at a skirt's boundary strays
        // sideways (samba's by 8 cm, which moved the mid-plane and the
        // hips, and sank a foot 16-29 cm into the floor in retargeting);
        // the knees, at the shins' ends, do not.
        let knees = (get("l_knee").position + get("r_knee").position) * 0.5;
        let left = sided.left;
        g + left * (knees - g).dot(left)
    } else {
        // Between the knees, at a usual crotch height: 47 % of the height,
        // or, with no head to measure the height by, 1.65 times the knees'
        // (crotch 0.47, knee 0.285 of the stature: Winter 2009, §4.1; the
        // fixtures' landmark rigs read 1.53-1.69).
        let mid = (get("l_knee").position + get("r_knee").position) * 0.5;
        let over_floor = if head {
            notes.push("groin: no hips from the motion to place it by (they do not show, or were taken for a clothing edge); placed between the knees at 47% of the height".into());
            0.47 * height
        } else {
            notes.push("groin: no hips from the motion to place it by (they do not show, or were taken for a clothing edge); placed between the knees at 1.65 times their height".into());
            GROIN_OVER_KNEES * (mid.dot(up) - lo)
        };
        mid + up * (lo + over_floor - mid.dot(up))
    };
    marks.push((Landmark::Groin, groin));
    if !head {
        return marks;
    }
    // The chin: 12.5 % of the height below the top of the head, ahead of
    // its axis by `place_joints`'s chin offset.
    let top = DVec3::from_array(body.rest[chains.head as usize]);
    marks.push((
        Landmark::Chin,
        top - up * (0.125 * height) + sided.facing * (0.04 * height),
    ));
    marks.push((Landmark::HeadTop, top));
    marks
}
