//! The verbs' jobs called as a library (issue 40: `src/cli` only parses,
//! calls and prints): mocap, render, blend and the report texts, on the
//! project's procedural clips and humanoid (no shared data). Their
//! refusals name options, not flags.

use std::path::PathBuf;
use surfmotion::jobs::blend::{BlendOptions, blend};
use surfmotion::jobs::mocap::{self, ProceduralOptions};
use surfmotion::jobs::render::{RenderOptions, render};
use surfmotion::jobs::text::written_list;
use surfmotion::mesh::MeshSequence;
use surfmotion::mesh::io::save_sequence;
use surfmotion::rig::LoadOptions;
use surfmotion::synth::Gait;

#[test]
fn mocap_jobs_write_read_convert_and_map_procedural_clips() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("clips");
    let mut seen = Vec::new();
    let opts = ProceduralOptions {
        output: dir.clone(),
        seconds: 1.0,
        ..Default::default()
    };
    let clips = mocap::procedural(&opts, &mut |c| seen.push(c.path.clone())).unwrap();
    assert_eq!(clips.len(), Gait::ALL.len());
    assert_eq!(
        seen,
        clips.iter().map(|c| c.path.clone()).collect::<Vec<_>>()
    );
    assert!(clips.iter().all(|c| c.frames == 30 && c.path.is_file()));
    let walk = dir.join("walk.bvh");
    let load = LoadOptions::default();
    let p = mocap::positions(&walk, &load, &[10, 0, 2], true).unwrap();
    assert_eq!(p.frames.keys().copied().collect::<Vec<_>>(), [0, 2, 10]);
    assert!(p.frames.values().all(|f| f.len() == p.joints.len()));
    assert_eq!(p.up, "y");
    let e = mocap::positions(&walk, &load, &[30], false).unwrap_err();
    assert!(e.to_string().contains("frame 30 out of range"), "{e}");
    let out = tmp.path().join("walk60.bvh");
    let c = mocap::convert(&walk, &load, &out, Some(60.0), false).unwrap();
    assert_eq!((c.fps, c.output.clone()), (60.0, out.clone()));
    assert!(c.frames > 30 && out.is_file());
    let e = mocap::convert(&walk, &load, &walk, None, false).unwrap_err();
    assert!(e.to_string().contains("would overwrite the input"), "{e}");
    let e = mocap::convert(&walk, &load, &tmp.path().join("x.txt"), None, false).unwrap_err();
    assert!(
        e.to_string().ends_with("only .bvh output is supported"),
        "{e}"
    );
    let map = tmp.path().join("map.json");
    let det = mocap::rigmap(&walk, &load, Some(&map)).unwrap();
    assert!(det.missing.is_empty() && map.is_file());
    // A refusal names the option, which the CLI maps to its flag.
    let bad = ProceduralOptions {
        output: tmp.path().join("x.obj"),
        ..Default::default()
    };
    let e = mocap::procedural(&bad, &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("`ProceduralOptions::output`") && !e.contains("--"),
        "{e}"
    );
}

/// The humanoid's rest mesh as an OBJ in `dir`.
fn humanoid_obj(dir: &std::path::Path) -> PathBuf {
    let ch = surfmotion::jobs::SynthCharacter::humanoid().unwrap();
    let path = dir.join("humanoid.obj");
    save_sequence(&MeshSequence::single(ch.rest), &path, None).unwrap();
    path
}

#[test]
fn render_and_blend_jobs_report_what_they_wrote() {
    let tmp = tempfile::tempdir().unwrap();
    let obj = humanoid_obj(tmp.path());
    let spec = obj.display().to_string();
    let png = tmp.path().join("two.png");
    let opts = RenderOptions {
        meshes: vec![spec.clone(), spec.clone()],
        output: png.clone(),
        size: 64,
        ..Default::default()
    };
    let r = render(&opts).unwrap();
    // Front and side views of each mesh, side by side.
    assert_eq!((r.width, r.height), (4 * 64, 64));
    assert_eq!(r.panels.len(), 2);
    assert!(png.is_file());
    for p in &r.panels {
        assert_eq!(p.up, [0.0, 1.0, 0.0]);
        assert!(p.facing[1].abs() < 1e-9, "{:?}", p.facing);
    }
    let bad = RenderOptions {
        facing: Some("q".into()),
        ..opts.clone()
    };
    let e = render(&bad).unwrap_err().to_string();
    assert!(e.starts_with("`RenderOptions::facing` \"q\""), "{e}");
    let mid = tmp.path().join("mid.obj");
    let b = blend(&BlendOptions {
        a: spec.clone(),
        b: spec.clone(),
        alpha: 0.5,
        output: mid.clone(),
        ..Default::default()
    })
    .unwrap();
    assert_eq!(b.method, "non-linear");
    // A mesh blended with itself is itself: no distortion either way.
    assert!(b.edge_length_distortion.abs() < 1e-6, "{b:?}");
    assert!(b.linear_volume_distortion.abs() < 1e-6, "{b:?}");
    assert!(mid.is_file());
    let e = blend(&BlendOptions {
        alpha: 1.5,
        ..Default::default()
    })
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("`BlendOptions::alpha`") && !e.contains("--"),
        "{e}"
    );
}

#[test]
fn written_list_names_a_folder_of_obj_frames_once() {
    let frames: Vec<PathBuf> = (0..5)
        .map(|k| PathBuf::from(format!("out/frame_{k:04}.obj")))
        .collect();
    let sep = std::path::MAIN_SEPARATOR;
    assert_eq!(
        written_list(&frames, ", "),
        format!("out{sep} (5 OBJ frames, frame_0000.obj .. frame_0004.obj)")
    );
    let two = [PathBuf::from("a.pc2"), PathBuf::from("a.obj")];
    assert_eq!(written_list(&two, " and "), "a.pc2 and a.obj");
}

/// `repair` and `live`'s checks as library calls (session 35 moved them out
/// of the CLI): the repaired humanoid written with its text, an output over
/// the input refused, a mesh of degenerate or of flat triangles refused with
/// nothing written; only the addresses other machines reach warned.
#[test]
fn repair_job_writes_reports_and_refuses_and_live_warns_of_exposed_addresses() {
    use surfmotion::jobs::repair::{RepairJobError, RepairJobOptions, repair_file};
    let tmp = tempfile::tempdir().unwrap();
    let obj = humanoid_obj(tmp.path());
    let out = tmp.path().join("fixed.obj");
    let o = RepairJobOptions {
        input: obj.display().to_string(),
        output: out.clone(),
        ..Default::default()
    };
    let r = repair_file(&o).unwrap();
    assert!(out.is_file() && r.triangles > 0 && r.vertices > 0, "{r:?}");
    let text = r.text();
    assert!(
        text.starts_with(&format!(
            "wrote {} ({} vertices, ",
            out.display(),
            r.vertices
        )),
        "{text}"
    );
    assert_eq!(text.lines().count(), 8, "{text}");
    let over = RepairJobOptions {
        output: obj.clone(),
        ..o.clone()
    };
    assert!(matches!(repair_file(&over), Err(RepairJobError::Mesh(_))));
    // One triangle on a repeated vertex: degenerate, dropped, nothing left;
    // one on three collinear vertices: kept, but no surface. Neither writes.
    let refused = |name: &str, obj: &str| {
        let input = tmp.path().join(name);
        std::fs::write(&input, obj).unwrap();
        let out = tmp.path().join("refused.obj");
        let e = repair_file(&RepairJobOptions {
            input: input.display().to_string(),
            output: out.clone(),
            ..Default::default()
        })
        .unwrap_err();
        assert!(!out.exists(), "{e}");
        e
    };
    let e = refused("degenerate.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 1 2\n");
    assert!(
        matches!(e, RepairJobError::NothingLeft { triangles: 1, .. }),
        "{e}"
    );
    assert!(e.to_string().ends_with("nothing to write"), "{e}");
    let e = refused("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
    assert!(
        matches!(e, RepairJobError::ZeroArea { triangles: 1, .. }),
        "{e}"
    );
    assert!(e.to_string().ends_with("not a surface"), "{e}");
    let addrs = [
        "127.0.0.1:7001",
        "0.0.0.0:39539",
        "[::1]:8080",
        "192.168.1.5:80",
    ]
    .map(|a| a.parse::<std::net::SocketAddr>().unwrap());
    let w = surfmotion::jobs::live_checks::exposed(addrs);
    assert_eq!(w.len(), 2, "{w:?}");
    assert!(
        w[0].starts_with("warning: listening on 0.0.0.0:39539,"),
        "{w:?}"
    );
    assert!(
        w[1].starts_with("warning: listening on 192.168.1.5:80,"),
        "{w:?}"
    );
}
