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

/// The body's frame on a rest mesh: up (groin to chin), the character's
/// left (from the limb landmarks), facing, the floor and the height along
/// up.
#[derive(Clone, Copy)]
struct Body {
    up: DVec3,
    left: DVec3,
    facing: DVec3,
    floor: f64,
    h: f64,
}

impl Body {
    /// `q` moved along up to `height`.
    fn at_height(&self, q: DVec3, height: f64) -> DVec3 {
        q + self.up * (height - q.dot(self.up))
    }
}

/// The required landmarks' points (the origin for an absent one).
struct Marks {
    chin: DVec3,
    groin: DVec3,
    lw: DVec3,
    rw: DVec3,
    le: DVec3,
    re: DVec3,
    lk: DVec3,
    rk: DVec3,
}

/// A landmark's point on `positions`, if given.
fn mark(lm: &Landmarks, positions: &[[f64; 3]], l: Landmark) -> Option<DVec3> {
    lm.point(l, positions).map(DVec3::from_array)
}

/// Places every canonical joint of a rest mesh from its landmarks, in
/// named steps: the body's frame, neck and head, the mid-plane and the
/// pelvis's centre, the ankles, the limbs (twice), the trunk, the toes,
/// the hand tips. `headless`: the body has no head (`lm` completed with a
/// chin at the top of its neck, [`Landmarks::completed`]).
pub(crate) fn place_joints(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    lm: &Landmarks,
    headless: bool,
) -> JointEstimate {
    use Canonical as C;
    use Landmark as L;
    let req = |l: L| mark(lm, positions, l).unwrap_or(DVec3::ZERO);
    let m = Marks {
        chin: req(L::Chin),
        groin: req(L::Groin),
        lw: req(L::LWrist),
        rw: req(L::RWrist),
        le: req(L::LElbow),
        re: req(L::RElbow),
        lk: req(L::LKnee),
        rk: req(L::RKnee),
    };
    let b = body_frame(positions, &m);
    let mut cx = Ctx {
        p: positions,
        t: triangles,
        h: b.h,
        notes: Vec::new(),
        twin: None,
    };
    let mut j = [DVec3::ZERO; Canonical::COUNT];
    let (neck_at, head_at, head_top) = neck_and_head(&mut cx, &b, lm, m.chin, headless, &mut j);
    let (plane, _) = estimate_mid_plane(
        positions,
        triangles,
        [m.groin, m.chin, (m.lk + m.rk) * 0.5],
        b.up,
        b.left,
        b.h,
    );
    let hip_h = m.groin.dot(b.up) + 0.035 * b.h;
    let (pc, pelvis_h) = pelvis_centre(&mut cx, &plane, m.groin, b.up, hip_h);
    for (c, name, at) in [(C::Neck, "neck", neck_at), (C::Head, "head", head_at)] {
        j[c.index()] = centred(&mut cx, &plane, name, j[c.index()], at);
    }
    let ankles = place_ankles(&mut cx, &b, lm, &m);
    let limbs = place_limbs(
        &mut cx,
        &b,
        lm,
        &m,
        &plane,
        pc,
        hip_h,
        ankles,
        j[C::Neck.index()],
    );
    let Limbs {
        knees,
        arm,
        shoulders,
        hip_w,
        hip_note,
    } = limbs;
    let hip = |w: f64, s: f64| pc + b.left * (s * w);
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
    place_trunk(&mut cx, &b, &plane, hip_h, pelvis_h, &mut j);
    let toe_tips = place_toes(positions, &b, lm, ankles, &mut j);

    // The same note from both refinement passes once.
    let mut seen = std::collections::HashSet::new();
    cx.notes.retain(|n| seen.insert(n.clone()));

    let hand_tips = hand_tips(positions, triangles, &b, &arm);
    JointEstimate {
        joints: j,
        head_top,
        hand_tips,
        toe_tips,
        up: b.up,
        facing: b.facing,
        left: b.left,
        height: b.h,
        mid_plane: plane,
        notes: cx.notes,
    }
}

/// Up from the groin to the chin, left from the limb landmarks' pairs,
/// facing = left × up; the floor and height along up.
fn body_frame(positions: &[[f64; 3]], m: &Marks) -> Body {
    let up = body_up(m.chin - m.groin);
    let side = (m.lk - m.rk) + (m.le - m.re) + (m.lw - m.rw);
    let left = (side - up * side.dot(up)).normalize_or(up.any_orthonormal_vector());
    let facing = left.cross(up);
    let hs = positions.iter().map(|q| DVec3::from_array(*q).dot(up));
    let (floor, top) = hs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    let h = (top - floor).max(1e-9);
    Body {
        up,
        left,
        facing,
        floor,
        h,
    }
}

/// Neck and head: horizontal sections below and above the chin, around a
/// point behind the chin (inside the neck/head), written into `j`; the
/// points they were looked for around and the head top (a landmark, or
/// the highest vertex above the head). A `headless` body's head joint is
/// the top of its stump ([`super::stump::stump_top`]).
fn neck_and_head(
    cx: &mut Ctx,
    b: &Body,
    lm: &Landmarks,
    chin: DVec3,
    headless: bool,
    j: &mut [DVec3; Canonical::COUNT],
) -> (DVec3, DVec3, DVec3) {
    use Canonical as C;
    let (up, h) = (b.up, b.h);
    let chin_h = chin.dot(up);
    let behind = chin - b.facing * 0.04 * h;
    let stump = headless
        .then(|| super::stump::stump_top(lm, cx.p, cx.t))
        .flatten();
    // The neck 5 % of the height below the chin; a headless body's as far
    // below its stump's top ring, which lies between the neck joint and
    // the chin, unless the measurement override says otherwise
    // ([`super::stump::neck_below_top`]), even when its head is on the
    // cut's rim ([`super::stump::StumpTop::ring`]).
    let neck_at = match stump {
        Some(s) => s.ring - up * (super::stump::neck_below_top() * h),
        None => b.at_height(behind, chin_h - 0.05 * h),
    };
    j[C::Neck.index()] = cx.centre("neck", neck_at, up, neck_at, 0.08, neck_at);
    // A body without a head: its head joint at the top of the stump (the
    // cut's centroid; it was sought 3 % of the height above the chin, over
    // the stump, where no surface is).
    let head_at = match stump {
        Some(s) => s.centre,
        None => b.at_height(behind, chin_h + 0.03 * h),
    };
    j[C::Head.index()] = match stump {
        Some(_) => head_at,
        None => cx.centre("head", head_at, up, head_at, 0.1, head_at),
    };
    let head_top = mark(lm, cx.p, Landmark::HeadTop).unwrap_or_else(|| {
        let hc = j[C::Head.index()];
        cx.p.iter()
            .map(|q| DVec3::from_array(*q))
            .filter(|q| {
                let d = *q - hc;
                (d - up * d.dot(up)).length() < 0.12 * h
            })
            .max_by(|a, b| a.dot(up).total_cmp(&b.dot(up)))
            .unwrap_or(hc + up * 0.1 * h)
    });
    (neck_at, head_at, head_top)
}

/// Ankles: from a landmark, or a section just above the floor under the
/// knee.
fn place_ankles(cx: &mut Ctx, b: &Body, lm: &Landmarks, m: &Marks) -> [DVec3; 2] {
    use Landmark as L;
    let p = cx.p;
    let get = |l: L| mark(lm, p, l);
    let ankle_h = b.floor + 0.055 * b.h;
    let mut ankles = [DVec3::ZERO; 2];
    for (k, (lmk, knee, name)) in [(L::LAnkle, m.lk, "l_ankle"), (L::RAnkle, m.rk, "r_ankle")]
        .into_iter()
        .enumerate()
    {
        let at = get(lmk).unwrap_or_else(|| b.at_height(knee, ankle_h));
        let axis = (knee - at).normalize_or(b.up);
        let near = b.at_height(knee, at.dot(b.up));
        let other = [m.rk, m.lk][k];
        let twin = get([L::RAnkle, L::LAnkle][k]).unwrap_or_else(|| b.at_height(other, ankle_h));
        cx.twin = Some(twin);
        ankles[k] = cx.centre(name, at, axis, near, 0.06, at);
    }
    ankles
}

/// The limbs' joints after [`place_limbs`]'s two passes.
struct Limbs {
    knees: [DVec3; 2],
    /// Left and right (elbow, wrist).
    arm: [[DVec3; 2]; 2],
    shoulders: [DVec3; 2],
    /// The hips' half width about the mid-plane.
    hip_w: f64,
    hip_note: Option<String>,
}

/// Knees, then the hips' width, then elbows, wrists and shoulders, twice:
/// each pass refines the limb axes.
#[allow(clippy::too_many_arguments)]
fn place_limbs(
    cx: &mut Ctx,
    b: &Body,
    lm: &Landmarks,
    m: &Marks,
    plane: &MidPlane,
    pc: DVec3,
    hip_h: f64,
    ankles: [DVec3; 2],
    neck: DVec3,
) -> Limbs {
    use Landmark as L;
    let (up, left, facing, h) = (b.up, b.left, b.facing, b.h);
    let (lk, rk) = (m.lk, m.rk);
    let mut hip_w = 0.055 * h;
    let hip = |w: f64, s: f64| pc + left * (s * w);
    let mut knees = [lk, rk];
    let mut arm = [[m.le, m.lw], [m.re, m.rw]];
    let mut shoulders = [DVec3::ZERO; 2];
    let mut hip_note = None;
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
            cx,
            plane,
            [hip(hip_w, 1.0), hip(hip_w, -1.0)],
            knees,
            up,
            hip_h,
        );
        hip_w = w;
        hip_note = note;
        for (k, (e_lm, w_lm, s, names)) in [
            (m.le, m.lw, 1.0, ["l_elbow", "l_wrist", "l_shoulder"]),
            (m.re, m.rw, -1.0, ["r_elbow", "r_wrist", "r_shoulder"]),
        ]
        .into_iter()
        .enumerate()
        {
            let sh_lm = mark(lm, cx.p, if s > 0.0 { L::LShoulder } else { L::RShoulder });
            let guess = sh_lm
                .map(|q| q - facing * (q - neck).dot(facing))
                .unwrap_or_else(|| neck + left * (s * 0.095 * h) - up * 0.01 * h);
            let w = cx.centre(names[1], w_lm, w_lm - e_lm, w_lm, 0.06, w_lm);
            let e_axis = (w - guess).normalize_or(-up);
            let e = cx.centre(names[0], e_lm, e_axis, e_lm, 0.07, on_line(e_lm, guess, w));
            // The upper arm's axis from a section a quarter of the way down it.
            let q = guess.lerp(e, 0.3);
            let len = guess.distance(e);
            shoulders[k] = match part_loop(cx.p, cx.t, q, e - guess, q) {
                Some(l) if l.radius < 0.06 * h && len > 0.0 => {
                    e + (l.centroid - e).normalize_or(guess - e) * len
                }
                _ => guess,
            };
            arm[k] = [e, w];
        }
    }
    Limbs {
        knees,
        arm,
        shoulders,
        hip_w,
        hip_note,
    }
}

/// Pelvis, spine and chest into `j` (the hips and neck placed): the pelvis
/// between the hips, a little above them, and inside the torso when the
/// crotch is above hip height; spine and chest on the pelvis-neck line,
/// centred on sections.
fn place_trunk(
    cx: &mut Ctx,
    b: &Body,
    plane: &MidPlane,
    hip_h: f64,
    pelvis_h: f64,
    j: &mut [DVec3; Canonical::COUNT],
) {
    use Canonical as C;
    let neck = j[C::Neck.index()];
    let mid_hips = (j[C::LHip.index()] + j[C::RHip.index()]) * 0.5;
    let pelvis = b.at_height(mid_hips, (hip_h + 0.02 * b.h).max(pelvis_h + 0.01 * b.h));
    j[C::Pelvis.index()] = pelvis;
    for (c, f, name) in [(C::Spine, 0.33, "spine"), (C::Chest, 0.66, "chest")] {
        let at = pelvis.lerp(neck, f);
        let q = cx.centre(name, at, b.up, at, 0.2, at);
        j[c.index()] = centred(cx, plane, name, q, at);
    }
}

/// Toes (into `j`) and toe tips: the front of each foot (vertices below the ankle,
/// near it and nearer to it than to the other ankle: with the feet
/// closer than the search radius, both feet would average to a point
/// between them), from a landmark when given.
fn place_toes(
    positions: &[[f64; 3]],
    b: &Body,
    lm: &Landmarks,
    ankles: [DVec3; 2],
    j: &mut [DVec3; Canonical::COUNT],
) -> [DVec3; 2] {
    use Canonical as C;
    use Landmark as L;
    let (up, facing, floor, h) = (b.up, b.facing, b.floor, b.h);
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
            .unwrap_or(b.at_height(a + facing * 0.12 * h, floor));
        toe_tips[k] = tip;
        let toe = match mark(lm, positions, lmk) {
            Some(q) => b.at_height(q, (q.dot(up) + floor) * 0.5),
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
                    b.at_height(a.lerp(tip, 0.72), floor + 0.02 * h)
                } else {
                    band.iter().copied().sum::<DVec3>() / band.len() as f64
                }
            }
        };
        j[c.index()] = toe;
    }
    toe_tips
}

/// Hand tips: each hand's vertex farthest beyond its wrist along the
/// forearm. The candidates lie beyond the wrist's plane and within 15 %
/// of the height of the wrist, and only those joined to the wrist by mesh
/// edges between candidates count (from the candidate nearest the
/// wrist's centre): the hip and the skirt beside a hanging hand lie
/// beyond the plane too, but are not joined to the hand there. Taking
/// them (samba with the automatic rig's wrists: the left hand's tip on
/// the skirt, 16 cm from the fingers) ran the hand's bone into the hip,
/// bone heat gave ~1,400 skirt, thigh and torso vertices to the hand, and
/// a retargeted CMU 02_02 sank 16 cm into the floor.
fn hand_tips(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    b: &Body,
    arm: &[[DVec3; 2]; 2],
) -> [DVec3; 2] {
    let mut hand_tips = [DVec3::ZERO; 2];
    for (k, [e, w]) in arm.iter().enumerate() {
        let a = (*w - *e).normalize_or(-b.up);
        let beyond = |q: DVec3| (q - *w).dot(a) > 0.0 && q.distance(*w) < 0.15 * b.h;
        let hand = joined_to_nearest(positions, triangles, *w, beyond);
        hand_tips[k] = hand
            .into_iter()
            .map(|v| DVec3::from_array(positions[v]))
            .max_by(|x, y| (*x - *w).dot(a).total_cmp(&(*y - *w).dot(a)))
            .unwrap_or(*w + a * 0.08 * b.h);
    }
    hand_tips
}

/// The vertices that satisfy `keep` and are joined by mesh edges between
/// such vertices to the one of them nearest `to`, in index order (none
/// when no vertex does).
fn joined_to_nearest(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    to: DVec3,
    keep: impl Fn(DVec3) -> bool,
) -> Vec<usize> {
    let kept: Vec<bool> = positions
        .iter()
        .map(|q| keep(DVec3::from_array(*q)))
        .collect();
    let Some(seed) = (0..positions.len()).filter(|&v| kept[v]).min_by(|&x, &y| {
        let d = |v: usize| DVec3::from_array(positions[v]).distance_squared(to);
        d(x).total_cmp(&d(y))
    }) else {
        return Vec::new();
    };
    let mut nb: Vec<Vec<usize>> = vec![Vec::new(); positions.len()];
    for t in triangles {
        for i in 0..3 {
            let (x, y) = (t[i] as usize, t[(i + 1) % 3] as usize);
            if x < kept.len() && y < kept.len() && kept[x] && kept[y] {
                nb[x].push(y);
                nb[y].push(x);
            }
        }
    }
    let mut seen = vec![false; positions.len()];
    seen[seed] = true;
    let mut stack = vec![seed];
    let mut out = Vec::new();
    while let Some(v) = stack.pop() {
        out.push(v);
        for &u in &nb[v] {
            if !seen[u] {
                seen[u] = true;
                stack.push(u);
            }
        }
    }
    out.sort_unstable();
    out
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
