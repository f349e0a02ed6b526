//! Bodies for the automatic rig's branch and partial-body tests
//! (`embed::auto_branches`, `embed::auto_headless`): a body driven by the
//! procedural turn through its rig, its variants (mirrored, turned Z-up,
//! in centimetres), a tube grafted on (a tail, a third arm), the hands or
//! any set of vertices cut off, a scan driven through its fixture's
//! landmarks, and the rig as `db init` makes it.

use super::auto::Variant;
use glam::DVec3;
use std::path::Path;
use surfmotion::embed::Embedding;
use surfmotion::embed::auto::options::{AutoError, AutoOptions, automatic_setup};
use surfmotion::embed::auto::report::AutoRig;
use surfmotion::embed::auto::rig::auto_rig;
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::embed::rest::choose_rest_frame;
use surfmotion::mesh::Mesh;
use surfmotion::tools::autorig::used_vertices_only;

pub(super) type Frames = Vec<Vec<[f64; 3]>>;

/// `rest` driven through the rig of `lm` by the procedural turn (2 s at
/// 30 frames a second); the rig too.
pub(super) fn driven(rest: &Mesh, lm: &Landmarks) -> (Frames, Embedding) {
    let rig = Embedding::new(rest, lm, None).unwrap();
    (super::auto_order::turn_frames(rest, &rig, 2.0), rig)
}

/// Variant `v` of a mesh and its frames (mirrored: triangles reversed).
pub(super) fn variant(v: Variant, mesh: &Mesh, frames: &Frames) -> (Mesh, Frames) {
    let mut tris = mesh.triangles().to_vec();
    if v == Variant::Mirrored {
        tris.iter_mut().for_each(|t| t.swap(1, 2));
    }
    let moved = |f: &[[f64; 3]]| f.iter().map(|p| v.point(*p)).collect::<Vec<_>>();
    let m = Mesh::new(moved(mesh.positions()), tris).unwrap();
    (m, frames.iter().map(|f| moved(f)).collect())
}

/// The automatic rig as `db init` makes it (its rules, its rest frame).
pub(super) fn rig_as_db_init(mesh: &Mesh, frames: &Frames) -> Result<AutoRig, AutoError> {
    rig_with(mesh, frames, |_| {})
}

/// [`rig_as_db_init`] with `set` applied to `db init`'s options.
pub(super) fn rig_with(
    mesh: &Mesh,
    frames: &Frames,
    set: impl Fn(&mut AutoOptions),
) -> Result<AutoRig, AutoError> {
    let f: Vec<&[[f64; 3]]> = frames.iter().map(Vec::as_slice).collect();
    let mut all = vec![mesh.positions()];
    all.extend_from_slice(&f);
    let (rule, mut auto) = automatic_setup(&AutoOptions::default()).unwrap();
    set(&mut auto);
    let choice = choose_rest_frame(mesh, &all, &rule).unwrap();
    let opts = AutoOptions {
        rest_frame: (choice.frame > 0).then(|| choice.frame - 1),
        ..auto
    };
    auto_rig(mesh, &f, &opts)
}

/// A vertex near the body's mid-plane (x = 0; +Y up, facing +Z) at
/// `frac` of the height: the backmost (`front` false) or the frontmost.
pub(super) fn mid_vertex(mesh: &Mesh, frac: f64, front: bool) -> u32 {
    let p = mesh.positions();
    let (lo, hi) = p
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), q| (a.min(q[1]), b.max(q[1])));
    let (h, y) = (hi - lo, lo + frac * (hi - lo));
    let near = |q: &[f64; 3]| (q[1] - y).abs() < 0.03 * h && q[0].abs() < 0.04 * h;
    let key = |q: &[f64; 3]| if front { q[2] } else { -q[2] };
    (0..p.len())
        .filter(|&v| near(&p[v]))
        .max_by(|&a, &b| key(&p[a]).total_cmp(&key(&p[b])))
        .unwrap() as u32
}

/// `mesh` with a tube grown at vertex `at`: the triangles within two
/// edge rings of it removed, a tube from the hole's rim along `dir`,
/// `length` long, narrowing to 40 %, closed at its end; the vertices left
/// unused dropped.
pub(super) fn graft(mesh: &Mesh, at: u32, dir: DVec3, length: f64) -> Mesh {
    let tris = mesh.triangles();
    let touches = |t: &[u32; 3], s: &[u32]| t.iter().any(|v| s.contains(v));
    let mut patch = vec![at];
    for _ in 0..2 {
        let ring: Vec<u32> = tris
            .iter()
            .filter(|t| touches(t, &patch))
            .flatten()
            .copied()
            .collect();
        patch.extend(ring);
        patch.sort_unstable();
        patch.dedup();
    }
    // The patch's inner vertices: all their triangles in it.
    let inner: Vec<u32> = patch
        .iter()
        .copied()
        .filter(|&v| {
            tris.iter()
                .filter(|t| t.contains(&v))
                .all(|t| t.iter().all(|u| patch.contains(u)))
        })
        .collect();
    let (cut, mut kept): (Vec<[u32; 3]>, Vec<[u32; 3]>) =
        tris.iter().partition(|t| touches(t, &inner));
    // The rim: the cut triangles' edges not shared between two of them,
    // in their direction.
    let edges: Vec<(u32, u32)> = cut
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .collect();
    let rim: Vec<(u32, u32)> = edges
        .iter()
        .copied()
        .filter(|&(a, b)| !edges.contains(&(b, a)))
        .collect();
    let mut ring = vec![rim[0].0];
    while let Some(&(_, b)) = rim.iter().find(|e| e.0 == *ring.last().unwrap()) {
        if b == ring[0] {
            break;
        }
        ring.push(b);
    }
    let mut pos = mesh.positions().to_vec();
    let at3 = |v: u32| DVec3::from_array(mesh.positions()[v as usize]);
    let centre = ring.iter().map(|&v| at3(v)).sum::<DVec3>() / ring.len() as f64;
    let k = ring.len();
    let steps = 12;
    let mut prev = ring.clone();
    for s in 1..=steps {
        let f = s as f64 / steps as f64;
        let cur: Vec<u32> = ring
            .iter()
            .map(|&v| {
                let q = centre + (at3(v) - centre) * (1.0 - 0.6 * f) + dir * (length * f);
                pos.push(q.to_array());
                (pos.len() - 1) as u32
            })
            .collect();
        for j in 0..k {
            let (p0, p1, c0, c1) = (prev[j], prev[(j + 1) % k], cur[j], cur[(j + 1) % k]);
            kept.push([p0, p1, c0]);
            kept.push([p1, c1, c0]);
        }
        prev = cur;
    }
    pos.push((centre + dir * (length * 1.05)).to_array());
    let tip = (pos.len() - 1) as u32;
    for j in 0..k {
        kept.push([prev[j], prev[(j + 1) % k], tip]);
    }
    used_vertices_only(&Mesh::new(pos, kept).unwrap()).unwrap()
}

/// The vertices of `rig`'s mesh left when the hands are cut: those of
/// the forearm parts beyond their wrist (1 % of the height on) go.
pub(super) fn without_hands(rig: &Embedding, rest: &[[f64; 3]]) -> Vec<bool> {
    use surfmotion::embed::parts::Part;
    use surfmotion::rig::Canonical as C;
    let j = |c: C| DVec3::from_array(rig.joints()[c.index()]);
    let arms = [
        (j(C::LElbow), j(C::LWrist), Part::LForearm.index()),
        (j(C::RElbow), j(C::RWrist), Part::RForearm.index()),
    ];
    (0..rest.len())
        .map(|v| {
            let q = DVec3::from_array(rest[v]);
            let part = rig.labels()[v] as usize;
            !arms.iter().any(|(e, w, arm)| {
                part == *arm && (q - *w).dot((*w - *e).normalize()) > 0.01 * rig.height()
            })
        })
        .collect()
}

/// Which vertices of `rest` to keep to cut `rig`'s feet off at the
/// ankles: a plane square to each shin, `above` of the height up the shin
/// from the ankle; the shin's and foot's vertices below it go.
pub(super) fn without_feet(rig: &Embedding, rest: &[[f64; 3]], above: f64) -> Vec<bool> {
    without_feet_of(rig, rest, above, [true, true])
}

/// [`without_feet`] on the legs `sides` says (left, right) only.
pub(super) fn without_feet_of(
    rig: &Embedding,
    rest: &[[f64; 3]],
    above: f64,
    sides: [bool; 2],
) -> Vec<bool> {
    use surfmotion::embed::parts::Part;
    use surfmotion::rig::Canonical as C;
    let j = |c: C| DVec3::from_array(rig.joints()[c.index()]);
    let legs: Vec<_> = [
        (j(C::LKnee), j(C::LAnkle), [Part::LShin, Part::LFoot]),
        (j(C::RKnee), j(C::RAnkle), [Part::RShin, Part::RFoot]),
    ]
    .into_iter()
    .zip(sides)
    .filter_map(|(leg, cut)| cut.then_some(leg))
    .collect();
    (0..rest.len())
        .map(|v| {
            let q = DVec3::from_array(rest[v]);
            let part = rig.labels()[v] as usize;
            !legs.iter().any(|(k, a, parts)| {
                parts.iter().any(|p| p.index() == part)
                    && (q - *a).dot((*k - *a).normalize()) < above * rig.height()
            })
        })
        .collect()
}

/// `mesh` and its frames with only the triangles whose corners are all
/// `keep`, and the vertices they use; and those vertices' old numbers.
pub(super) fn keep_only(mesh: &Mesh, frames: &Frames, keep: &[bool]) -> (Mesh, Frames, Vec<usize>) {
    let (m, old) = mesh.keep_vertices(keep).unwrap();
    let f = frames
        .iter()
        .map(|f| old.iter().map(|&v| f[v]).collect())
        .collect();
    (m, f, old)
}

/// The scan `file` (its `group`, the vertices it uses), its fixture's
/// landmarks and the frames of the procedural turn through their rig.
pub(super) fn scan_driven(
    d: &Path,
    file: &str,
    group: Option<&str>,
    fixture: &str,
) -> (Mesh, Frames, Embedding) {
    use surfmotion::mesh::io::{LoadOptions, load_sequence};
    let seq = load_sequence(d.join(file).to_str().unwrap(), &LoadOptions::default()).unwrap();
    let whole = match group {
        Some(g) => seq.mesh().select_groups(&[g.to_string()]).unwrap(),
        None => seq.mesh().clone(),
    };
    let mesh = used_vertices_only(&whole).unwrap();
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(format!("tests/fixtures/{fixture}.landmarks.json"));
    let lm = Landmarks::load(&path, mesh.vertex_count()).unwrap();
    let (frames, rig) = driven(&mesh, &lm);
    (mesh, frames, rig)
}
