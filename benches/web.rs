//! The web viewer's geometry codec and export on real data: encoding samba
//! (175 frames × 9,971 vertices) at the default 1 mm bound and DEFLATE
//! levels 3 and 6, decoding it (the Rust decoder; the page's is timed by
//! `tests/it/web/mod.rs`), and `web export` of a 1,050-frame database (samba's
//! capture six times, graph cache warm; `--linear-transitions`, the
//! precomputed non-linear windows timed once apart, and their blend alone
//! per window frame as a ratio to the sparse-solve floor). The geometry
//! figures involve no solve: bare times next to the raw float32 size. It also prints the
//! other candidate measured for the README: per-sequence PCA of the vertex
//! trajectories (snapshot method), the fewest components whose
//! reconstruction keeps every vertex within 1 mm before any quantisation,
//! and the size that basis and coefficients take at 16 bits.

#[path = "common/mod.rs"]
mod common;

use criterion::Criterion;
use std::hint::black_box;
use surfmotion::web::{self, EncodeOptions, ExportOptions, codec};

fn main() {
    let Some(d) = common::data() else {
        eprintln!("benchmark skipped: no ../shared/data");
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let samba = d.join("4d/samba");
    let db = |name: &str, copies: usize| {
        let dir = tmp.path().join(name);
        std::fs::create_dir_all(&dir).unwrap();
        let mut t = format!(
            "name = \"{name}\"\ntopology = \"{}\"\n",
            samba.join("samba.obj").display()
        );
        for i in 0..copies {
            t += &format!(
                "[[sequence]]\nname = \"dance{i}\"\npath = \"{}\"\n",
                samba.join("samba.pc2").display()
            );
        }
        std::fs::write(dir.join("character.toml"), t).unwrap();
        dir
    };
    let one = db("samba", 1);
    let big = db("samba6", 6);
    let (_, g, _) = web::load_db_geometry(&one).unwrap();
    pca_candidate(&g.sequences[0], g.vertices, 1e-3);
    let mut c = Criterion::default().configure_from_args();
    let mut grp = c.benchmark_group("web");
    grp.sample_size(10);
    for level in [3, 6] {
        let o = EncodeOptions {
            level,
            ..EncodeOptions::default()
        };
        let (bytes, rep) = codec::encode(&g, &o).unwrap();
        eprintln!(
            "samba level {level}: {} bytes ({:.1} KB/frame), max error {:.3} mm",
            bytes.len(),
            bytes.len() as f64 / 1e3 / 175.0,
            rep.max_error * 1e3
        );
        grp.bench_function(format!("encode_samba_level{level}"), |b| {
            b.iter(|| codec::encode(black_box(&g), &o).unwrap())
        });
        grp.bench_function(format!("decode_samba_level{level}"), |b| {
            b.iter(|| codec::decode(black_box(&bytes)).unwrap())
        });
    }
    let site = tmp.path().join("site");
    // The first export builds the graph cache and precomputes the
    // transitions' non-linear windows (the default; timed once, it takes
    // a solve per window frame); the timed ones read the cache and leave
    // the windows to the page's linear blend.
    let r = web::export_db(&big, &site, &ExportOptions::default()).unwrap();
    eprintln!(
        "samba6 export with non-linear windows: {:.1} s, {} transitions, {} window frames blended in {:.1} s, {} of {} bytes",
        r.seconds,
        r.transitions,
        r.transition_frames,
        r.transition_seconds,
        r.transition_bytes,
        r.geometry.bytes
    );
    // The windows' blend alone (each database frame decomposed once, one
    // prefactored solve per window frame): per window frame and as a ratio
    // to the sparse-solve floor (ARCHITECTURE.md: 0.74 ms per 3-column
    // solve at 10K vertices).
    let (_, g6, graph6) = web::load_db_geometry(&big).unwrap();
    let table = web::export::transition_table(&graph6, &g6);
    let frames: usize = table.iter().map(|t| 2 * t.window + 1).sum();
    let t = std::time::Instant::now();
    web::blend_windows(&g6, &table, &Default::default()).unwrap();
    let per = t.elapsed().as_secs_f64() * 1e3 / frames as f64;
    eprintln!(
        "samba6 windows: {} transitions, {frames} frames, {:.2} ms per window frame on {} threads = {:.1}x the 0.74 ms solve floor",
        table.len(),
        per,
        rayon::current_num_threads(),
        per / 0.74
    );
    let part = &table[..table.len().min(24)];
    grp.bench_function("blend_windows_samba6_24_transitions", |b| {
        b.iter(|| web::blend_windows(black_box(&g6), part, &Default::default()).unwrap())
    });
    let linear = ExportOptions {
        linear_transitions: true,
        ..ExportOptions::default()
    };
    grp.bench_function("export_1050_frames_linear_transitions", |b| {
        b.iter(|| web::export_db(&big, &site, &linear).unwrap())
    });
    grp.finish();
    c.final_summary();
}

/// The PCA candidate: trajectories `X` (3V × F, mean frame removed), the
/// eigenvectors `v_k` of `XᵀX` (F × F), reconstruction `X V_k V_kᵀ`; prints
/// the smallest `k` whose maximum vertex error is within `bound`.
fn pca_candidate(seq: &[[f32; 3]], n: usize, bound: f64) {
    let f = seq.len() / n;
    let rows = 3 * n;
    let mut mean = vec![0f64; rows];
    for t in 0..f {
        for v in 0..n {
            for c in 0..3 {
                mean[3 * v + c] += seq[t * n + v][c] as f64 / f as f64;
            }
        }
    }
    let x: Vec<Vec<f64>> = (0..f)
        .map(|t| {
            (0..rows)
                .map(|r| seq[t * n + r / 3][r % 3] as f64 - mean[r])
                .collect()
        })
        .collect();
    let gram = nalgebra::DMatrix::from_fn(f, f, |a, b| {
        x[a].iter().zip(&x[b]).map(|(p, q)| p * q).sum::<f64>()
    });
    let eig = nalgebra::SymmetricEigen::new(gram);
    let mut order: Vec<usize> = (0..f).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let mut rec = vec![vec![0f64; rows]; f];
    for (k, &j) in order.iter().enumerate() {
        let v = eig.eigenvectors.column(j);
        // basis column u = X v (unnormalised); frame t gains u · v[t].
        let mut u = vec![0f64; rows];
        for t in 0..f {
            for r in 0..rows {
                u[r] += x[t][r] * v[t];
            }
        }
        for t in 0..f {
            for r in 0..rows {
                rec[t][r] += u[r] * v[t];
            }
        }
        let worst = (0..f)
            .flat_map(|t| (0..n).map(move |vv| (t, vv)))
            .map(|(t, vv)| {
                (0..3)
                    .map(|c| (rec[t][3 * vv + c] - x[t][3 * vv + c]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .fold(0.0, f64::max);
        if worst <= bound || k + 1 == f {
            eprintln!(
                "PCA candidate: {} of {f} components for max vertex error {:.3} mm; basis + coefficients at 16 bits: {} KB (before entropy coding, before quantisation error)",
                k + 1,
                worst * 1e3,
                (k + 1) * (rows + f) * 2 / 1000
            );
            return;
        }
    }
}
