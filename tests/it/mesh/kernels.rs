//! Geometry kernels on real data, against libigl where a peer value exists.

use crate::common;

use glam::DVec3;
use surfmotion::mesh::blend::{Blender, linear_blend};
use surfmotion::mesh::frames::RestFrames;
use surfmotion::mesh::harmonic::Harmonic;
use surfmotion::mesh::io::{LoadOptions, load_sequence, obj::read_obj};
use surfmotion::mesh::laplacian::{cotan_triplets, mul, to_rows};
use surfmotion::mesh::measure::distortion;
use surfmotion::mesh::poisson::Poisson;
use surfmotion::mesh::{Mesh, MeshSequence};

fn seq(d: &std::path::Path, name: &str) -> MeshSequence {
    load_sequence(
        d.join(format!("4d/{name}/{name}.pc2")).to_str().unwrap(),
        &LoadOptions::default(),
    )
    .unwrap()
}

fn json(d: &std::path::Path, f: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(d.join("reference").join(f)).unwrap()).unwrap()
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn cotan_laplacian_matches_libigl_on_samba() {
    let Some(d) = common::data_dir() else { return };
    let r = json(&d, "cotan_samba.json");
    let m = read_obj(&d.join("4d/samba/samba.obj")).unwrap();
    let rows = to_rows(m.vertex_count(), cotan_triplets(&m));
    let nnz: usize = rows.iter().map(Vec::len).sum();
    assert_eq!(nnz as u64, r["nnz"].as_u64().unwrap());
    let diag: f64 = rows
        .iter()
        .enumerate()
        .map(|(i, row)| row.iter().find(|x| x.0 as usize == i).unwrap().1)
        .sum();
    let want = r["diagonal_sum"].as_f64().unwrap();
    assert!(
        (diag - want).abs() < 1e-6 * want.abs(),
        "diagonal sum {diag} vs {want}"
    );
    let x: Vec<[f64; 3]> = m.positions().to_vec();
    let lv = mul(&rows, &x);
    let refv = r["L_times_positions"].as_array().unwrap();
    let scale = refv
        .iter()
        .flat_map(|v| (0..3).map(move |k| v[k].as_f64().unwrap().abs()))
        .fold(0.0, f64::max);
    let mut worst = 0.0f64;
    for (a, b) in lv.iter().zip(refv) {
        for k in 0..3 {
            worst = worst.max((a[k] - b[k].as_f64().unwrap()).abs());
        }
    }
    eprintln!(
        "L·V: max |Δ| = {worst:.3e}, relative to max |L·V| {scale:.3e}: {:.3e}",
        worst / scale
    );
    assert!(
        worst <= 1e-6 * scale,
        "L·V differs by {worst} (scale {scale})"
    );
    // Invariants: rows sum to zero, symmetric.
    for (i, row) in rows.iter().enumerate() {
        let s: f64 = row.iter().map(|x| x.1).sum();
        assert!(s.abs() < 1e-9, "row {i} sums to {s}");
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn harmonic_fields_match_libigl_on_armadillo() {
    let Some(d) = common::data_dir() else { return };
    let r = json(&d, "harmonic_armadillo.json");
    let m = read_obj(&d.join("scans/armadillo/armadillo.obj")).unwrap();
    let b: Vec<u32> = r["boundary_vertices"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as u32)
        .collect();
    let vals: Vec<[f64; 4]> = r["boundary_values"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| std::array::from_fn(|k| v[k].as_f64().unwrap()))
        .collect();
    let h = Harmonic::new(&m, &b).unwrap();
    let mut ws = h.workspace::<4>();
    let mut out = vec![[0.0; 4]; m.vertex_count()];
    h.solve(&vals, &mut out, &mut ws);
    let field = r["field"].as_array().unwrap();
    let mut worst = 0.0f64;
    for (a, f) in out.iter().zip(field) {
        for k in 0..4 {
            worst = worst.max((a[k] - f[k].as_f64().unwrap()).abs());
        }
    }
    eprintln!("harmonic: max |Δ| = {worst:.3e}");
    assert!(worst < 1e-6, "harmonic field differs by {worst}");
    // It reproduces its boundary values exactly and stays within their range (maximum principle).
    for (k, &v) in b.iter().enumerate() {
        assert_eq!(out[v as usize], vals[k]);
    }
    for c in 0..4 {
        let (lo, hi) = vals
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(v[c]), h.max(v[c])));
        assert!(out.iter().all(|o| o[c] >= lo - 1e-9 && o[c] <= hi + 1e-9));
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn poisson_reconstructs_real_frames_from_their_own_gradients() {
    let Some(d) = common::data_dir() else { return };
    for (name, f) in [("samba", 60), ("crane", 100)] {
        let s = seq(&d, name);
        let m = s.mesh();
        let poisson = Poisson::new(m).unwrap();
        let g = RestFrames::new(m.positions(), m.triangles()).gradients(s.frame(f), m.triangles());
        let mut ws = poisson.workspace();
        let mut out = vec![[0.0; 3]; m.vertex_count()];
        poisson.reconstruct(&g, &mut ws, &mut out);
        let target = s.frame(f);
        let a = poisson.anchors()[0] as usize;
        let shift = DVec3::from_array(out[a]) - DVec3::from_array(target[a]);
        let worst = out
            .iter()
            .zip(target)
            .map(|(o, t)| (DVec3::from_array(*o) - shift - DVec3::from_array(*t)).length())
            .fold(0.0, f64::max);
        let diag = s.bounds().diagonal();
        eprintln!(
            "{name} frame {f}: reconstruction error {:.2e} of the diagonal",
            worst / diag
        );
        assert!(worst < 1e-5 * diag);
    }
}

fn blend_quality(d: &std::path::Path, name: &str, f: usize) -> (f64, f64, f64, f64) {
    let s = seq(d, name);
    let m: &Mesh = s.mesh();
    let b = Blender::new(m).unwrap();
    let mut ws = b.workspace();
    let (ga, gb) = (
        b.decompose(s.frame(0), &mut ws),
        b.decompose(s.frame(f), &mut ws),
    );
    let mut nl = vec![[0.0f64; 3]; m.vertex_count()];
    b.blend(&ga, &gb, 0.5, &mut nl, &mut ws);
    let lin = linear_blend(s.frame(0), s.frame(f), 0.5);
    let dn = distortion(m, s.frame(0), s.frame(f), &nl);
    let dl = distortion(m, s.frame(0), s.frame(f), &lin);
    eprintln!(
        "{name} 0/{f} α=0.5: edge-length distortion non-linear {:.4} vs linear {:.4}; volume {:.4} vs {:.4}",
        dn.edge_length, dl.edge_length, dn.volume, dl.volume
    );
    // Endpoints and identity on real data.
    let diag = s.bounds().diagonal();
    for (alpha, want) in [(0.0, s.frame(0)), (1.0, s.frame(f))] {
        b.blend(&ga, &gb, alpha, &mut nl, &mut ws);
        let e = nl
            .iter()
            .zip(want)
            .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
            .fold(0.0, f64::max);
        assert!(e < 1e-5 * diag, "{name}: α={alpha} off by {e}");
    }
    b.blend(&gb, &gb, 0.3, &mut nl, &mut ws);
    let e = nl
        .iter()
        .zip(s.frame(f))
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0, f64::max);
    assert!(e < 1e-5 * diag, "{name}: G(M, M) off by {e}");
    (dn.edge_length, dl.edge_length, dn.volume, dl.volume)
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn nonlinear_blend_preserves_shape_better_than_linear() {
    let Some(d) = common::data_dir() else { return };
    for (name, f) in [("samba", 60), ("crane", 100)] {
        let (en, el, vn, vl) = blend_quality(&d, name, f);
        assert!(
            en < el,
            "{name}: edge distortion {en} not below linear {el}"
        );
        assert!(
            vn < vl,
            "{name}: volume distortion {vn} not below linear {vl}"
        );
    }
}
