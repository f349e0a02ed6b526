//! Never a panic on input: every reader gets truncated real files, flipped
//! bytes, random bytes and absurd header counts, and must return (Ok or a
//! typed error) promptly. The cargo-fuzz targets in fuzz/ explore further;
//! this is the quick corpus run of the normal suite.

use crate::common;

use proptest::prelude::*;
use std::path::Path;
use surfmotion::mesh::io::{gltf, mdd, obj, pc2, ply};
use surfmotion::mocap::asfamc::{AmcOptions, parse_amc, parse_asf};
use surfmotion::mocap::bvh::{BvhOptions, parse_bvh};

type Reader = fn(&[u8]);

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn readers() -> Vec<(&'static str, Reader)> {
    vec![
        ("bvh", |b| {
            drop(parse_bvh(
                &text(b),
                Path::new("f.bvh"),
                &BvhOptions::default(),
            ))
        }),
        ("asf", |b| drop(parse_asf(&text(b), Path::new("f.asf")))),
        ("amc", |b| {
            if let Ok(skel) = parse_asf(TINY_ASF, Path::new("t.asf")) {
                drop(parse_amc(
                    &text(b),
                    Path::new("f.amc"),
                    &skel,
                    &AmcOptions::default(),
                ));
            }
        }),
        ("obj", |b| {
            drop(obj::parse_obj(&text(b), Path::new("f.obj")))
        }),
        ("ply", |b| drop(ply::parse_ply(b, Path::new("f.ply")))),
        ("pc2", |b| drop(pc2::parse_pc2(b, Path::new("f.pc2")))),
        ("mdd", |b| drop(mdd::parse_mdd(b, Path::new("f.mdd")))),
        ("gltf", |b| drop(gltf::parse_gltf(b, Path::new("f.glb")))),
        ("landmarks", |b| {
            drop(surfmotion::embed::landmarks::Landmarks::parse(
                &text(b),
                Path::new("f.json"),
                100,
            ))
        }),
        ("markers", |b| {
            drop(surfmotion::transfer::MarkerFile::parse(
                &text(b),
                Path::new("m.json"),
                100,
            ))
        }),
        ("parts", |b| {
            let tris = [[0u32, 1, 2], [0, 2, 3]];
            drop(surfmotion::embed::parse_parts(
                &text(b),
                Path::new("p.json"),
                &tris,
                4,
            ))
        }),
        // Session 8: the readers the fuzz targets cover and this run did
        // not (fuzz/fuzz_targets/{rigmap,sm4d,script,motion,embedding,cache}.rs).
        ("rigmap", |b| {
            drop(serde_json::from_str::<surfmotion::rig::RigMap>(&text(b)))
        }),
        ("sm4d", |b| drop(surfmotion::web::codec::decode(b))),
        ("script", |b| {
            use surfmotion::parametric::Parameter;
            let spaces: [(&str, &[Parameter]); 1] =
                [("locomotion", &[Parameter::Speed, Parameter::Turn])];
            drop(surfmotion::parametric::script::parse_script_for(
                &text(b),
                Path::new("s.json"),
                &spaces,
            ))
        }),
        ("motion", |b| {
            let mesh = surfmotion::mesh::Mesh::new(
                vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                vec![[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]],
            )
            .unwrap();
            let key = b
                .get(8..16)
                .map_or(0, |k| u64::from_le_bytes(k.try_into().unwrap()));
            drop(surfmotion::parametric::store::parse(
                b,
                key,
                &mesh,
                &Default::default(),
            ))
        }),
        ("embedding", |b| {
            drop(surfmotion::embed::Embedding::parse(
                &text(b),
                Path::new("rig.json"),
                4,
            ))
        }),
        ("manifest", |b| {
            if let Ok(m) = toml::from_str::<surfmotion::db::Manifest>(&text(b)) {
                let _ = m.validate();
            }
        }),
        // Sampled at 1 fps: a flipped take length must not make a run of
        // hours (the reader's own limit is 200 million samples).
        ("fbx", |b| {
            drop(surfmotion::mocap::fbx::parse_fbx(
                b,
                Path::new("f.fbx"),
                &surfmotion::mocap::fbx::FbxOptions {
                    fps: Some(1.0),
                    take: None,
                },
            ))
        }),
        // The glTF clip reader (skin + animation as a clip), at 1 fps too.
        ("gltf-clip", |b| {
            drop(surfmotion::mesh::io::gltf::clip::parse_gltf_clip(
                b,
                Path::new("f.glb"),
                &surfmotion::mesh::io::gltf::clip::GltfClipOptions {
                    fps: Some(1.0),
                    take: None,
                },
            ))
        }),
    ]
}

const TINY_ASF: &str = ":units\n length 0.45\n angle deg\n:root\n order TX TY TZ RX RY RZ\n axis XYZ\n position 0 0 0\n orientation 0 0 0\n:bonedata\n begin\n id 1\n name a\n direction 0 1 0\n length 2\n axis 0 0 0 XYZ\n dof rx ry rz\n end\n:hierarchy\n begin\n root a\n end\n";

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

/// Small seeds per format, made in code (real files are added when present).
fn seeds(fmt: &str) -> Vec<Vec<u8>> {
    let bvh = "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n JOINT L\n {\n  OFFSET 1 0 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  End Site\n  {\n   OFFSET 0 1 0\n  }\n }\n}\nMOTION\nFrames: 2\nFrame Time: 0.0333\n0 1 2 3 4 5 6 7 8\n1 2 3 4 5 6 7 8 9\n";
    let mesh = surfmotion::mesh::Mesh::new(
        vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        vec![[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]],
    )
    .unwrap();
    let seq = surfmotion::mesh::MeshSequence::new(
        mesh.clone(),
        [mesh.positions(), mesh.positions()].concat(),
        Some(30.0),
    )
    .unwrap();
    match fmt {
        "bvh" => vec![bvh.into(), bvh.replace("Frames: 2", "Frames: 99999999999").into()],
        "asf" => vec![TINY_ASF.into()],
        "amc" => vec![":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 1 2 3 4 5\na 1 2 3\n2\nroot 0 1 2 3 4 5\na 1 2 3\n".into()],
        "obj" => vec![obj::format_obj(&mesh, None).into_bytes()],
        "ply" => vec![ply::encode_ply(&mesh, None)],
        "pc2" => vec![pc2::encode_pc2(4, seq.all_positions())],
        "mdd" => vec![mdd::encode_mdd(4, seq.all_positions(), 30.0)],
        "gltf" | "gltf-clip" => vec![surfmotion::mesh::io::glb::encode_glb(&seq, None).unwrap()],
        "landmarks" => vec![br#"{"chin": 1, "groin": [0, 1, 0], "l_wrist": 2, "r_wrist": 3, "l_elbow": 4, "r_elbow": 5, "l_knee": 6, "r_knee": [1e308, -0.5, 0]}"#.to_vec()],
        "markers" => vec![br#"{"triangle_count": 100, "markers": [{"name": "l_forearm/0/1", "triangle": 7, "bone": "l_elbow"}, {"name": "x", "triangle": 99}]}"#.to_vec()],
        "parts" => vec![br#"{"torso": [0, 1], "head": [2], "l_shin": [3, 3]}"#.to_vec()],
        "rigmap" => vec![br#"{"convention": "x", "joints": {"pelvis": "Hips", "spine": "Spine", "l_knee": "L"}}"#.to_vec()],
        "sm4d" => vec![[&b"SM4DGEO\0"[..], &[4, 0, 0, 0, 2, 0, 0, 0, 255, 255, 255, 127], &[0u8; 64]].concat()],
        "script" => vec![br#"[{"t": 0, "space": "locomotion", "speed": 1.2}, {"t": 3, "turn": 30}, {"t": 4.5, "speed": -99.5}]"#.to_vec()],
        "motion" => vec![[&b"SMPAR001"[..], &[7u8; 8], &[4, 0, 0, 0, 255, 255, 255, 255], &[0u8; 64]].concat()],
        "embedding" => vec![br#"{"vertex_count": 4, "labels": [0, 1, 2, 3], "skin": [], "regressors": [], "regions": [], "joints": [], "facing": [1, 0, 0], "height": 1.7}"#.to_vec()],
        "fbx" => vec![
            b"Kaydara FBX Binary  \0\x1a\0\xe8\x1c\0\0".to_vec(),
            b"; FBX 7.5.0 project file\nObjects:  {\n Model: 1, \"Model::Hips\", \"LimbNode\" {\n }\n}\n".to_vec(),
        ],
        "manifest" => vec![b"name = \"x\"\ntopology = \"t.obj\"\nfps = 30.0\nunits = \"m\"\nup = \"y\"\n[[sequence]]\nname = \"a\"\npath = \"a.pc2\"\n[rig]\nlandmarks = \"l.json\"\n[graph]\ntop_n = 3\n[[space]]\nname = \"s\"\nsequences = [\"a\"]\nparameters = [\"speed\"]\n".to_vec()],
        _ => vec![],
    }
}

fn real_seeds(fmt: &str) -> Vec<Vec<u8>> {
    let Some(d) = common::optional_data_dir() else {
        return vec![];
    };
    let files: &[&str] = match fmt {
        "bvh" => &[
            "mocap/bandai-namco/dataset-1_run_normal_001.bvh",
            "mocap/cmu-bvh-ccrig/002_03.bvh",
        ],
        "asf" => &["mocap/cmu-amc/02/02.asf"],
        "gltf" | "gltf-clip" => &["gltf/RiggedSimple/RiggedSimple.glb", "gltf/Fox/Fox.glb"],
        "fbx" => &[
            "fbx/ufbx/max_transformed_skin_7500_binary.fbx",
            "fbx/ufbx/maya_game_sausage_7500_ascii_combined.fbx",
        ],
        _ => &[],
    };
    files
        .iter()
        .map(|f| std::fs::read(d.join(f)).unwrap())
        .collect()
}

#[test]
fn truncations_flips_and_noise_never_panic() {
    let mut rng = Rng(0x9E3779B97F4A7C15);
    for (fmt, read) in readers() {
        let mut all = seeds(fmt);
        all.extend(real_seeds(fmt));
        for seed in &all {
            read(seed);
            // Truncations.
            for k in 0..=24 {
                read(&seed[..seed.len() * k / 24]);
            }
            // Byte flips and overwrites with interesting values.
            for _ in 0..300 {
                let mut m = seed.clone();
                for _ in 0..1 + rng.next() % 4 {
                    let i = (rng.next() as usize) % m.len().max(1);
                    if i < m.len() {
                        m[i] = match rng.next() % 5 {
                            0 => 0xff,
                            1 => 0,
                            2 => b'9',
                            3 => b'-',
                            _ => rng.next() as u8,
                        };
                    }
                }
                if std::panic::catch_unwind(|| read(&m)).is_err() {
                    let keep = std::env::temp_dir().join(format!("surfmotion-panic-{fmt}.bin"));
                    std::fs::write(&keep, &m).unwrap();
                    panic!("{fmt} reader panicked; input kept in {}", keep.display());
                }
            }
        }
        // Pure noise.
        for len in [0usize, 1, 7, 12, 32, 33, 100, 4096] {
            let v: Vec<u8> = (0..len).map(|_| rng.next() as u8).collect();
            read(&v);
        }
    }
}

#[test]
fn absurd_counts_are_refused() {
    // PC2 claiming 2^31 - 1 points.
    let mut b = b"POINTCACHE2\0".to_vec();
    for v in [1i32, i32::MAX] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b.extend_from_slice(&0f32.to_le_bytes());
    b.extend_from_slice(&1f32.to_le_bytes());
    b.extend_from_slice(&i32::MAX.to_le_bytes());
    assert!(pc2::parse_pc2(&b, Path::new("x.pc2")).is_err());
    // MDD claiming 2^31 - 1 frames.
    let mut m = i32::MAX.to_be_bytes().to_vec();
    m.extend_from_slice(&i32::MAX.to_be_bytes());
    assert!(mdd::parse_mdd(&m, Path::new("x.mdd")).is_err());
    // PLY element count beyond the data.
    let p = b"ply\nformat binary_little_endian 1.0\nelement vertex 99999999999\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    assert!(ply::parse_ply(p, Path::new("x.ply")).is_err());
    let p = b"ply\nformat ascii 1.0\nelement junk 18446744073709551615\nelement vertex 0\nproperty float x\nend_header\n";
    assert!(ply::parse_ply(p, Path::new("x.ply")).is_err());
    // BVH with a huge frame count in the header but two frames of data: reads the data.
    let bvh = String::from_utf8(seeds("bvh")[1].clone()).unwrap();
    let c = parse_bvh(&bvh, Path::new("x.bvh"), &BvhOptions::default()).unwrap();
    assert_eq!(c.frame_count(), 2);
    assert!(c.warnings()[0].contains("99999999999"));
    // Deep nesting does not overflow the stack.
    let deep = format!(
        "HIERARCHY\nROOT a\n{{\n{}",
        "JOINT b\n{\nOFFSET 0 0 0\n".repeat(200_000)
    );
    assert!(parse_bvh(&deep, Path::new("deep.bvh"), &BvhOptions::default()).is_err());
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, .. ProptestConfig::default() })]

    #[test]
    fn bvh_from_keyword_soup_never_panics(words in proptest::collection::vec(prop_oneof![
        Just("HIERARCHY"), Just("ROOT"), Just("JOINT"), Just("End"), Just("Site"), Just("{"), Just("}"),
        Just("OFFSET"), Just("CHANNELS"), Just("3"), Just("6"), Just("Xrotation"), Just("Yposition"),
        Just("MOTION"), Just("Frames:"), Just("Frame"), Just("Time:"), Just("0.1"), Just("-1e308"), Just("\n"),
        Just("nan"), Just("a"),
    ], 0..80)) {
        let t = words.join(" ");
        let _ = parse_bvh(&t, Path::new("p.bvh"), &BvhOptions::default());
    }

    #[test]
    fn obj_from_line_soup_never_panics(lines in proptest::collection::vec(prop_oneof![
        Just("v 0 0 0"), Just("v 1 2"), Just("v 1 2 3 4 5 6"), Just("f 1 2 3"), Just("f -1 -2 -3"), Just("f 0 1 2"),
        Just("f 1/2/3 4//5 6"), Just("g x"), Just("o"), Just("v nan 0 0"), Just("f 99999999999999999999 1 2"),
    ], 0..40)) {
        let _ = obj::parse_obj(&lines.join("\n"), Path::new("p.obj"));
    }

    #[test]
    fn point_caches_from_random_headers_never_panic(points in any::<i32>(), frames in any::<i32>(), tail in proptest::collection::vec(any::<u8>(), 0..64)) {
        let mut b = b"POINTCACHE2\0".to_vec();
        b.extend_from_slice(&1i32.to_le_bytes());
        b.extend_from_slice(&points.to_le_bytes());
        b.extend_from_slice(&[0; 8]);
        b.extend_from_slice(&frames.to_le_bytes());
        b.extend_from_slice(&tail);
        let _ = pc2::parse_pc2(&b, Path::new("p.pc2"));
        let mut m = frames.to_be_bytes().to_vec();
        m.extend_from_slice(&points.to_be_bytes());
        m.extend_from_slice(&tail);
        let _ = mdd::parse_mdd(&m, Path::new("p.mdd"));
    }
}

/// cargo-fuzz found this: a GLB header declaring fewer bytes than the header
/// itself made the gltf crate underflow (a panic with overflow checks on).
#[test]
fn regression_glb_declared_length_under_header_size() {
    let crash = b"glTF\x40\x40\0\0\0\0\0\0\x40\x40\x40\x40\x46\x40\x40\x40\x40";
    assert!(gltf::parse_gltf(crash, Path::new("crash.glb")).is_err());
    let mut short = b"glTF\x02\0\0\0\x04\0\0\0".to_vec();
    short.extend_from_slice(&[0; 12]);
    assert!(gltf::parse_gltf(&short, Path::new("short.glb")).is_err());
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]

    /// The similarity cache and a manifest's `[graph]` section: arbitrary
    /// and bit-flipped bytes never panic or allocate from header counts.
    #[test]
    fn cache_and_graph_settings_never_panic(
        bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..300),
        flip in 0usize..4096,
    ) {
        use surfmotion::db::cache::parse_matrix;
        if bytes.len() >= 16 {
            let key = u64::from_le_bytes(bytes[8..16].try_into().unwrap());
            let _ = parse_matrix(&bytes, key);
        }
        // A valid file with one byte changed.
        let spans = vec![surfmotion::similarity::Span { name: "a".into(), start: 0, len: 3 }];
        let m = surfmotion::similarity::SimilarityMatrix::new(spans, vec![0.5; 9]).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.bin");
        surfmotion::db::cache::save_matrix(&p, 7, &m).unwrap();
        let mut good = std::fs::read(&p).unwrap();
        let i = flip % good.len();
        good[i] ^= 0x5a;
        let _ = parse_matrix(&good, 7);
        let text = format!(
            "name = \"x\"\ntopology = \"t.obj\"\n[graph]\n{}\n",
            String::from_utf8_lossy(&bytes)
        );
        if let Ok(m) = toml::from_str::<surfmotion::db::Manifest>(&text) {
            let _ = m.validate();
        }
    }
}

/// Issue 44: a malformed FBX (zero length, garbage, the wrong magic, a
/// truncated real file, a node claiming a huge count) gives one line naming
/// the file, through the same dispatch every verb uses (`read_clip`, by
/// extension and by magic bytes), never a panic.
#[test]
fn malformed_fbx_gives_one_line_naming_the_file() {
    use surfmotion::mocap::read_clip;
    let dir = tempfile::tempdir().unwrap();
    let mut cases: Vec<(&str, Vec<u8>)> = vec![
        ("empty.fbx", vec![]),
        ("garbage.fbx", b"\x00\x01garbage\xff".repeat(50)),
        ("bvh-inside.fbx", b"HIERARCHY\nROOT Hips\n{\n}\n".to_vec()),
        (
            "header-only.fbx",
            b"Kaydara FBX Binary  \0\x1a\0\xe8\x1c\0\0".to_vec(),
        ),
        (
            "ascii-no-skeleton.fbx",
            b"; FBX 7.5.0 project file\n".to_vec(),
        ),
    ];
    // A binary node whose array claims 2^32 - 1 elements.
    let mut huge = b"Kaydara FBX Binary  \0\x1a\0".to_vec();
    huge.extend_from_slice(&7400u32.to_le_bytes());
    let name = b"Vertices";
    let mut prop = vec![b'd'];
    prop.extend_from_slice(&u32::MAX.to_le_bytes()); // array length
    prop.extend_from_slice(&0u32.to_le_bytes()); // encoding
    prop.extend_from_slice(&16u32.to_le_bytes()); // compressed length
    prop.extend_from_slice(&[0u8; 16]);
    let end = (huge.len() + 13 + name.len() + prop.len()) as u32;
    huge.extend_from_slice(&end.to_le_bytes());
    huge.extend_from_slice(&1u32.to_le_bytes());
    huge.extend_from_slice(&(prop.len() as u32).to_le_bytes());
    huge.push(name.len() as u8);
    huge.extend_from_slice(name);
    huge.extend_from_slice(&prop);
    huge.extend_from_slice(&[0u8; 13]);
    cases.push(("huge-count.fbx", huge));
    if let Some(d) = common::optional_data_dir() {
        let real = std::fs::read(d.join("fbx/threejs/Samba Dancing.fbx")).unwrap();
        cases.push(("truncated.fbx", real[..real.len() / 3].to_vec()));
        cases.push(("truncated-header.fbx", real[..40].to_vec()));
        // FBX bytes under another extension are found by their magic.
        let small = std::fs::read(d.join("fbx/ufbx/max_transformed_skin_7500_binary.fbx")).unwrap();
        let p = dir.path().join("clip.mocap");
        std::fs::write(&p, &small).unwrap();
        let c = read_clip(&p, None, None, None).unwrap();
        assert_eq!(c.joint_count(), 5);
    }
    for (name, bytes) in &cases {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        let e = read_clip(&p, None, None, None)
            .err()
            .unwrap_or_else(|| panic!("{name} was read"))
            .to_string();
        assert!(e.starts_with(&p.display().to_string()), "{name}: {e}");
        assert_eq!(e.lines().count(), 1, "{name}: {e}");
        eprintln!("{name}: {e}");
    }
    // A take that does not exist names the takes there are.
    if let Some(d) = common::optional_data_dir() {
        let p = d.join("fbx/ufbx/maya_game_sausage_7500_ascii_combined.fbx");
        let e = read_clip(&p, None, None, Some("walk"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no take named 'walk'") && e.contains("'spin'"),
            "{e}"
        );
    }
}
