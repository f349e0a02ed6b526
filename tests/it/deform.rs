//! Part-based PCA Laplacian deformation on the samba character.

use crate::common;

use glam::DVec3;
use surfmotion::db::Character;
use surfmotion::deform::{DeformMode, DeformOptions, Deformer};
use surfmotion::drive::query::{ClipQuery, load_mocap};
use surfmotion::drive::{DriveOptions, Output, synthesise};
use surfmotion::pose::Pose;

fn height(p: &[[f64; 3]]) -> f64 {
    let (lo, hi) = p
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v[1]), h.max(v[1]))
        });
    hi - lo
}

fn max_dist(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| DVec3::from_array(*p).distance(DVec3::from_array(*q)))
        .fold(0.0, f64::max)
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn constraints_from_an_example_frame_return_that_frame() {
    let Some(d) = common::data_dir() else { return };
    let db = common::synthetic_db(&d);
    let ch = Character::load(&db, &surfmotion::db::Quiet).unwrap();
    let n = ch.n();
    for mode in [DeformMode::Part, DeformMode::Global] {
        // A basis spanning all examples (keep everything).
        // A frame every region uses as an example.
        let f = surfmotion::graph::FlatFrame::new(57);
        let opts = DeformOptions {
            keep: 1.0,
            include: Some(f),
            ..Default::default()
        };
        let def = Deformer::new(&ch, mode, &opts).unwrap();
        assert!(!def.constraint_vertices.is_empty());
        assert!(def.examples.iter().all(|e| e.contains(&f)));
        let mut x = vec![[0.0; 3]; n];
        ch.frame_metres(f, &mut x);
        let pose = *ch.pose(f);
        let mut out = vec![[0.0; 3]; n];
        def.deform(&ch, &x, &pose, &pose, &mut out, &mut def.workspace());
        let err = max_dist(&out, &x) / height(&x);
        assert!(err < 1e-4, "{mode:?}: frame {f} moved {err} of the height");
        // The space is centred on the edited frame, so with the paper's 95 %
        // basis too a frame deformed to its own skeleton is returned.
        let def95 = Deformer::new(&ch, mode, &DeformOptions::default()).unwrap();
        def95.deform(&ch, &x, &pose, &pose, &mut out, &mut def95.workspace());
        let err95 = max_dist(&out, &x) / height(&x);
        assert!(err95 < 1e-4, "{mode:?}: {err95}");
        eprintln!(
            "{mode:?}: frame {f}, full basis {err:.2e}, 95 % basis {err95:.2e} of the height"
        );
    }
}

fn skeleton_error(ch: &Character, p: &[[f64; 3]], q: &[Pose]) -> f64 {
    let n = ch.n();
    let mut s = 0.0;
    for (k, t) in q.iter().enumerate() {
        let e = ch.rig().frame_joints(&p[k * n..(k + 1) * n]);
        s += e.iter().zip(t).map(|(a, b)| a.distance(*b)).sum::<f64>() / 19.0;
    }
    s / q.len() as f64
}

/// The query `m` on `ch` with deformation `mode` (default options).
fn run(ch: &Character, m: &ClipQuery, mode: DeformMode) -> Output {
    let opts = DriveOptions {
        deform: mode,
        ..Default::default()
    };
    synthesise(ch, &m.poses, &m.reference, 30.0, &opts).unwrap()
}

/// Triangle-frames of `res` turned over relative to the frames `raw` they
/// were made from, read two ways: `surface`, a normal opposing the source
/// normal turned by its neighbourhood's own rigid turn
/// ([`surfmotion::deform::near_turns::SurfaceFolds`]: a fold as a person
/// sees it, the reading the tests judge by, issue 42), and `skin`, turned
/// by the skeleton's skin-blended rotation (blind where a vertex's bones
/// turn apart, as the skirt between the thighs: a looser, second check).
/// A triangle that merely turns with its limb counts in neither.
#[derive(Debug, Clone, Copy)]
struct Turned {
    surface: usize,
    skin: usize,
}

fn turned_over(ch: &Character, raw: &Output, res: &Output) -> Turned {
    let n = ch.n();
    let tris = ch.topology().triangles();
    let mut folds = surfmotion::deform::near_turns::SurfaceFolds::new(n, tris);
    let mut count = Turned {
        surface: 0,
        skin: 0,
    };
    let mut turn = vec![glam::DQuat::IDENTITY; n];
    for k in 0..raw.report.frames {
        let (a, b) = (
            &raw.positions[k * n..(k + 1) * n],
            &res.positions[k * n..(k + 1) * n],
        );
        let g = surfmotion::pose::pose_rotations(&ch.rig().frame_joints(a), &raw.query[k]);
        surfmotion::deform::unflip::skin_turns(ch.rig().skin(), &g, &mut turn);
        count.skin += surfmotion::deform::unflip::turned_over(tris, a, b, &turn).len();
        count.surface += folds.turned_over(tris, a, b).len();
    }
    count
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn deformation_follows_the_query_and_turns_no_triangle_over() {
    let Some(d) = common::data_dir() else { return };
    let db = common::synthetic_db(&d);
    let ch = Character::load(&db, &surfmotion::db::Quiet).unwrap();
    let tris = ch.topology().triangles();
    for clip in ["cmu-amc/02/02_02.amc", "cmu-bvh/131_01.bvh"] {
        let m = load_mocap(&d.join("mocap").join(clip), &Default::default(), 30.0).unwrap();
        let (raw, part) = (
            run(&ch, &m, DeformMode::None),
            run(&ch, &m, DeformMode::Part),
        );
        assert!(
            part.positions.iter().flatten().all(|x| x.is_finite()),
            "{clip}"
        );
        let e_raw = skeleton_error(&ch, &raw.positions, &raw.query);
        let e_part = skeleton_error(&ch, &part.positions, &part.query);
        assert!(
            e_part < e_raw,
            "{clip}: part {e_part} vs interpolation {e_raw}"
        );
        let lbs = run(&ch, &m, DeformMode::Lbs);
        let flips = |res: &Output| turned_over(&ch, &raw, res);
        let (part_t, lbs_t) = (flips(&part), flips(&lbs));
        let (f_part, f_lbs) = (part_t.surface, lbs_t.surface.max(lbs_t.skin));
        let total = raw.report.frames * tris.len();
        // Skinning folds the skirt between the legs (and the lunges of
        // 131_01 the hem at the knee); the repair and untangling leave no
        // triangle facing against its surroundings.
        assert!(f_lbs > 0, "{clip}: the query should fold LBS somewhere");
        assert_eq!(
            f_part, 0,
            "{clip}: {f_part} of {total} triangle-frames turned over"
        );
        // Without the repair the solve does turn some over, so the check
        // above has something to catch.
        let bare = synthesise(
            &ch,
            &m.poses,
            &m.reference,
            30.0,
            &DriveOptions {
                deform_options: DeformOptions {
                    repair: surfmotion::deform::unflip::RepairOptions {
                        rounds: 0,
                        ..Default::default()
                    },
                    ..Default::default()
                },
                ..Default::default()
            },
        )
        .unwrap();
        let bare_t = flips(&bare);
        let f_bare = bare_t.surface;
        assert!(
            f_bare > 0,
            "{clip}: the unrepaired solve turned nothing over"
        );
        // The looser check: against the skin's blend the repair leaves
        // fewer than the solve turned over.
        assert!(
            part_t.skin < bare_t.skin,
            "{clip}: against the skin's turns {part_t:?} after the repair, {bare_t:?} before"
        );
        eprintln!(
            "{clip}: turned-over triangle-frames (surface, skin): part {part_t:?} (unrepaired {bare_t:?}), LBS {lbs_t:?} of {total}"
        );
        eprintln!("{clip}: mean joint error {e_raw:.4} m -> {e_part:.4} m");
        // The report counts the same triangles.
        assert_eq!(part.report.turned_over.after, 0);
        assert!(part.report.turned_over.before >= f_bare.min(1));
    }
}

/// The real samba capture as a database (`db init`, its graph built and
/// cached by a first load), made once per test binary.
pub(crate) fn samba_capture_db(d: &std::path::Path) -> std::path::PathBuf {
    use std::sync::OnceLock;
    static DB: OnceLock<std::path::PathBuf> = OnceLock::new();
    DB.get_or_init(|| {
        let db = common::fixture_dir("deform-samba").join("samba");
        common::run_ok(
            std::process::Command::new(common::bin())
                .args(["db", "init", db.to_str().unwrap(), "--mesh"])
                .arg(d.join("4d/samba/samba.obj"))
                .arg("--sequence")
                .arg(format!("dance={}", d.join("4d/samba/samba.pc2").display()))
                .arg("--landmarks")
                .arg(
                    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                        .join("tests/fixtures/samba.landmarks.json"),
                ),
        );
        Character::load(&db, &surfmotion::db::Quiet).unwrap();
        db
    })
    .clone()
}

/// The real samba capture itself as the database (its own dress, with the
/// captured folds): a CMU walk leaves no triangle turned over either.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_walk_on_the_real_capture_turns_no_triangle_over() {
    let Some(d) = common::data_dir() else { return };
    let ch = Character::load(&samba_capture_db(&d), &surfmotion::db::Quiet).unwrap();
    let m = load_mocap(
        &d.join("mocap/cmu-amc/02/02_02.amc"),
        &Default::default(),
        30.0,
    )
    .unwrap();
    let [raw, part, lbs] =
        [DeformMode::None, DeformMode::Part, DeformMode::Lbs].map(|mode| run(&ch, &m, mode));
    let (part_t, lbs_t) = (turned_over(&ch, &raw, &part), turned_over(&ch, &raw, &lbs));
    assert!(lbs_t.surface.max(lbs_t.skin) > 0, "{lbs_t:?}");
    assert_eq!(part_t.surface, 0, "{part_t:?} triangle-frames turned over");
    // The looser check against the skin's blend (the thighs' turns under
    // the skirt, which the cloth does not follow): fewer than the solve
    // turned over.
    assert!(
        part_t.skin < part.report.turned_over.before,
        "{part_t:?} against {} before the repair",
        part.report.turned_over.before
    );
    eprintln!(
        "real samba, 02_02: turned over after the solve {}, after the repair {part_t:?}; LBS {lbs_t:?}",
        part.report.turned_over.before
    );
}

/// Checks the fold repair's restricted readings (issue 45) on one folded
/// frame `out` of a surface `tris` whose retrieved frame is `src`: after
/// the first reading (`SurfaceReading::read_all`), each move — the
/// repair's patch solves with the reading's turns, as the deformation
/// runs them, or one vertex pushed through the middle — is read again
/// only near what moved (`read_again`), which must flag exactly the triangles a full
/// reading flags, with the same turns bit for bit (one vertex moved: a
/// few seeds computed again); and the untangling with its reference
/// normals computed on demand (`untangle::OnDemand`) must move every
/// vertex to the same bits as with all of them computed first, computing
/// fewer than half. The moves change what is flagged, so a reading that
/// kept its last flags would fail.
fn check_readings(what: &str, tris: &[[u32; 3]], src: &[[f64; 3]], mut out: Vec<[f64; 3]>) {
    use glam::DQuat;
    use surfmotion::deform::near_turns::{Neighbourhoods, RINGS, ReadingOf, SurfaceReading};
    use surfmotion::deform::unflip::{
        Adjacency, Budget, RepairOptions, WorkLimit, source_normals, turned_over_from, unflip,
    };
    use surfmotion::deform::untangle::{
        LazyReferences, OnDemand, UntangleOptions, turned_references, untangle, untangle_with,
    };
    let n = src.len();
    let adj = Adjacency::new(n, tris);
    let near = Neighbourhoods::new(&adj, RINGS);
    let mut sn = vec![DVec3::ZERO; tris.len()];
    source_normals(tris, src, &mut sn);
    let f = ReadingOf {
        near: &near,
        adj: &adj,
        tris,
        source: src,
        source_normals: &sn,
    };
    let bits = |q: &[DQuat]| -> Vec<[u64; 4]> {
        q.iter().map(|q| q.to_array().map(f64::to_bits)).collect()
    };
    let pbits =
        |x: &[[f64; 3]]| -> Vec<[u64; 3]> { x.iter().map(|p| p.map(f64::to_bits)).collect() };
    let mut r = SurfaceReading::default();
    let (mut seeds, mut turn) = (Vec::new(), vec![DQuat::IDENTITY; n]);
    let mut bad = r.read_all(&f, &out, &mut seeds, &mut turn);
    assert_eq!(bad, turned_over_from(tris, &sn, &out, &turn), "{what}");
    assert!(bad.len() >= 5, "{what}: {} flagged", bad.len());
    // The untangling: all normals first, or on demand.
    let areas: Vec<f64> = sn.iter().map(|c| 0.5 * c.length()).collect();
    let mut all = vec![DVec3::ZERO; tris.len()];
    turned_references(tris, &sn, &turn, &mut all);
    let folded: Vec<u32> = (0..tris.len() as u32)
        .filter(|&t| {
            let [a, b, c] = tris[t as usize].map(|v| DVec3::from_array(out[v as usize]));
            all[t as usize].dot((b - a).cross(c - a)) <= 0.0
        })
        .collect();
    let opts = UntangleOptions::default();
    let (mut x, mut y) = (out.clone(), out.clone());
    let left_x = untangle(tris, &adj, &all, &areas, &mut x, folded.clone(), &opts);
    let mut lazy = LazyReferences::new(tris.len());
    let mut refs = OnDemand {
        lazy: &mut lazy,
        source_normals: &sn,
        turn: &turn,
    };
    let mut budget = Budget::new(WorkLimit::NONE);
    let left_y = untangle_with(
        tris,
        &adj,
        &mut refs,
        &areas,
        &mut y,
        folded,
        &opts,
        &mut budget,
    );
    assert_eq!(left_x, left_y, "{what}: untangled");
    assert!(
        pbits(&x) == pbits(&y),
        "{what}: the untangling moved other bits"
    );
    assert!(
        pbits(&x) != pbits(&out),
        "{what}: the untangling moved nothing"
    );
    assert!(
        lazy.computed < tris.len() / 2,
        "{what}: {} of {} normals computed",
        lazy.computed,
        tris.len()
    );
    // The repair's moves, read again.
    let mut changes = 0;
    for round in 0..6 {
        if round % 2 == 0 {
            let opts = RepairOptions {
                rounds: 3 + round / 2,
                ..Default::default()
            };
            unflip(tris, &adj, src, &mut out, &turn, bad.clone(), &opts);
        } else {
            // A vertex pushed through the middle: its fan turns over.
            let v = (round * 3001 + 17) % n;
            let mid = out.iter().map(|q| DVec3::from_array(*q)).sum::<DVec3>() / n as f64;
            out[v] = (mid + (mid - DVec3::from_array(out[v])) * 0.3).to_array();
        }
        let again = r.read_again(&f, &out, &mut seeds, &mut turn);
        let (mut s2, mut t2) = (Vec::new(), vec![DQuat::IDENTITY; n]);
        let full = SurfaceReading::default().read_all(&f, &out, &mut s2, &mut t2);
        assert_eq!(again, full, "{what}, round {round}");
        assert!(
            bits(&turn) == bits(&t2),
            "{what}, round {round}: turns differ"
        );
        assert!(
            bits(&seeds) == bits(&s2),
            "{what}, round {round}: seed turns differ"
        );
        if round % 2 == 1 {
            assert!(
                r.work.seeds > 0 && r.work.seeds < 40,
                "{what}, round {round}: {:?} of {} seeds",
                r.work,
                near.seeds()
            );
        }
        changes += usize::from(full != bad);
        bad = full;
    }
    assert!(changes >= 2, "{what}: the moves changed no flag");
}

/// [`check_readings`] on the real samba capture (frame 40 as the source,
/// frame 120, the dancer turned and stepped, with six vertices pushed
/// through the body by hand), in the capture's numbering and reversed;
/// and on a generated sphere (bent and stretched, five vertices pushed
/// through), in its numbering and shuffled with its triangles reversed.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn restricted_repair_readings_flag_what_full_readings_flag() {
    use surfmotion::mesh::io::{obj, pc2};
    use surfmotion::mesh::subdivide::{icosahedron, midpoint};
    let Some(d) = common::data_dir() else { return };
    let mesh = obj::read_obj(&d.join("4d/samba/samba.obj")).unwrap();
    let cache = pc2::read_pc2(&d.join("4d/samba/samba.pc2")).unwrap();
    let sphere = midpoint(&midpoint(&midpoint(&icosahedron())));
    let pushed = |mut p: Vec<[f64; 3]>, k: usize, by: f64| {
        let mid = p.iter().map(|q| DVec3::from_array(*q)).sum::<DVec3>() / p.len() as f64;
        for j in 0..k {
            let v = (j * 1601 + 250) % p.len();
            p[v] = (mid + (mid - DVec3::from_array(p[v])) * by).to_array();
        }
        p
    };
    let n = mesh.positions().len();
    let frame = |k: usize| cache.positions[k * n..(k + 1) * n].to_vec();
    let bent: Vec<[f64; 3]> = sphere
        .positions()
        .iter()
        .map(|p| {
            let v = DVec3::from_array(*p);
            (glam::DQuat::from_rotation_z(0.8 * v.y) * v * DVec3::new(1.3, 0.8, 1.0)).to_array()
        })
        .collect();
    let cases = [
        (
            "samba",
            mesh.triangles().to_vec(),
            frame(40),
            pushed(frame(120), 6, 0.3),
        ),
        (
            "sphere",
            sphere.triangles().to_vec(),
            sphere.positions().to_vec(),
            pushed(bent, 5, 0.4),
        ),
    ];
    for (name, tris, src, out) in cases {
        check_readings(name, &tris, &src, out.clone());
        // Renumbered: the vertices shuffled (a fixed LCG), the triangles
        // in reverse order, each starting at its second corner.
        let m = src.len();
        let mut order: Vec<usize> = (0..m).collect();
        let mut s = 7u64;
        for i in (1..m).rev() {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            order.swap(i, (s >> 33) as usize % (i + 1));
        }
        let mut new = vec![0u32; m];
        for (k, &o) in order.iter().enumerate() {
            new[o] = k as u32;
        }
        let t2: Vec<[u32; 3]> = tris
            .iter()
            .rev()
            .map(|t| [t[1], t[2], t[0]].map(|v| new[v as usize]))
            .collect();
        let re = |p: &[[f64; 3]]| order.iter().map(|&o| p[o]).collect::<Vec<_>>();
        check_readings(&format!("{name} renumbered"), &t2, &re(&src), re(&out));
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_manifest_overrides_constraints_and_examples() {
    let Some(d) = common::data_dir() else { return };
    let db = common::synthetic_db(&d);
    let tmp = tempfile::tempdir().unwrap();
    // A copy of the database with a [deform] section.
    for e in std::fs::read_dir(&db).unwrap().flatten() {
        if e.path().is_file() {
            std::fs::copy(e.path(), tmp.path().join(e.file_name())).unwrap();
        }
    }
    let mut m = surfmotion::db::Manifest::load(tmp.path()).unwrap();
    std::fs::write(tmp.path().join("c.json"), "[10, 500, 2000, 7000]").unwrap();
    m.deform.constraints = Some("c.json".into());
    m.deform.examples = vec!["02_01:10".into(), "02_03:5".into(), "02_01:40".into()];
    m.save(tmp.path()).unwrap();
    let ch = Character::load(tmp.path(), &surfmotion::db::Quiet).unwrap();
    let def = Deformer::new(&ch, DeformMode::Part, &DeformOptions::default()).unwrap();
    assert_eq!(def.constraint_vertices, vec![10, 500, 2000, 7000]);
    let s0 = ch
        .graph()
        .sequences()
        .iter()
        .position(|s| s.name == "02_01")
        .unwrap();
    let ids = def.examples[0].clone();
    assert_eq!(ids.len(), 3);
    assert_eq!(ids[0], ch.graph().flat_id(s0, 10));
    assert!(def.examples.iter().all(|e| *e == ids));
    // Bad overrides are one-line errors naming the manifest.
    m.deform.examples = vec!["02_01:9999".into()];
    m.save(tmp.path()).unwrap();
    let e = Character::load(tmp.path(), &surfmotion::db::Quiet)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("[deform]") && e.contains("9999"), "{e}");
    std::fs::write(tmp.path().join("c.json"), "[99999999]").unwrap();
    m.deform.examples.clear();
    m.save(tmp.path()).unwrap();
    let e = Character::load(tmp.path(), &surfmotion::db::Quiet)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("out of range"), "{e}");
}

/// A turned-over triangle nearly edge-on to its reference normal (its far
/// edge almost along that normal) barely changes its signed area wherever
/// its vertex goes: the relaxation's step `gap / |g|` along its tiny
/// gradient `g` once sent the vertex metres off the surface. That is what
/// made the single-vertex spikes of retargeted results (CMU 131_01 on a
/// synthetic samba database: vertex 9760 1.3 m off its ring in frame 121;
/// the fan triangle's gradient was 10⁻³ of its neighbours'). Generated
/// here on a sphere, for several vertices, fan triangles and tilts: the
/// untangling must leave every vertex inside its neighbourhood (within
/// twice its longest edge of where it was) and, where such a place exists
/// (the smaller tilts), face the triangle the right way.
#[test]
fn an_edge_on_triangle_does_not_send_its_vertex_off_the_surface() {
    use glam::DQuat;
    use surfmotion::deform::unflip::Adjacency;
    use surfmotion::deform::untangle::{UntangleOptions, references, untangle};
    use surfmotion::mesh::subdivide::{icosahedron, midpoint};
    let m = midpoint(&midpoint(&midpoint(&icosahedron())));
    let (tris, src) = (m.triangles(), m.positions().to_vec());
    let (n, nt) = (src.len(), tris.len());
    let adj = Adjacency::new(n, tris);
    let turn = vec![DQuat::IDENTITY; n];
    let (mut normals0, mut areas) = (vec![DVec3::ZERO; nt], vec![0.0; nt]);
    references(tris, &src, &turn, &mut normals0, &mut areas);
    let p = |x: &[[f64; 3]], v: u32| DVec3::from_array(x[v as usize]);
    let longest: Vec<f64> = (0..n as u32)
        .map(|v| {
            adj.vertices[v as usize]
                .iter()
                .map(|&u| p(&src, u).distance(p(&src, v)))
                .fold(0.0, f64::max)
        })
        .collect();
    let mut cases = 0;
    for v in (0..n as u32).step_by(41) {
        for (j, &t) in adj.triangles[v as usize].iter().enumerate().step_by(2) {
            for alpha in [1e-2, 1e-3, 1e-4] {
                // The triangle's far edge `b − c` and an in-plane reference
                // normal nearly along it (tilt `alpha`), dipped below the
                // plane by alpha / 20 so that the triangle is turned over.
                let tri = tris[t as usize];
                let i = tri.iter().position(|&u| u == v).unwrap();
                let (b, c) = (tri[(i + 1) % 3], tri[(i + 2) % 3]);
                let e = (p(&src, b) - p(&src, c)).normalize();
                let nn = normals0[t as usize];
                let q = nn.cross(e);
                let beta = alpha / 20.0;
                let mut normals = normals0.clone();
                normals[t as usize] =
                    (e * f64::cos(alpha) + q * f64::sin(alpha) - nn * f64::sin(beta)).normalize();
                let mut out = src.clone();
                let left = untangle(
                    tris,
                    &adj,
                    &normals,
                    &areas,
                    &mut out,
                    vec![t],
                    &UntangleOptions::default(),
                );
                for u in 0..n as u32 {
                    let moved = p(&out, u).distance(p(&src, u));
                    assert!(
                        moved <= 2.0 * longest[u as usize],
                        "vertex {v}, fan triangle {j}, tilt {alpha}: vertex {u} moved {moved:.3} \
                         (its longest edge {:.3})",
                        longest[u as usize]
                    );
                }
                if alpha >= 1e-3 {
                    assert!(
                        left.is_empty(),
                        "vertex {v}, triangle {j}, tilt {alpha}: {left:?}"
                    );
                }
                cases += 1;
            }
        }
    }
    assert!(cases >= 100, "{cases} cases");
}

/// CMU 131_01 retargeted onto the real samba capture: no vertex leaves its
/// one-ring by more than the captured frames do + the plausibility check's
/// margin ([`surfmotion::tools::eval::Limits::off_ring_margin`], 4 mean rest edge
/// lengths). The repair's untangling once shot vertex 2357 0.39 m (27 edge
/// lengths) off its ring in frame 108, against the capture's 1.6. The
/// frames around it are deformed (the library's `deform`, as `retarget`
/// calls it, on the interpolated retrieval), not the whole clip, to keep the
/// test fast.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_real_retarget_keeps_every_vertex_in_its_ring() {
    use surfmotion::tools::eval::triangles::RestTriangles;
    let Some(d) = common::data_dir() else { return };
    let ch = Character::load(&samba_capture_db(&d), &surfmotion::db::Quiet).unwrap();
    let n = ch.n();
    let rest = ch.topology_metres();
    let rt = RestTriangles::new(rest.positions(), rest.triangles()).unwrap();
    let mut captured = 0.0f64;
    let mut buf = vec![[0.0; 3]; n];
    for f in surfmotion::graph::FlatFrame::all(ch.frame_count()) {
        ch.frame_metres(f, &mut buf);
        captured = captured.max(rt.off_ring(&buf).0);
    }
    let line = captured + surfmotion::tools::eval::Limits::default().off_ring_margin;
    let mut m = load_mocap(
        &d.join("mocap/cmu-bvh/131_01.bvh"),
        &Default::default(),
        30.0,
    )
    .unwrap();
    // Its first 130 frames (4.3 s) keep the test fast; the retrieval still
    // reaches the lunge where the spikes were.
    m.poses.truncate(130);
    let raw = run(&ch, &m, DeformMode::None);
    let def = Deformer::new(&ch, DeformMode::Part, &DeformOptions::default()).unwrap();
    let mut ws = def.workspace();
    let mut out = vec![[0.0; 3]; n];
    let mut worst = (0.0, 0, 0, 0.0);
    for f in 96..120.min(raw.report.frames) {
        let src = &raw.positions[f * n..(f + 1) * n];
        let t = def.deform(
            &ch,
            src,
            &ch.rig().frame_joints(src),
            &raw.query[f],
            &mut out,
            &mut ws,
        );
        assert_eq!(t.after, 0, "frame {f}: {t:?}");
        let (r, v, dist) = rt.off_ring(&out);
        if r > worst.0 {
            worst = (r, v, f, dist);
        }
    }
    let (r, v, f, dist) = worst;
    eprintln!(
        "131_01 on samba, frames 96-119: worst vertex {v} in frame {f}, {r:.2} edge lengths \
         ({:.1} cm) off its ring; captured up to {captured:.2}",
        100.0 * dist
    );
    assert!(captured > 0.5 && captured < 2.0, "captured {captured}");
    assert!(
        r <= line,
        "vertex {v} in frame {f}: {r:.1} edge lengths ({:.1} cm) off its ring, line {line:.1}",
        100.0 * dist
    );
}

/// The real samba capture with its vertices in reverse order (and its
/// triangles, each turned to start elsewhere): the same surface, another
/// numbering, so another order of every region's unknowns and of the
/// solver's elimination. Its chin landmark is renumbered with it. Made once
/// per test binary.
pub(crate) fn reversed_samba_db(d: &std::path::Path) -> std::path::PathBuf {
    use std::sync::OnceLock;
    use surfmotion::mesh::io::{obj, pc2};
    static DB: OnceLock<std::path::PathBuf> = OnceLock::new();
    DB.get_or_init(|| {
        let dir = common::fixture_dir("deform-samba-reversed");
        let mesh = obj::read_obj(&d.join("4d/samba/samba.obj")).unwrap();
        let cache = pc2::read_pc2(&d.join("4d/samba/samba.pc2")).unwrap();
        let n = mesh.positions().len() as u32;
        let new = |v: u32| n - 1 - v;
        let tris: Vec<[u32; 3]> = mesh
            .triangles()
            .iter()
            .rev()
            .map(|t| [new(t[1]), new(t[2]), new(t[0])])
            .collect();
        let rev = |p: &[[f64; 3]]| p.iter().rev().copied().collect::<Vec<_>>();
        let m = surfmotion::mesh::Mesh::new(rev(mesh.positions()), tris).unwrap();
        obj::write_obj(&m, None, &dir.join("samba.obj")).unwrap();
        let frames: Vec<[f64; 3]> = cache.positions.chunks(n as usize).flat_map(rev).collect();
        pc2::write_pc2(n as usize, &frames, &dir.join("samba.pc2")).unwrap();
        let fixture = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures/samba.landmarks.json");
        let mut marks: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(fixture).unwrap()).unwrap();
        let chin = marks["chin"].as_u64().unwrap() as u32;
        marks["chin"] = serde_json::json!(new(chin));
        std::fs::write(dir.join("marks.json"), marks.to_string()).unwrap();
        let db = dir.join("db");
        common::run_ok(
            std::process::Command::new(common::bin())
                .args(["db", "init", db.to_str().unwrap(), "--mesh"])
                .arg(dir.join("samba.obj"))
                .arg("--sequence")
                .arg(format!("dance={}", dir.join("samba.pc2").display()))
                .arg("--landmarks")
                .arg(dir.join("marks.json")),
        );
        // Its graph built and cached once here, not by two tests loading
        // it at once (`tools::surface_crumple` uses it too).
        Character::load(&db, &surfmotion::db::Quiet).unwrap();
        db
    })
    .clone()
}

/// The regions solved level by level, a level's regions on several
/// threads at once (`DeformOptions::parallel_regions`, the default since
/// session 28), give the sequential solve's frames bit for bit, repair
/// included, and each region's own result too: on the real samba capture,
/// on it with its vertices renumbered in reverse, and on the synthetic
/// database; frames of a walk (CMU 02_02) and of kicks and lunges
/// (131_01, the repair's hardest), retrieved and interpolated as
/// `retarget` retrieves them. The levels must be in use (4 of them: torso;
/// head, upper arms, thighs; forearms, shins; feet), and a configuration
/// that reads results in solve order (`parent_seams` off) is solved in
/// order.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn regions_solved_by_level_in_parallel_equal_the_sequential_solve_bit_for_bit() {
    let Some(d) = common::data_dir() else { return };
    let dbs = [
        ("samba", samba_capture_db(&d)),
        ("samba reversed", reversed_samba_db(&d)),
        ("synthetic", common::synthetic_db(&d)),
    ];
    let bits =
        |p: &[[f64; 3]]| -> Vec<[u64; 3]> { p.iter().map(|x| x.map(f64::to_bits)).collect() };
    let mut compared = 0;
    for (name, db) in dbs {
        let ch = Character::load(&db, &surfmotion::db::Quiet).unwrap();
        let n = ch.n();
        let par = Deformer::new(&ch, DeformMode::Part, &DeformOptions::default()).unwrap();
        let seq_opts = DeformOptions {
            parallel_regions: false,
            ..Default::default()
        };
        let seq = Deformer::new(&ch, DeformMode::Part, &seq_opts).unwrap();
        assert_eq!(par.levels(), Some(4), "{name}: the levels are not in use");
        assert_eq!(seq.levels(), None, "{name}");
        let in_order = DeformOptions {
            parent_seams: false,
            ..Default::default()
        };
        let old = Deformer::new(&ch, DeformMode::Part, &in_order).unwrap();
        assert_eq!(
            old.levels(),
            None,
            "{name}: the last result's seams need the order"
        );
        let (mut wp, mut ws) = (par.workspace(), seq.workspace());
        let (mut a, mut b) = (vec![[0.0; 3]; n], vec![[0.0; 3]; n]);
        for clip in ["cmu-amc/02/02_02.amc", "cmu-bvh/131_01.bvh"] {
            let m = load_mocap(&d.join("mocap").join(clip), &Default::default(), 30.0).unwrap();
            let raw = run(&ch, &m, DeformMode::None);
            let mut repaired = 0;
            for k in (0..raw.report.frames).step_by(9) {
                let src = &raw.positions[k * n..(k + 1) * n];
                let sp = ch.rig().frame_joints(src);
                let ca = par.deform(&ch, src, &sp, &raw.query[k], &mut a, &mut wp);
                let cb = seq.deform(&ch, src, &sp, &raw.query[k], &mut b, &mut ws);
                assert_eq!(ca, cb, "{name} {clip} frame {k}: turned-over counts");
                assert!(
                    bits(&a) == bits(&b),
                    "{name} {clip} frame {k}: frames differ"
                );
                let (ra, rb) = (
                    par.region_results(&raw.query[k], &wp),
                    seq.region_results(&raw.query[k], &ws),
                );
                for (x, y) in ra.iter().zip(&rb) {
                    assert!(
                        bits(&x.positions) == bits(&y.positions),
                        "{name} {clip} frame {k}: region {:?} differs",
                        x.joint
                    );
                }
                repaired += usize::from(ca.before > 0);
                compared += 1;
            }
            eprintln!("{name} {clip}: frames equal bit for bit, {repaired} of them repaired");
        }
    }
    assert!(compared >= 30, "{compared} frames compared");
}
