//! Canonical joint positions inside a rest mesh, from landmarks.
//!
//! Limb joints (wrists, elbows, knees, ankles) are the centres of the limb's
//! cross-section through the landmark, perpendicular to the limb; torso and
//! head joints are centres of horizontal sections at heights set from the
//! chin, groin and floor. Where a section is not limb-like (a skirt over a
//! knee, an arm touching the torso) the joint falls back to the landmark
//! projected onto the line between its neighbours, and a note says so.
//! Proportions used where the surface says nothing (hip height above the
//! groin, ankle height above the floor, shoulder width) are standard
//! anthropometric ratios of the body height `H`.
//!
//! The pelvis lies on the body's mid-plane ([`super::midplane`]) and the
//! hips are symmetric about it: each hip is where its thigh's axis (the
//! centre of a cross-section of the upper thigh, through the knee centre)
//! reaches hip height, and the two distances from the plane are averaged.
//! The pelvis is never the centre of whatever one horizontal section finds
//! (below a high crotch that is one thigh, 5-6 % of the height to the side).

use super::axes::body_up;
use super::landmarks::{Landmark, Landmarks};
use super::midplane::{MidPlane, estimate_mid_plane};
use super::section::{cross_section, encloses, part_loop};
use crate::rig::Canonical;
use glam::DVec3;

/// Joint positions and the body frame they were found in.
#[derive(Debug, Clone)]
pub struct JointEstimate {
    /// Position of each canonical joint, indexed by [`Canonical::index`].
    pub joints: [DVec3; Canonical::COUNT],
    /// Ends of the end segments: head top, left and right hand tips, left
    /// and right toe tips.
    pub head_top: DVec3,
    /// Left, right hand tips.
    pub hand_tips: [DVec3; 2],
    /// Left, right toe tips.
    pub toe_tips: [DVec3; 2],
    /// Unit up (groin to chin).
    pub up: DVec3,
    /// Unit facing direction.
    pub facing: DVec3,
    /// Character's left.
    pub left: DVec3,
    /// Height of the mesh along `up`.
    pub height: f64,
    /// The body's mid-plane the pelvis was placed on.
    pub mid_plane: MidPlane,
    /// What was assumed, per joint.
    pub notes: Vec<String>,
}

struct Ctx<'a> {
    p: &'a [[f64; 3]],
    t: &'a [[u32; 3]],
    h: f64,
    notes: Vec<String>,
    /// The twin limb's point for the next [`Ctx::centre`] (taken by it): a
    /// loop that encloses it is both limbs joined (legs together), not
    /// this one.
    twin: Option<DVec3>,
}

impl Ctx<'_> {
    /// The centre of the section through `at` perpendicular to `axis` when
    /// its loop is narrower than `max_r` (and does not enclose the twin
    /// point set in `self.twin`), else `fallback`.
    fn centre(
        &mut self,
        name: &str,
        at: DVec3,
        axis: DVec3,
        near: DVec3,
        max_r: f64,
        fallback: DVec3,
    ) -> DVec3 {
        let twin = self.twin.take();
        match part_loop(self.p, self.t, at, axis, near) {
            Some(l) if twin.is_some_and(|q| encloses(&l, q, axis)) => {
                self.notes.push(format!(
                    "{name}: the section holds both limbs (joined); placed from the landmarks"
                ));
                fallback
            }
            Some(l) if l.radius <= max_r * self.h => l.centroid,
            Some(l) => {
                self.notes.push(format!(
                    "{name}: the section is {:.0}% of the height across (not limb-like: clothing?); placed from the landmarks",
                    200.0 * l.radius / self.h
                ));
                fallback
            }
            None => {
                self.notes.push(format!(
                    "{name}: no section found; placed from the landmarks"
                ));
                fallback
            }
        }
    }
}

/// The point of the line through `a` and `b` nearest to `p`.
fn on_line(p: DVec3, a: DVec3, b: DVec3) -> DVec3 {
    let d = b - a;
    if d.length_squared() == 0.0 {
        return a;
    }
    a + d * ((p - a).dot(d) / d.length_squared())
}

/// Places every canonical joint of a rest mesh from its landmarks.
pub fn place_joints(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    lm: &Landmarks,
) -> JointEstimate {
    use Canonical as C;
    use Landmark as L;
    let get = |l: L| lm.point(l, positions).map(DVec3::from_array);
    let req = |l: L| get(l).unwrap_or(DVec3::ZERO);
    let (chin, groin) = (req(L::Chin), req(L::Groin));
    let (lw, rw, le, re, lk, rk) = (
        req(L::LWrist),
        req(L::RWrist),
        req(L::LElbow),
        req(L::RElbow),
        req(L::LKnee),
        req(L::RKnee),
    );
    let up = body_up(chin - groin);
    let side = (lk - rk) + (le - re) + (lw - rw);
    let left = (side - up * side.dot(up)).normalize_or(up.any_orthonormal_vector());
    let facing = left.cross(up);
    let hs = positions.iter().map(|q| DVec3::from_array(*q).dot(up));
    let (floor, top) = hs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    let h = (top - floor).max(1e-9);
    let mut cx = Ctx {
        p: positions,
        t: triangles,
        h,
        notes: Vec::new(),
        twin: None,
    };
    let at_height = |q: DVec3, height: f64| q + up * (height - q.dot(up));
    let mut j = [DVec3::ZERO; Canonical::COUNT];

    // Neck and head: horizontal sections below and above the chin, around a
    // point behind the chin (inside the neck/head).
    let chin_h = chin.dot(up);
    let behind = chin - facing * 0.04 * h;
    let neck_at = at_height(behind, chin_h - 0.05 * h);
    j[C::Neck.index()] = cx.centre("neck", neck_at, up, neck_at, 0.08, neck_at);
    let head_at = at_height(behind, chin_h + 0.03 * h);
    j[C::Head.index()] = cx.centre("head", head_at, up, head_at, 0.1, head_at);
    let head_top = get(L::HeadTop).unwrap_or_else(|| {
        let hc = j[C::Head.index()];
        positions
            .iter()
            .map(|q| DVec3::from_array(*q))
            .filter(|q| {
                let d = *q - hc;
                (d - up * d.dot(up)).length() < 0.12 * h
            })
            .max_by(|a, b| a.dot(up).total_cmp(&b.dot(up)))
            .unwrap_or(hc + up * 0.1 * h)
    });

    // Pelvis and hips: on and about the mid-plane, at a height a little
    // above the groin; the pelvis's depth from the torso's section there.
    let (plane, _) = estimate_mid_plane(
        positions,
        triangles,
        [groin, chin, (lk + rk) * 0.5],
        up,
        left,
        h,
    );
    let hip_h = groin.dot(up) + 0.035 * h;
    let (pc, pelvis_h) = pelvis_centre(&mut cx, &plane, groin, up, hip_h);
    for (c, name, at) in [(C::Neck, "neck", neck_at), (C::Head, "head", head_at)] {
        j[c.index()] = centred(&mut cx, &plane, name, j[c.index()], at);
    }
    let mut hip_w = 0.055 * h;
    let hip = |w: f64, s: f64| pc + left * (s * w);

    // Ankles: from a landmark, or a section just above the floor under the knee.
    let ankle_h = floor + 0.055 * h;
    let mut ankles = [DVec3::ZERO; 2];
    for (k, (lmk, knee, name)) in [(L::LAnkle, lk, "l_ankle"), (L::RAnkle, rk, "r_ankle")]
        .into_iter()
        .enumerate()
    {
        let at = get(lmk).unwrap_or_else(|| at_height(knee, ankle_h));
        let axis = (knee - at).normalize_or(up);
        let near = at_height(knee, at.dot(up));
        let other = [rk, lk][k];
        cx.twin = Some(get([L::RAnkle, L::LAnkle][k]).unwrap_or_else(|| at_height(other, ankle_h)));
        ankles[k] = cx.centre(name, at, axis, near, 0.06, at);
    }
    // Knees, then elbows and wrists, twice: each pass refines the limb axes.
    let mut knees = [lk, rk];
    let mut arm = [[le, lw], [re, rw]];
    let mut shoulders = [DVec3::ZERO; 2];
    let mut hip_note = None;
    let neck = j[C::Neck.index()];
    for _ in 0..2 {
        for (k, (lmk, s, name)) in [(lk, 1.0, "l_knee"), (rk, -1.0, "r_knee")]
            .into_iter()
            .enumerate()
        {
            let hp = hip(hip_w, s);
            let axis = (ankles[k] - hp).normalize_or(-up);
            let fb = on_line(lmk, hp, ankles[k]);
            cx.twin = Some([rk, lk][k]);
            knees[k] = cx.centre(name, lmk, axis, lmk, 0.07, fb);
        }
        let (w, note) = hip_half_width(
            &cx,
            &plane,
            [hip(hip_w, 1.0), hip(hip_w, -1.0)],
            knees,
            up,
            hip_h,
        );
        hip_w = w;
        hip_note = note;
        for (k, (e_lm, w_lm, s, names)) in [
            (le, lw, 1.0, ["l_elbow", "l_wrist", "l_shoulder"]),
            (re, rw, -1.0, ["r_elbow", "r_wrist", "r_shoulder"]),
        ]
        .into_iter()
        .enumerate()
        {
            let sh_lm = get(if s > 0.0 { L::LShoulder } else { L::RShoulder });
            let guess = sh_lm
                .map(|q| q - facing * (q - neck).dot(facing))
                .unwrap_or_else(|| neck + left * (s * 0.095 * h) - up * 0.01 * h);
            let w = cx.centre(names[1], w_lm, w_lm - e_lm, w_lm, 0.06, w_lm);
            let e_axis = (w - guess).normalize_or(-up);
            let e = cx.centre(names[0], e_lm, e_axis, e_lm, 0.07, on_line(e_lm, guess, w));
            // The upper arm's axis from a section a quarter of the way down it.
            let q = guess.lerp(e, 0.3);
            let len = guess.distance(e);
            shoulders[k] = match part_loop(positions, triangles, q, e - guess, q) {
                Some(l) if l.radius < 0.06 * h && len > 0.0 => {
                    e + (l.centroid - e).normalize_or(guess - e) * len
                }
                _ => guess,
            };
            arm[k] = [e, w];
        }
    }
    cx.notes.extend(hip_note);
    j[C::LShoulder.index()] = shoulders[0];
    j[C::RShoulder.index()] = shoulders[1];
    j[C::LElbow.index()] = arm[0][0];
    j[C::LWrist.index()] = arm[0][1];
    j[C::RElbow.index()] = arm[1][0];
    j[C::RWrist.index()] = arm[1][1];
    j[C::LHip.index()] = hip(hip_w, 1.0);
    j[C::RHip.index()] = hip(hip_w, -1.0);
    j[C::LKnee.index()] = knees[0];
    j[C::RKnee.index()] = knees[1];
    j[C::LAnkle.index()] = ankles[0];
    j[C::RAnkle.index()] = ankles[1];
    // Between the hips, a little above them, and inside the torso when the
    // crotch is above hip height.
    let mid_hips = (j[C::LHip.index()] + j[C::RHip.index()]) * 0.5;
    let pelvis = at_height(mid_hips, (hip_h + 0.02 * h).max(pelvis_h + 0.01 * h));
    j[C::Pelvis.index()] = pelvis;
    for (c, f, name) in [(C::Spine, 0.33, "spine"), (C::Chest, 0.66, "chest")] {
        let at = pelvis.lerp(neck, f);
        let q = cx.centre(name, at, up, at, 0.2, at);
        j[c.index()] = centred(&mut cx, &plane, name, q, at);
    }

    // Toes and toe tips: the front of each foot (vertices below the ankle,
    // near it and nearer to it than to the other ankle: with the feet
    // closer than the search radius, both feet would average to a point
    // between them), from a landmark when given.
    let mut toe_tips = [DVec3::ZERO; 2];
    for (k, (c, lmk)) in [(C::LToe, L::LToe), (C::RToe, L::RToe)]
        .into_iter()
        .enumerate()
    {
        let a = ankles[k];
        let other = ankles[1 - k];
        let flat = |d: DVec3| (d - up * d.dot(up)).length();
        let foot: Vec<DVec3> = positions
            .iter()
            .map(|q| DVec3::from_array(*q))
            .filter(|q| {
                let d = *q - a;
                d.dot(up) < 0.0 && flat(d) < 0.12 * h && flat(d) <= flat(*q - other)
            })
            .collect();
        let tip = foot
            .iter()
            .copied()
            .max_by(|x, y| x.dot(facing).total_cmp(&y.dot(facing)))
            .unwrap_or(at_height(a + facing * 0.12 * h, floor));
        toe_tips[k] = tip;
        let toe = match get(lmk) {
            Some(q) => at_height(q, (q.dot(up) + floor) * 0.5),
            None => {
                let (fa, ft) = (a.dot(facing), tip.dot(facing));
                let band: Vec<DVec3> = foot
                    .iter()
                    .copied()
                    .filter(|q| {
                        let f = (q.dot(facing) - fa) / (ft - fa).max(1e-12);
                        (0.65..=0.8).contains(&f)
                    })
                    .collect();
                if band.is_empty() {
                    at_height(a.lerp(tip, 0.72), floor + 0.02 * h)
                } else {
                    band.iter().copied().sum::<DVec3>() / band.len() as f64
                }
            }
        };
        j[c.index()] = toe;
    }

    // The same note from both refinement passes once.
    let mut seen = std::collections::HashSet::new();
    cx.notes.retain(|n| seen.insert(n.clone()));

    // Hand tips: the farthest arm vertex beyond each wrist.
    let mut hand_tips = [DVec3::ZERO; 2];
    for (k, [e, w]) in arm.iter().enumerate() {
        let a = (*w - *e).normalize_or(-up);
        hand_tips[k] = positions
            .iter()
            .map(|q| DVec3::from_array(*q))
            .filter(|q| (*q - *w).dot(a) > 0.0 && q.distance(*w) < 0.15 * h)
            .max_by(|x, y| (*x - *w).dot(a).total_cmp(&(*y - *w).dot(a)))
            .unwrap_or(*w + a * 0.08 * h);
    }
    JointEstimate {
        joints: j,
        head_top,
        hand_tips,
        toe_tips,
        up,
        facing,
        left,
        height: h,
        mid_plane: plane,
        notes: cx.notes,
    }
}

/// A central joint (spine, chest, neck, head) from its section centre `q`
/// found around `at` (the point the landmarks give): kept when within 2 %
/// of the height of the mid-plane, or when `at` is itself off the plane
/// (the landmarks put it there: a turned head, a body not in a rest pose);
/// else moved onto the plane with a note (a lopsided section: a shoulder or
/// an arm joined to it on one side). A rest pose holds these joints on the
/// mid-plane.
fn centred(cx: &mut Ctx, plane: &MidPlane, name: &str, q: DVec3, at: DVec3) -> DVec3 {
    let d = plane.distance(q);
    if d.abs() <= 0.02 * cx.h || plane.distance(at).abs() > 0.02 * cx.h {
        return q;
    }
    cx.notes.push(format!(
        "{name}: the section's centre is {:.1}% of the height off the mid-plane (lopsided: a shoulder or an arm joined to it?); centred on the plane",
        100.0 * d.abs() / cx.h
    ));
    plane.project(q)
}

/// The pelvis centre at height `hip_h` on the mid-plane, and the height of
/// the section it was found in. Its depth (front to back) is the centroid
/// of the horizontal section loop that encloses the mid-plane point above
/// the groin; where the section there is two thighs apart (the crotch is
/// higher), the first enclosing section up to 12 % of the height higher.
fn pelvis_centre(
    cx: &mut Ctx,
    plane: &MidPlane,
    groin: DVec3,
    up: DVec3,
    hip_h: f64,
) -> (DVec3, f64) {
    let h = cx.h;
    let at_height = |q: DVec3, height: f64| q + up * (height - q.dot(up));
    for k in 0..=12 {
        let height = hip_h + k as f64 * 0.01 * h;
        let at = plane.project(at_height(groin, height));
        let found = cross_section(cx.p, cx.t, at, up)
            .into_iter()
            .filter(|l| l.points.len() >= 3 && encloses(l, at, up))
            .min_by(|a, b| a.length.total_cmp(&b.length));
        let Some(l) = found else { continue };
        if k > 0 {
            cx.notes.push(format!(
                "pelvis: at hip height the section is the two thighs apart (the crotch is higher); its depth from the section {:.1}% of the height higher",
                k as f64
            ));
        }
        if l.radius > 0.2 * h {
            cx.notes.push(format!(
                "pelvis: the section is {:.0}% of the height across (not limb-like: clothing?); placed from the landmarks",
                200.0 * l.radius / h
            ));
            return (plane.project(at_height(groin, hip_h)), height);
        }
        return (plane.project(at_height(l.centroid, hip_h)), height);
    }
    cx.notes.push(
        "pelvis: no section encloses the mid-plane above the groin; placed from the landmarks"
            .into(),
    );
    (plane.project(at_height(groin, hip_h)), hip_h)
}

/// The hips' common distance from the mid-plane. For each leg, the axis of
/// its thigh (the centre of a section perpendicular to the thigh, 35 % of
/// the way from the current hip `hips[k]` to the knee centre, and the knee
/// centre) is followed up to hip height `hip_h`; the two distances are
/// averaged (a single one used for both when only one thigh is limb-like,
/// half the knees' separation when neither is, as under a skirt), within
/// plausible proportions (3-8 % of the height). Also a note when the two
/// thighs disagree by more than 1 % of the height.
fn hip_half_width(
    cx: &Ctx,
    plane: &MidPlane,
    hips: [DVec3; 2],
    knees: [DVec3; 2],
    up: DVec3,
    hip_h: f64,
) -> (f64, Option<String>) {
    let h = cx.h;
    let mut d = Vec::with_capacity(2);
    for (k, s) in [(0, 1.0), (1, -1.0)] {
        let q = hips[k].lerp(knees[k], 0.35);
        let Some(l) = part_loop(cx.p, cx.t, q, knees[k] - hips[k], q) else {
            continue;
        };
        let dir = l.centroid - knees[k];
        let rise = dir.dot(up);
        if l.radius > 0.07 * h || rise < 0.05 * h {
            continue;
        }
        let x = knees[k] + dir * ((hip_h - knees[k].dot(up)) / rise);
        d.push(s * plane.distance(x));
    }
    let mut note = None;
    let w = match d.as_slice() {
        [a, b] => {
            if (a - b).abs() > 0.01 * h {
                note = Some(format!(
                    "hips: the thighs' axes reach hip height {:.1}% and {:.1}% of the height from the mid-plane; placed symmetrically",
                    100.0 * a / h,
                    100.0 * b / h
                ));
            }
            0.5 * (a + b)
        }
        [a] => *a,
        _ => 0.5 * (plane.distance(knees[0]) - plane.distance(knees[1])),
    };
    (w.clamp(0.03 * h, 0.08 * h), note)
}
