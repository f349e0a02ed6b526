//! Confluent Motion transfer (de Aguiar et al. 2007) on real data: self-
//! transfer of the samba and crane captures, identity and rigid motions,
//! the candy-wrapper case, a CMU walk on the armadillo, raw-scan repair.

use crate::common;

use glam::{DQuat, DVec3};
use std::path::Path;
use surfmotion::drive::query::load_mocap;
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::mesh::io::{LoadOptions, load_sequence};
use surfmotion::mesh::{Mesh, MeshSequence};
use surfmotion::tools::eval::vertex_error;
use surfmotion::transfer::markers::generate;
use surfmotion::transfer::{
    Driving, Job, MarkerOptions, MarkerSpec, SignMode, TransferOptions, TransferStats, prepare,
    transfer,
};

fn fixture(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn capture(d: &Path, name: &str) -> MeshSequence {
    let p = d.join(format!("4d/{name}/{name}.pc2"));
    load_sequence(p.to_str().unwrap(), &LoadOptions::default()).unwrap()
}

/// Transfers `template` onto `scan` with markers from `landmarks` (the
/// template's markers made by the same rule from the same landmarks).
fn self_transfer(
    scan: &Mesh,
    template: &MeshSequence,
    landmarks: &Landmarks,
    count: usize,
    signs: SignMode,
) -> (Vec<[f64; 3]>, TransferStats, f64) {
    let opts = MarkerOptions {
        count,
        ..Default::default()
    };
    let prepared = prepare(scan, MarkerSpec::Landmarks(landmarks, opts)).unwrap();
    let rig = prepared.rig.as_ref().unwrap();
    let tmarkers = generate(&template.frame_mesh(0), rig, &opts);
    let mut job = Job::new(
        &prepared,
        Driving::Template {
            frames: template,
            markers: &tmarkers,
            reference: 0,
            align: glam::DQuat::IDENTITY,
        },
    )
    .unwrap();
    let (out, stats) = transfer(
        &job.confluent,
        &mut job.motion,
        &TransferOptions { signs },
        &|_| {},
    );
    (out, stats, rig.height())
}

fn assert_finite(p: &[[f64; 3]]) {
    assert!(p.iter().flatten().all(|x| x.is_finite()), "NaN in output");
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn self_transfer_reproduces_real_captures_better_with_more_markers() {
    let Some(d) = common::data_dir() else { return };
    for name in ["samba", "crane"] {
        let seq = capture(&d, name);
        let scan = seq.frame_mesh(0);
        let lm = Landmarks::load(
            &fixture(&format!("{name}.landmarks.json")),
            scan.vertex_count(),
        )
        .unwrap();
        let mut means = Vec::new();
        for count in [20, 80, 180] {
            let (out, stats, h) = self_transfer(&scan, &seq, &lm, count, SignMode::Consistent);
            assert_finite(&out);
            assert_eq!(stats.frames, seq.frame_count());
            assert_eq!(stats.max_weak_triangles, 0, "{name}: collapse threatened");
            let e = vertex_error(&out, seq.all_positions(), scan.vertex_count(), h);
            // The reference frame itself is reproduced.
            assert!(
                e.per_frame[0] < 1e-6,
                "{name}: frame 0 moved {}",
                e.per_frame[0]
            );
            eprintln!(
                "{name}, {count} markers ({} used): mean {:.2}%, p95 {:.2}% of height",
                stats.markers, e.mean_pct, e.p95_pct
            );
            means.push(e.mean_pct);
        }
        assert!(
            means[2] < means[0],
            "{name}: 180 markers ({:.2}%) are no better than 20 ({:.2}%)",
            means[2],
            means[0]
        );
        // Measured 2.4% (samba) and 2.9% (crane) of the height at 180
        // markers: the pose is carried; what is left is cloth and hair.
        assert!(means[2] < 4.0, "{name}: mean error {:.2}% at 180", means[2]);
    }
}

/// The samba frame 0 as a template moved rigidly (or not at all).
fn moved_template(scan: &Mesh, f: impl Fn(DVec3) -> DVec3, frames: usize) -> MeshSequence {
    let mut all = Vec::new();
    for k in 0..frames {
        all.extend(scan.positions().iter().map(|p| {
            let q = DVec3::from_array(*p);
            if k == 0 { q } else { f(q) }.to_array()
        }));
    }
    MeshSequence::new(scan.clone(), all, Some(30.0)).unwrap()
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn identity_and_rigid_motions_are_reproduced() {
    let Some(d) = common::data_dir() else { return };
    let scan = capture(&d, "samba").frame_mesh(0);
    let lm = Landmarks::load(&fixture("samba.landmarks.json"), scan.vertex_count()).unwrap();
    let r = DQuat::from_axis_angle(DVec3::new(0.2, 1.0, 0.3).normalize(), 2.0);
    let t = DVec3::new(0.4, 0.1, -0.7);
    type Motion = Box<dyn Fn(DVec3) -> DVec3>;
    let cases: [(&str, Motion); 2] = [
        ("identity", Box::new(|q| q)),
        ("rigid", Box::new(move |q| r * q + t)),
    ];
    for (what, f) in cases {
        let tpl = moved_template(&scan, &f, 3);
        let (out, _, h) = self_transfer(&scan, &tpl, &lm, 80, SignMode::Consistent);
        let e = vertex_error(&out, tpl.all_positions(), scan.vertex_count(), h);
        assert!(e.max_pct < 1e-5, "{what}: moved {}% of height", e.max_pct);
    }
}

/// Ratios of every edge's length (every frame) to its rest length, sorted.
fn edge_ratios(rest: &Mesh, p: &[[f64; 3]]) -> Vec<f64> {
    let r = rest.positions();
    let n = r.len();
    let mut all = Vec::new();
    for frame in p.chunks(n) {
        for t in rest.triangles() {
            for k in 0..3 {
                let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
                let l0 = (DVec3::from_array(r[a]) - DVec3::from_array(r[b])).length();
                let l1 = (DVec3::from_array(frame[a]) - DVec3::from_array(frame[b])).length();
                if l0 > 0.0 {
                    all.push(l1 / l0);
                }
            }
        }
    }
    all.sort_by(f64::total_cmp);
    all
}

/// (min, max) edge-length ratio.
fn edge_band(rest: &Mesh, p: &[[f64; 3]]) -> (f64, f64) {
    let e = edge_ratios(rest, p);
    (e[0], e[e.len() - 1])
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn near_half_turns_do_not_collapse_the_mesh() {
    // The candy-wrapper case of Sec. 4.3: the template turns by 180° about
    // the vertical, a little more at the head than at the feet, so marker
    // rotations straddle w = 0. With w ≥ 0 per marker the quaternion field
    // crosses zero and triangles collapse; with consistent signs the scan
    // turns smoothly.
    let Some(d) = common::data_dir() else { return };
    let scan = capture(&d, "samba").frame_mesh(0);
    let lm = Landmarks::load(&fixture("samba.landmarks.json"), scan.vertex_count()).unwrap();
    let twist = |q: DVec3| {
        let a = std::f64::consts::PI + 0.3 * (q.y - 0.9);
        DQuat::from_rotation_y(a) * q
    };
    let tpl = moved_template(&scan, twist, 2);
    let (good, gs, _) = self_transfer(&scan, &tpl, &lm, 180, SignMode::Consistent);
    let (bad, bs, _) = self_transfer(&scan, &tpl, &lm, 180, SignMode::Hemisphere);
    let n = scan.vertex_count();
    let (gmin, gmax) = edge_band(&scan, &good[n..]);
    let (bmin, _) = edge_band(&scan, &bad[n..]);
    eprintln!(
        "consistent: {} weak triangles, edges x{gmin:.2}..{gmax:.2}; w ≥ 0: {} weak, shortest edge x{bmin:.3}",
        gs.max_weak_triangles, bs.max_weak_triangles
    );
    assert!(gs.singular_frames == 1 && bs.singular_frames == 1);
    assert_eq!(gs.max_weak_triangles, 0);
    assert!(
        bs.max_weak_triangles > 0,
        "the naive rule should collapse here"
    );
    assert!(gmin > 0.5 && gmax < 2.0);
    assert!(bmin < gmin);
}

/// A CMU walk on a scan: no NaN, no collapse, edges in a sane band, and
/// it travels.
fn walk_on(name: &str, scan: &Mesh, landmarks: &str, clip: &Path) {
    let lm = Landmarks::load(&fixture(landmarks), scan.vertex_count()).unwrap();
    let prepared = prepare(scan, MarkerSpec::Landmarks(&lm, MarkerOptions::default())).unwrap();
    assert!(
        prepared.markers.len() >= 140,
        "{name}: {} markers",
        prepared.markers.len()
    );
    let clip = load_mocap(clip, &Default::default(), 30.0).unwrap();
    let mut job = Job::new(&prepared, Driving::Mocap(&clip.poses, &clip.reference)).unwrap();
    let (out, stats) = transfer(
        &job.confluent,
        &mut job.motion,
        &TransferOptions::default(),
        &|_| {},
    );
    assert_finite(&out);
    assert_eq!(stats.frames, clip.poses.len());
    assert_eq!(stats.max_weak_triangles, 0, "{name}");
    let e = edge_ratios(&prepared.mesh, &out);
    let q = |f: f64| e[((e.len() - 1) as f64 * f) as usize];
    let (lo, hi) = (e[0], e[e.len() - 1]);
    eprintln!(
        "{name}: {} frames, {} markers, edge lengths x{lo:.3}..x{hi:.3} of rest, \
         99.9% within x{:.3}..x{:.3}",
        stats.frames,
        stats.markers,
        q(0.0005),
        q(0.9995)
    );
    // Rest poses differ from the clip's (the armadillo's arms are above its
    // head, MakeHuman's in an A): skin folds in the armpits (shortest
    // edges); nothing tears or inverts into a spike. (Measured on the
    // armadillo with 02_01: one armpit edge at x0.089 in one frame with the
    // rest-pose-aware retargeting, which keeps its hunched torso, x0.154
    // before; the 99.9 % band narrowed from x0.53..1.51 to x0.62..1.40.)
    // The marker centres' pull in the Poisson solve (s14: limbs go where
    // the skeleton puts them) folds the SMPL armpit further when its
    // T-pose arms come down: the 99.9 % band's low end x0.525 → x0.417 at
    // frame 60 of 02_01 (one armpit edge x0.386 → x0.280); rendered front
    // and side, the arms lie against the body as before, nothing torn.
    assert!(lo > 0.05 && hi < 3.0, "{name}: edges x{lo}..x{hi}");
    assert!(q(0.0005) > 0.35 && q(0.9995) < 2.0, "{name}");
    // It walks: the centroid moves forward by more than a body height.
    let n = prepared.mesh.vertex_count();
    let c = |f: usize| {
        out[f * n..(f + 1) * n]
            .iter()
            .map(|p| DVec3::new(p[0], 0.0, p[2]))
            .sum::<DVec3>()
            / n as f64
    };
    let h = prepared.rig.as_ref().unwrap().height();
    assert!(
        (c(stats.frames - 1) - c(0)).length() > h,
        "{name}: it did not travel"
    );
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_cmu_walk_moves_every_scan_without_tearing() {
    let Some(d) = common::data_dir() else { return };
    let walk = d.join("mocap/cmu-amc/02/02_01.amc");
    let read = |p: &str| surfmotion::mesh::io::obj::read_obj(&d.join(p)).unwrap();
    walk_on(
        "armadillo",
        &read("scans/armadillo/armadillo.obj"),
        "armadillo.landmarks.json",
        &walk,
    );
    walk_on(
        "smpl",
        &read("scans/smpl-template/human_man.obj"),
        "smpl.landmarks.json",
        &walk,
    );
    let mh = read("scans/makehuman/base.obj")
        .select_groups(&["body".into()])
        .unwrap();
    walk_on("makehuman body", &mh, "makehuman.landmarks.json", &walk);
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn raw_scans_are_repaired_and_stray_pieces_dropped() {
    let Some(d) = common::data_dir() else { return };
    let seq = load_sequence(
        d.join("scans/armadillo/armadillo.obj").to_str().unwrap(),
        &LoadOptions::default(),
    )
    .unwrap();
    let clean = seq.frame_mesh(0);
    // Every vertex duplicated and the second copy used by half the
    // triangles (an unwelded scan), plus a stray tetrahedron far away.
    let n = clean.vertex_count() as u32;
    let mut p = clean.positions().to_vec();
    p.extend_from_slice(clean.positions());
    let mut t: Vec<[u32; 3]> = clean
        .triangles()
        .iter()
        .enumerate()
        .map(|(i, tv)| if i % 2 == 0 { *tv } else { tv.map(|v| v + n) })
        .collect();
    let s = p.len() as u32;
    p.extend([
        [5.0, 0.0, 0.0],
        [5.1, 0.0, 0.0],
        [5.0, 0.1, 0.0],
        [5.0, 0.0, 0.1],
    ]);
    t.extend([
        [s, s + 2, s + 1],
        [s, s + 1, s + 3],
        [s, s + 3, s + 2],
        [s + 1, s + 2, s + 3],
    ]);
    let raw = Mesh::new(p, t).unwrap();
    let lm = Landmarks::load(&fixture("armadillo.landmarks.json"), clean.vertex_count()).unwrap();
    let prepared = prepare(&raw, MarkerSpec::Landmarks(&lm, MarkerOptions::default())).unwrap();
    assert_eq!(prepared.mesh.vertex_count(), clean.vertex_count());
    assert_eq!(prepared.report.repair.welded_vertices, clean.vertex_count());
    assert_eq!(prepared.report.dropped_components, vec![(4, 4)]);
    // The repaired scan factors and an identity motion leaves it in place.
    let tpl = moved_template(&prepared.mesh, |q| q, 2);
    let rig = prepared.rig.as_ref().unwrap();
    let tm = generate(&prepared.mesh, rig, &MarkerOptions::default());
    let mut job = Job::new(
        &prepared,
        Driving::Template {
            frames: &tpl,
            markers: &tm,
            reference: 0,
            align: glam::DQuat::IDENTITY,
        },
    )
    .unwrap();
    let (out, _) = transfer(
        &job.confluent,
        &mut job.motion,
        &Default::default(),
        &|_| {},
    );
    let e = vertex_error(
        &out,
        tpl.all_positions(),
        clean.vertex_count(),
        rig.height(),
    );
    assert!(e.max_pct < 1e-5);
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_performance_moves_onto_another_character() {
    // The samba dancer's capture onto the crane capture's first frame: the
    // two face different ways; the template's rotations are turned into
    // the crane's frame. The crane's limbs then point where the dancer's
    // do (bone directions from each character's own joint regressors).
    let Some(d) = common::data_dir() else { return };
    let samba = capture(&d, "samba");
    let crane = capture(&d, "crane").frame_mesh(0);
    let opts = MarkerOptions::default();
    let lc = Landmarks::load(&fixture("crane.landmarks.json"), crane.vertex_count()).unwrap();
    let ls = Landmarks::load(
        &fixture("samba.landmarks.json"),
        samba.mesh().vertex_count(),
    )
    .unwrap();
    let prepared = prepare(&crane, MarkerSpec::Landmarks(&lc, opts)).unwrap();
    let crig = prepared.rig.as_ref().unwrap();
    let srig = surfmotion::embed::Embedding::new(&samba.frame_mesh(0), &ls, None).unwrap();
    let align = surfmotion::transfer::alignment(&srig, crig);
    let tm = generate(&samba.frame_mesh(0), &srig, &opts);
    let mut job = Job::new(
        &prepared,
        Driving::Template {
            frames: &samba,
            markers: &tm,
            reference: 0,
            align,
        },
    )
    .unwrap();
    assert!(job.used.len() > 140, "{} paired markers", job.used.len());
    let (out, stats) = transfer(
        &job.confluent,
        &mut job.motion,
        &Default::default(),
        &|_| {},
    );
    assert_finite(&out);
    assert_eq!(stats.max_weak_triangles, 0);
    use surfmotion::rig::Canonical as C;
    let limbs = [
        (C::LShoulder, C::LElbow),
        (C::LElbow, C::LWrist),
        (C::RShoulder, C::RElbow),
        (C::RElbow, C::RWrist),
        (C::LHip, C::LKnee),
        (C::LKnee, C::LAnkle),
        (C::RHip, C::RKnee),
        (C::RKnee, C::RAnkle),
    ];
    let n = crane.vertex_count();
    let (mut with, mut without, mut k) = (0.0, 0.0, 0);
    for f in (0..samba.frame_count()).step_by(5) {
        let sj = srig.frame_joints(samba.frame(f));
        let cj = crig.frame_joints(&out[f * n..(f + 1) * n]);
        let c0 = crig.frame_joints(crane.positions());
        for (a, b) in limbs {
            let want = align * (sj[b.index()] - sj[a.index()]).normalize();
            let got = (cj[b.index()] - cj[a.index()]).normalize();
            let rest = (c0[b.index()] - c0[a.index()]).normalize();
            with += got.dot(want).clamp(-1.0, 1.0).acos().to_degrees();
            without += rest.dot(want).clamp(-1.0, 1.0).acos().to_degrees();
            k += 1;
        }
    }
    let (with, without) = (with / k as f64, without / k as f64);
    eprintln!("crane limbs off the dancer's by {with:.1}° (standing still: {without:.1}°)");
    assert!(
        with < 15.0 && with < 0.5 * without,
        "{with:.1}° vs {without:.1}°"
    );
}
