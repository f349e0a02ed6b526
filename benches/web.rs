//! The web viewer's geometry codec and export on real data: encoding samba
//! (175 frames × 9,971 vertices) at the default 1 mm bound and DEFLATE
//! levels 3 and 6, decoding it (the Rust decoder; the page's is timed by
//! `tests/web.rs`), and `web export` of a 1,050-frame database (samba's
//! capture six times, graph cache warm). No solve is involved, so the
//! figures are bare times next to the raw float32 size.

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
    // The first export builds the graph cache; the timed ones read it.
    web::export_db(&big, &site, &ExportOptions::default()).unwrap();
    grp.bench_function("export_1050_frames", |b| {
        b.iter(|| web::export_db(&big, &site, &ExportOptions::default()).unwrap())
    });
    grp.finish();
    c.final_summary();
}
