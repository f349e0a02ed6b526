//! The reference's torso taken from the motion where a frame of the clip
//! stands in for its rest (issue 44).
//!
//! A clip whose rest skeleton does not stand upright (a conversion onto a
//! rig with bone-local bind frames, CMU 02_03 on the Reallusion CC rig)
//! is measured from its most neutral frame, and that frame's posture is
//! the file's choice of instant, not the performance's: CMU 02_03's CC
//! BVH's frame 34 has the hips turned 8.2° against the shoulders and the
//! trunk leaning with the stride, and every torso rotation measured from
//! it carried that into every frame. The torso's reference is instead the
//! clip's mean carriage: each torso joint where the clip holds it on
//! average relative to its pelvis in the body's heading frame, and the
//! file joints' mean rotations in that frame. The same performance in
//! two files has the same mean carriage whichever frame either file's
//! reference is (a mean over the clip, not one instant). The limbs keep
//! the frame's (they take the clip's directions; the reference's legs
//! only give their length and the feet's stance).

use super::reference::{ClipNeutral, ClipNeutralSource, JointRotations};
use crate::pose::Pose;
use crate::rig::Canonical;
use glam::{DQuat, DVec3, DVec4};

use Canonical as C;

/// The environment variable that chooses the torso's reference of a clip
/// whose rest skeleton stands upright (a measurement option, issue 44):
/// `rest` (the default: the rest skeleton, the clip's own calibration
/// pose) or `carriage` (the clip's mean carriage, as for a clip whose
/// reference is a frame: both files of one performance then measure the
/// torso from the same carriage). Another value warns and is the default.
pub const REFERENCE_ENV: &str = "SURFMOTION_REFERENCE";

/// Whether an upright rest skeleton's torso is replaced by the clip's
/// mean carriage ([`REFERENCE_ENV`], read once per process; a value that
/// is not a rule warns and is the default).
pub(super) fn carriage_for_rest() -> bool {
    static ON: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *ON.get_or_init(|| {
        let v = std::env::var(REFERENCE_ENV).ok();
        reference_rule(v.as_deref()).unwrap_or_else(|why| {
            tracing::warn!("{REFERENCE_ENV}: {why}; the rest skeleton is used");
            false
        })
    })
}

/// [`REFERENCE_ENV`]'s value read: `Ok(true)` for `carriage`, `Ok(false)`
/// for none, empty or `rest`; `Err` naming any other value.
fn reference_rule(value: Option<&str>) -> Result<bool, String> {
    match value.map(str::trim) {
        None | Some("" | "rest") => Ok(false),
        Some("carriage") => Ok(true),
        Some(other) => Err(format!("'{other}' is not 'rest' or 'carriage'")),
    }
}

/// The torso's reference of the kernel: a frame reference `r` (a frame
/// of `mocap`, levelled by `tilt`) takes the clip's mean carriage
/// ([`torso_from_motion`]); an upright rest skeleton keeps its own (and
/// the identity as its file rotations, `None`) unless `carriage_rest`.
pub(super) fn torso_reference(
    r: &Pose,
    mocap: &[Pose],
    reference: &ClipNeutral,
    tilt: DQuat,
    carriage_rest: bool,
) -> (Pose, Option<JointRotations>) {
    match reference.source {
        ClipNeutralSource::Rest if !carriage_rest => (*r, None),
        _ => torso_from_motion(r, mocap, &reference.rotations, tilt),
    }
}

/// The turn about the vertical taking `p`'s heading (the hips' and the
/// shoulders' left-right lines, summed, seen from above) onto +X;
/// `None` when the heading has no horizontal length.
pub(super) fn to_heading(p: &Pose) -> Option<DQuat> {
    let v = (p[C::LHip.index()] - p[C::RHip.index()])
        + (p[C::LShoulder.index()] - p[C::RShoulder.index()]);
    let v = DVec3::new(v.x, 0.0, v.z);
    (v.length() > 1e-12 && v.is_finite()).then(|| DQuat::from_rotation_y(v.z.atan2(v.x)))
}

/// The joints carried with each torso joint when the reference's torso
/// is replaced: a hip carries its leg, a shoulder its arm.
fn carried(c: C) -> &'static [C] {
    match c {
        C::LHip => &[C::LKnee, C::LAnkle, C::LToe],
        C::RHip => &[C::RKnee, C::RAnkle, C::RToe],
        C::LShoulder => &[C::LElbow, C::LWrist],
        C::RShoulder => &[C::RElbow, C::RWrist],
        _ => &[],
    }
}

/// The torso joints whose place relative to the pelvis is taken from the
/// motion.
const TORSO_PLACES: [C; 8] = [
    C::Spine,
    C::Chest,
    C::Neck,
    C::Head,
    C::LShoulder,
    C::RShoulder,
    C::LHip,
    C::RHip,
];

/// The reference `r` (a frame of `mocap`, levelled as it is) with its
/// torso from the clip's mean carriage ([`torso_places_from_motion`]),
/// and the file joints' rotations matching it
/// ([`file_rotations_from_motion`], `file` the clip's own per frame,
/// `tilt` the levelling; `None` when `file` does not hold one per frame).
pub(super) fn torso_from_motion(
    r: &Pose,
    mocap: &[Pose],
    file: &[JointRotations],
    tilt: DQuat,
) -> (Pose, Option<JointRotations>) {
    let pose = torso_places_from_motion(r, mocap);
    let at = match to_heading(&pose) {
        Some(q) if file.len() == mocap.len() => {
            Some(file_rotations_from_motion(q, mocap, file, tilt))
        }
        _ => None,
    };
    (pose, at)
}

/// `r` with its torso joints (spine, chest, neck, head, hips, shoulders;
/// a hip's leg and a shoulder's arm moved with it) where the clip holds
/// them on average relative to its pelvis, in the body's heading frame
/// (the mean over the frames of `mocap`, turned into `r`'s heading). `r`
/// unchanged when its heading or no frame's is defined.
pub(super) fn torso_places_from_motion(r: &Pose, mocap: &[Pose]) -> Pose {
    let p = C::Pelvis.index();
    let Some(qr) = to_heading(r) else {
        return *r;
    };
    let mut sum = [DVec3::ZERO; Canonical::COUNT];
    let mut n = 0usize;
    for m in mocap {
        let Some(q) = to_heading(m) else { continue };
        if !m.iter().all(|x| x.is_finite()) {
            continue;
        }
        for c in TORSO_PLACES {
            sum[c.index()] += q * (m[c.index()] - m[p]);
        }
        n += 1;
    }
    if n == 0 {
        return *r;
    }
    let mut out = *r;
    for c in TORSO_PLACES {
        let j = c.index();
        out[j] = r[p] + qr.inverse() * (sum[j] / n as f64);
        for k in carried(c) {
            out[k.index()] = r[k.index()] + (out[j] - r[j]);
        }
    }
    out
}

/// The mean of the file joints' world rotations over the frames (each
/// turned into its frame's heading, sign-aligned, normalised), turned
/// into the heading `qr`: the reference's file rotations matching
/// [`torso_places_from_motion`]. A joint no frame knows stays `None`.
pub(super) fn file_rotations_from_motion(
    qr: DQuat,
    mocap: &[Pose],
    file: &[JointRotations],
    tilt: DQuat,
) -> JointRotations {
    let mut out: JointRotations = [None; Canonical::COUNT];
    for (j, slot) in out.iter_mut().enumerate() {
        let mut sum = DVec4::ZERO;
        let mut first: Option<DVec4> = None;
        for (m, w) in mocap.iter().zip(file) {
            let (Some(q), Some(wj)) = (to_heading(m), w[j]) else {
                continue;
            };
            let v = DVec4::from(q * tilt * wj);
            if !v.is_finite() {
                continue;
            }
            let f = *first.get_or_insert(v);
            sum += if v.dot(f) < 0.0 { -v } else { v };
        }
        if sum.length_squared() > 1e-24 {
            *slot = Some((qr.inverse() * DQuat::from_vec4(sum).normalize()).normalize());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A person standing square (metres, Y up, facing +z, left at +x),
    /// the shoulders turned `twist` radians against the hips.
    fn standing(twist: f64) -> Pose {
        let mut p = [DVec3::ZERO; Canonical::COUNT];
        let mut set = |c: C, x: f64, y: f64, z: f64| p[c.index()] = DVec3::new(x, y, z);
        set(C::Pelvis, 0.0, 1.0, 0.0);
        set(C::Spine, 0.0, 1.15, 0.01);
        set(C::Chest, 0.0, 1.35, 0.0);
        set(C::Neck, 0.0, 1.5, 0.02);
        set(C::Head, 0.0, 1.6, 0.04);
        set(C::LShoulder, 0.18, 1.45, 0.0);
        set(C::LElbow, 0.2, 1.18, 0.0);
        set(C::LWrist, 0.21, 0.93, 0.05);
        set(C::RShoulder, -0.18, 1.45, 0.0);
        set(C::RElbow, -0.2, 1.18, 0.0);
        set(C::RWrist, -0.21, 0.93, 0.05);
        set(C::LHip, 0.1, 0.95, 0.0);
        set(C::LKnee, 0.1, 0.52, 0.03);
        set(C::LAnkle, 0.1, 0.08, 0.0);
        set(C::LToe, 0.1, 0.02, 0.14);
        set(C::RHip, -0.1, 0.95, 0.0);
        set(C::RKnee, -0.1, 0.52, 0.03);
        set(C::RAnkle, -0.1, 0.08, 0.0);
        set(C::RToe, -0.1, 0.02, 0.14);
        let q = DQuat::from_rotation_y(twist);
        let o = p[C::Chest.index()];
        for c in Canonical::ARMS {
            p[c.index()] = o + q * (p[c.index()] - o);
        }
        p
    }

    /// A clip whose frames twist the shoulders ±`amp` about a square
    /// carriage, each frame turned to heading `yaw0 + 0.1 i` and moved
    /// along; then the whole turned by `q` and scaled by `k`.
    fn clip(n: usize, amp: f64, q: DQuat, k: f64) -> Vec<Pose> {
        (0..n)
            .map(|i| {
                let t = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
                let h = DQuat::from_rotation_y(0.3 + 0.1 * i as f64);
                let d = DVec3::new(0.05 * i as f64, 0.0, 0.4 * i as f64);
                standing(amp * t.sin()).map(|x| q * ((h * x + d) * k))
            })
            .collect()
    }

    fn near(a: &Pose, b: &Pose, tol: f64) -> bool {
        a.iter().zip(b).all(|(x, y)| x.distance(*y) < tol)
    }

    /// The yaw (radians) of the shoulders' line against the hips'.
    fn twist_of(p: &Pose) -> f64 {
        let h = p[C::LHip.index()] - p[C::RHip.index()];
        let s = p[C::LShoulder.index()] - p[C::RShoulder.index()];
        h.x.mul_add(s.z, -(h.z * s.x)).atan2(h.x * s.x + h.z * s.z)
    }

    #[test]
    fn a_twisted_frame_takes_the_square_mean_carriage() {
        let mocap = clip(40, 0.15, DQuat::IDENTITY, 1.0);
        // Frame 10: the shoulders 0.15 rad against the hips (the crest).
        let r = mocap[10];
        assert!((twist_of(&r).abs() - 0.15).abs() < 1e-9);
        let got = torso_places_from_motion(&r, &mocap);
        // Square again (the mean of a symmetric twist), to the second
        // order of the twist.
        assert!(twist_of(&got).abs() < 0.005, "{}", twist_of(&got));
        // The torso keeps its shape: each place as far from the pelvis.
        let p = C::Pelvis.index();
        for c in TORSO_PLACES {
            let d = |q: &Pose| q[c.index()].distance(q[p]);
            assert!((d(&got) - d(&r)).abs() < 0.002, "{c:?}");
        }
        // The shoulders and hips each turned back by part of the twist
        // (9.6 mm: the result keeps the frame's heading, the sum of the
        // two lines), the arms and legs carried with them.
        let moved = |c: C| got[c.index()] - r[c.index()];
        assert!(moved(C::LShoulder).length() > 0.005 && moved(C::LHip).length() > 0.005);
        assert!(moved(C::LElbow).distance(moved(C::LShoulder)) < 1e-12);
        assert!(moved(C::RToe).distance(moved(C::RHip)) < 1e-12);
    }

    #[test]
    fn the_carriage_turns_and_scales_with_the_clip() {
        let q = DQuat::from_rotation_y(0.52);
        for k in [0.6, 1.37] {
            let (a, b) = (clip(31, 0.2, DQuat::IDENTITY, 1.0), clip(31, 0.2, q, k));
            let ga = torso_places_from_motion(&a[7], &a);
            let gb = torso_places_from_motion(&b[7], &b);
            assert!(near(&ga.map(|x| q * x * k), &gb, 1e-9), "{k}");
        }
        // Re-ordered frames: the same mean.
        let a = clip(31, 0.2, DQuat::IDENTITY, 1.0);
        let mut b = a.clone();
        b.reverse();
        let (ga, gb) = (
            torso_places_from_motion(&a[7], &a),
            torso_places_from_motion(&a[7], &b),
        );
        assert!(near(&ga, &gb, 1e-9));
    }

    #[test]
    fn the_file_rotations_take_the_mean_carriage_in_the_heading() {
        // Each frame's chest rotation: its heading turn composed on a
        // constant carriage `c`; the mean is `c` in the reference's heading.
        let mocap = clip(20, 0.0, DQuat::IDENTITY, 1.0);
        let c = DQuat::from_rotation_x(0.2) * DQuat::from_rotation_z(-0.1);
        let file: Vec<JointRotations> = (0..20)
            .map(|i| {
                let mut w: JointRotations = [None; Canonical::COUNT];
                w[C::Chest.index()] = Some(DQuat::from_rotation_y(0.3 + 0.1 * i as f64) * c);
                w
            })
            .collect();
        let (pose, at) = torso_from_motion(&mocap[5], &mocap, &file, DQuat::IDENTITY);
        let at = at.expect("one rotation per frame");
        let want = file[5][C::Chest.index()].unwrap();
        assert!(at[C::Chest.index()].unwrap().angle_between(want) < 1e-9);
        assert!(at[C::Head.index()].is_none());
        assert!(near(&pose, &mocap[5], 1e-9));
        // No rotation per frame: none given.
        assert!(
            torso_from_motion(&mocap[5], &mocap, &file[..3], DQuat::IDENTITY)
                .1
                .is_none()
        );
    }

    #[test]
    fn the_reference_rule_reads_rest_and_carriage_and_names_any_other() {
        assert_eq!(reference_rule(None), Ok(false));
        assert_eq!(reference_rule(Some(" rest ")), Ok(false));
        assert_eq!(reference_rule(Some("")), Ok(false));
        assert_eq!(reference_rule(Some("carriage")), Ok(true));
        let e = reference_rule(Some("Carriage")).unwrap_err();
        assert!(e.contains("'Carriage'"), "{e}");
    }

    #[test]
    fn an_upright_rest_takes_the_carriage_only_when_asked() {
        let mocap = clip(30, 0.15, DQuat::IDENTITY, 1.0);
        let rest = ClipNeutral {
            pose: standing(0.0),
            source: ClipNeutralSource::Rest,
            rotations: std::sync::Arc::from(Vec::new()),
        };
        let r = rest.pose;
        let (kept, at) = torso_reference(&r, &mocap, &rest, DQuat::IDENTITY, false);
        assert_eq!((kept, at), (r, None));
        let (moved, _) = torso_reference(&r, &mocap, &rest, DQuat::IDENTITY, true);
        assert_eq!(moved, torso_places_from_motion(&r, &mocap));
        // A frame reference takes it either way.
        let frame = ClipNeutral {
            source: ClipNeutralSource::Frame(4),
            pose: mocap[4],
            ..rest
        };
        for on in [false, true] {
            let (p, _) = torso_reference(&mocap[4], &mocap, &frame, DQuat::IDENTITY, on);
            assert_eq!(p, torso_places_from_motion(&mocap[4], &mocap));
        }
    }

    #[test]
    fn a_pose_with_no_heading_is_left() {
        let mut r = standing(0.0);
        for c in [C::LHip, C::RHip, C::LShoulder, C::RShoulder] {
            r[c.index()].x = 0.0;
        }
        let mocap = clip(5, 0.1, DQuat::IDENTITY, 1.0);
        assert_eq!(torso_places_from_motion(&r, &mocap), r);
        let nan = [DVec3::NAN; Canonical::COUNT];
        let s = standing(0.1);
        assert_eq!(torso_places_from_motion(&s, &[nan]), s);
    }
}
