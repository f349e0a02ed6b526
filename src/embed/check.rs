//! A self-check of an embedding: what a rigger looks at before using one.
//! Left and right limbs symmetric (bone lengths, and joint distances from
//! the body's mid-plane), the pelvis on the mid-plane, every joint inside
//! the body (generalised winding number, [`super::surface`]), every part
//! non-empty and one connected region. Each problem is a [`Warning`]
//! naming the joint (or part) and the distance, in the mesh's units and as
//! a percentage of the height.
//!
//! The mid-plane here is estimated afresh from the joints the pelvis and
//! hips do not depend on (spine, chest, neck, head, and the midpoints of
//! the knees, ankles and shoulders: their median offset along the
//! embedding's left), so a pelvis placed off the middle is caught rather
//! than taken as the middle.

use super::Embedding;
use super::midplane::MidPlane;
use super::parts::{Part, neighbours, piece_counts};
use super::surface::{distance_to_surface, winding_number};
use crate::mesh::Mesh;
use crate::rig::Canonical;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Tolerances of the self-check, as fractions of the body height (bone
/// lengths: of the longer bone).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CheckOptions {
    /// The pelvis's distance from the mid-plane. Default value: 0.01.
    pub pelvis_offset: f64,
    /// Difference of the two hips' distances from the mid-plane. Default
    /// value: 0.01.
    pub hip_symmetry: f64,
    /// Difference of left and right limb joints' distances from the
    /// mid-plane (shoulders, elbows, wrists, knees, ankles, toes). Default
    /// value: 0.03.
    pub limb_symmetry: f64,
    /// Distance of spine, chest, neck and head from the mid-plane. Default
    /// value: 0.03.
    pub central_offset: f64,
    /// Relative difference of a left bone's length and its right twin's.
    /// Default value: 0.05.
    pub bone_ratio: f64,
    /// Least distance across between a left joint and its right twin.
    /// Default value: 0.02.
    pub twin_separation: f64,
}

impl Default for CheckOptions {
    fn default() -> Self {
        CheckOptions {
            pelvis_offset: 0.01,
            hip_symmetry: 0.01,
            limb_symmetry: 0.03,
            central_offset: 0.03,
            bone_ratio: 0.05,
            twin_separation: 0.02,
        }
    }
}

/// What kind of problem a warning reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Problem {
    /// A central joint (pelvis, spine, chest, neck, head) off the mid-plane.
    OffMidPlane,
    /// A left joint and its right twin at different distances from the
    /// mid-plane.
    Asymmetric,
    /// A left joint and its right twin (nearly) at one place across: both
    /// limbs' joints put in the middle of the two.
    Merged,
    /// A left bone and its right twin of different lengths.
    BoneLengths,
    /// A joint outside the body.
    Outside,
    /// A part with no vertex.
    EmptyPart,
    /// A part in several pieces.
    SplitPart,
    /// The embedding was made for another mesh.
    Mismatch,
    /// Both feet reach farther behind their ankle than in front along the
    /// rig's facing: the landmarks' left and right are swapped (facing is
    /// left × up).
    Backwards,
}

/// One problem of an embedding.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Warning {
    /// What kind.
    pub problem: Problem,
    /// The joint (for symmetry problems the left one of the pair) or part.
    pub joint: String,
    /// How far off, in the mesh's units (0 for part problems).
    pub distance: f64,
    /// `distance` as a percentage of the height.
    pub percent_of_height: f64,
    /// The whole message.
    pub message: String,
}

/// A left bone and its right twin.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BonePair {
    /// The left bone's child joint (e.g. `l_knee` for the left thigh).
    pub joint: String,
    /// Left length.
    pub left: f64,
    /// Right length.
    pub right: f64,
    /// `|left − right| / max(left, right)`.
    pub ratio: f64,
}

/// A part's size and connectedness.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PartCheck {
    /// The part.
    pub part: String,
    /// Labelled vertices.
    pub vertices: usize,
    /// Connected pieces (1 is right).
    pub pieces: usize,
}

/// The self-check of an embedding.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EmbedCheck {
    /// The body height the percentages are of.
    pub height: f64,
    /// The mid-plane the symmetry is measured about.
    pub mid_plane: MidPlane,
    /// Signed distance of the pelvis from the mid-plane (positive: left).
    pub pelvis_offset: f64,
    /// The same as a percentage of the height.
    pub pelvis_offset_percent: f64,
    /// Distances of the left and right hips from the mid-plane (each
    /// positive on its own side).
    pub hip_distances: [f64; 2],
    /// `|d_left − d_right|` of the hips as a percentage of the height.
    pub hip_asymmetry_percent: f64,
    /// Left/right bone pairs.
    pub bones: Vec<BonePair>,
    /// Joints found outside the body.
    pub outside: Vec<String>,
    /// Every part's size and pieces.
    pub parts: Vec<PartCheck>,
    /// The tolerances used.
    pub options: CheckOptions,
    /// Every problem found; empty when the embedding passes.
    pub warnings: Vec<Warning>,
    /// The checks skipped for a body end the mesh lacks
    /// ([`Embedding::absent`]), one line each; empty (and not written) for
    /// a whole body.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub skipped: Vec<String>,
}

impl EmbedCheck {
    /// Whether no problem was found.
    pub fn passed(&self) -> bool {
        self.warnings.is_empty()
    }
}

/// The mirror twin of each left joint.
const PAIRS: [(Canonical, Canonical); 7] = [
    (Canonical::LShoulder, Canonical::RShoulder),
    (Canonical::LElbow, Canonical::RElbow),
    (Canonical::LWrist, Canonical::RWrist),
    (Canonical::LHip, Canonical::RHip),
    (Canonical::LKnee, Canonical::RKnee),
    (Canonical::LAnkle, Canonical::RAnkle),
    (Canonical::LToe, Canonical::RToe),
];

/// [`check_with`] at the default tolerances.
pub fn check(e: &Embedding, mesh: &Mesh) -> EmbedCheck {
    check_with(e, mesh, &CheckOptions::default())
}

/// The self-check of embedding `e` of `mesh` at tolerances `o`, in named
/// steps (the mid-plane, central joints, twins, bones, joints inside,
/// parts), each adding its warnings in that order.
/// O(#joints · #F) for the inside test, O(#V) for the parts.
pub(crate) fn check_with(e: &Embedding, mesh: &Mesh, o: &CheckOptions) -> EmbedCheck {
    let h = e.height.max(1e-12);
    let plane = check_plane(e);
    let headless = e.absent.iter().any(|a| a == "head");
    // A body cut above the feet (`embed::footless`): its toes are the
    // embedding's guess on a foot that is not there.
    // One foot cut (`l_foot`, `r_foot`): its toe is the other's mirrored.
    let cut = ["l_foot", "r_foot"].map(|f| e.absent.iter().any(|a| a == "feet" || a == f));
    let footless = cut[0] || cut[1];
    let pairs: Vec<(Canonical, Canonical)> = PAIRS
        .into_iter()
        .filter(|(l, _)| !(footless && *l == Canonical::LToe))
        .collect();
    let mut w = Warnings {
        h,
        list: Vec::new(),
    };
    let pelvis_offset = plane.distance(joint(e, Canonical::Pelvis));
    check_central(e, &plane, o, headless, &mut w);
    let hip_distances = check_twins(e, &plane, o, &pairs, &mut w);
    let bones = check_bones(e, o, &pairs, &mut w);
    let outside = check_inside(e, mesh, headless, cut, &mut w);
    let parts = check_parts(e, mesh, headless, &mut w);
    if !footless {
        check_feet(e, mesh, &mut w);
    }
    let mut skipped = Vec::new();
    if headless {
        skipped.push("no head: head checks skipped (the head on the mid-plane, inside the body, the head part)".into());
    }
    match cut {
        [true, true] => skipped.push("no feet: foot checks skipped (the toes' symmetry, bones and place inside the body, the feet's direction)".into()),
        [true, false] | [false, true] => {
            let side = if cut[0] { "left" } else { "right" };
            skipped.push(format!("no {side} foot: foot checks skipped (the toes' symmetry and bones, the {side} toe's place inside the body, the feet's direction)"));
        }
        _ => {}
    }
    EmbedCheck {
        height: h,
        mid_plane: plane,
        pelvis_offset,
        pelvis_offset_percent: w.pct(pelvis_offset),
        hip_distances,
        hip_asymmetry_percent: w.pct((hip_distances[0] - hip_distances[1]).abs()),
        bones,
        outside,
        parts,
        options: *o,
        warnings: w.list,
        skipped,
    }
}

/// The warnings found so far, and the height their percentages are of.
struct Warnings {
    h: f64,
    list: Vec<Warning>,
}

impl Warnings {
    /// `d` as a percentage of the height.
    fn pct(&self, d: f64) -> f64 {
        100.0 * d / self.h
    }

    /// A warning logged and kept.
    fn warn(&mut self, problem: Problem, joint: &str, distance: f64, message: String) {
        tracing::warn!(target: crate::util::fsutil::WARNING, joint, "{message}");
        let percent_of_height = self.pct(distance);
        self.list.push(Warning {
            problem,
            joint: joint.to_string(),
            distance,
            percent_of_height,
            message,
        });
    }
}

/// A joint of `e`.
fn joint(e: &Embedding, c: Canonical) -> DVec3 {
    DVec3::from_array(e.joints[c.index()])
}

/// The mid-plane from the joints the pelvis and hips do not depend on.
fn check_plane(e: &Embedding) -> MidPlane {
    use Canonical as C;
    let j = |c: C| joint(e, c);
    let left = DVec3::from_array(e.left).normalize_or(DVec3::X);
    let mid = |a: C, b: C| (j(a) + j(b)) * 0.5;
    MidPlane::median_of(
        left,
        &[
            j(C::Spine),
            j(C::Chest),
            j(C::Neck),
            j(C::Head),
            mid(C::LKnee, C::RKnee),
            mid(C::LAnkle, C::RAnkle),
            mid(C::LShoulder, C::RShoulder),
        ],
    )
}

/// Central joints on the mid-plane.
fn check_central(
    e: &Embedding,
    plane: &MidPlane,
    o: &CheckOptions,
    headless: bool,
    w: &mut Warnings,
) {
    use Canonical as C;
    let h = w.h;
    for (c, tol) in [
        (C::Pelvis, o.pelvis_offset),
        (C::Spine, o.central_offset),
        (C::Chest, o.central_offset),
        (C::Neck, o.central_offset),
        (C::Head, o.central_offset),
    ] {
        if headless && c == C::Head {
            continue;
        }
        let d = plane.distance(joint(e, c)).abs();
        if d > tol * h {
            let message = format!(
                "{} is {d:.4} ({:.2}% of the height) off the body's mid-plane (tolerance {:.1}%)",
                c.name(),
                w.pct(d),
                100.0 * tol
            );
            w.warn(Problem::OffMidPlane, c.name(), d, message);
        }
    }
}

/// Twins at the same distance from the mid-plane, and apart; the hips'
/// distances.
fn check_twins(
    e: &Embedding,
    plane: &MidPlane,
    o: &CheckOptions,
    pairs: &[(Canonical, Canonical)],
    w: &mut Warnings,
) -> [f64; 2] {
    use Canonical as C;
    let h = w.h;
    let mut hip_distances = [0.0; 2];
    for &(l, r) in pairs {
        let (dl, dr) = (plane.distance(joint(e, l)), -plane.distance(joint(e, r)));
        if l == C::LHip {
            hip_distances = [dl, dr];
        }
        let tol = if l == C::LHip {
            o.hip_symmetry
        } else {
            o.limb_symmetry
        };
        if dl + dr < o.twin_separation * h {
            let message = format!(
                "{} and {} are only {:.4} apart across the body ({:.2}% of the height; at least {:.0}% expected): both placed between the two limbs?",
                l.name(),
                r.name(),
                dl + dr,
                w.pct(dl + dr),
                100.0 * o.twin_separation
            );
            w.warn(Problem::Merged, l.name(), dl + dr, message);
        }
        let d = (dl - dr).abs();
        if d > tol * h {
            let message = format!(
                "{} and {} are {dl:.4} and {dr:.4} from the mid-plane: {d:.4} apart ({:.2}% of the height; tolerance {:.1}%)",
                l.name(),
                r.name(),
                w.pct(d),
                100.0 * tol
            );
            w.warn(Problem::Asymmetric, l.name(), d, message);
        }
    }
    hip_distances
}

/// Twin bones of one length.
fn check_bones(
    e: &Embedding,
    o: &CheckOptions,
    pairs: &[(Canonical, Canonical)],
    w: &mut Warnings,
) -> Vec<BonePair> {
    let mut bones = Vec::new();
    for &(l, r) in pairs {
        let (Some(pl), Some(pr)) = (l.parent(), r.parent()) else {
            continue;
        };
        let (a, b) = (
            joint(e, l).distance(joint(e, pl)),
            joint(e, r).distance(joint(e, pr)),
        );
        let ratio = (a - b).abs() / a.max(b).max(1e-12);
        if ratio > o.bone_ratio {
            let message = format!(
                "the bones to {} and {} are {:.1}% and {:.1}% of the height long ({a:.4} and {b:.4} in the mesh's units; {:.1}% apart; tolerance {:.0}%)",
                l.name(),
                r.name(),
                w.pct(a),
                w.pct(b),
                100.0 * ratio,
                100.0 * o.bone_ratio
            );
            w.warn(Problem::BoneLengths, l.name(), (a - b).abs(), message);
        }
        bones.push(BonePair {
            joint: l.name().to_string(),
            left: a,
            right: b,
            ratio,
        });
    }
    bones
}

/// Joints inside the body (not the head of a headless body, nor the toe
/// of a foot `cut`, left and right); the names of those outside.
fn check_inside(
    e: &Embedding,
    mesh: &Mesh,
    headless: bool,
    cut: [bool; 2],
    w: &mut Warnings,
) -> Vec<String> {
    let (p, t) = (mesh.positions(), mesh.triangles());
    let mut outside = Vec::new();
    for c in Canonical::ALL {
        let cut_toe = c == Canonical::LToe && cut[0] || c == Canonical::RToe && cut[1];
        if headless && c == Canonical::Head || cut_toe {
            continue;
        }
        let q = joint(e, c);
        if winding_number(p, t, q).abs() > 0.5 {
            continue;
        }
        let d = distance_to_surface(p, t, q);
        outside.push(c.name().to_string());
        let message = format!(
            "{} is outside the body, {d:.4} from its surface ({:.2}% of the height)",
            c.name(),
            w.pct(d)
        );
        w.warn(Problem::Outside, c.name(), d, message);
    }
    outside
}

/// Parts: non-empty, one piece.
fn check_parts(e: &Embedding, mesh: &Mesh, headless: bool, w: &mut Warnings) -> Vec<PartCheck> {
    let (p, t) = (mesh.positions(), mesh.triangles());
    let mut parts = Vec::new();
    if e.labels.len() == p.len() {
        let pieces = piece_counts(&e.labels, &neighbours(p.len(), t));
        let mut sizes = [0usize; Part::COUNT];
        for &l in &e.labels {
            if let Some(s) = sizes.get_mut(l as usize) {
                *s += 1;
            }
        }
        for part in Part::ALL {
            let (n, k) = (sizes[part.index()], pieces[part.index()]);
            if headless && part == Part::Head {
                // No head: whatever the top of the neck holds.
            } else if n == 0 {
                w.warn(
                    Problem::EmptyPart,
                    part.name(),
                    0.0,
                    format!("part {} has no vertex", part.name()),
                );
            } else if k != 1 {
                w.warn(
                    Problem::SplitPart,
                    part.name(),
                    0.0,
                    format!("part {} is in {k} pieces", part.name()),
                );
            }
            parts.push(PartCheck {
                part: part.name().to_string(),
                vertices: n,
                pieces: k,
            });
        }
    } else {
        w.warn(
            Problem::Mismatch,
            "",
            0.0,
            format!(
                "the embedding labels {} vertices, the mesh has {}",
                e.labels.len(),
                p.len()
            ),
        );
    }
    parts
}

/// The feet point along the rig's facing: each foot's reach (the
/// vertices below its ankle, within 12 % of the height of it across and
/// nearer it than the other ankle) in front of its ankle (toes) beats its
/// reach behind (heel). Both feet reaching 1.5 times farther behind than
/// in front (pointing backwards) is a left/right swap
/// of the landmarks (facing is left × up): warned, naming the reaches.
fn check_feet(e: &Embedding, mesh: &Mesh, w: &mut Warnings) {
    let p = mesh.positions();
    let facing = DVec3::from_array(e.facing);
    let up = DVec3::from_array(e.up);
    let flat = |d: DVec3| (d - up * d.dot(up)).length();
    let ankles = [joint(e, Canonical::LAnkle), joint(e, Canonical::RAnkle)];
    let mut reach = [(0.0f64, 0.0f64); 2];
    for k in 0..2 {
        let (a, other) = (ankles[k], ankles[1 - k]);
        for q in p.iter().map(|q| DVec3::from_array(*q)) {
            let d = q - a;
            if d.dot(up) < 0.0 && flat(d) < 0.12 * w.h && flat(d) <= flat(q - other) {
                let f = d.dot(facing);
                reach[k] = (reach[k].0.max(f), reach[k].1.max(-f));
            }
        }
    }
    // 1.5: a claw or a flat foot reaches about as far behind (the
    // armadillo: 0.108 behind against 0.097 in front).
    if reach.iter().all(|&(front, back)| back > 1.5 * front) {
        let message = format!(
            "both feet point backwards along the rig's facing (toes {:.3} and {:.3} in front of the ankles, {:.3} and {:.3} behind): are the landmarks' left and right swapped?",
            reach[0].0, reach[1].0, reach[0].1, reach[1].1
        );
        let d = reach[0].1 - reach[0].0;
        w.warn(Problem::Backwards, "l_ankle", d, message);
    }
}
