//! `surfmotion synth`: a multi-motion 4D database from a rest mesh, its
//! landmarks and mocap clips (skinning plus secondary dynamics).

use anyhow::{Context, bail};
use std::path::PathBuf;
use std::time::Instant;
use surfmotion::db::{Manifest, RigSpec, SequenceEntry};
use surfmotion::mesh::MeshSequence;
use surfmotion::mesh::io::{LoadOptions, load_sequence, save_sequence};
use surfmotion::rig::Canonical;
use surfmotion::rig::embed::Embedding;
use surfmotion::rig::embed::landmarks::Landmarks;
use surfmotion::synth::database::{Dynamics, synthesise};

/// Arguments of `synth`.
#[derive(clap::Args)]
pub struct Args {
    /// Rest mesh of the character (a file, or SEQ.pc2:FRAME), metres, Y-up.
    #[arg(long)]
    pub mesh: String,
    /// Landmarks on the rest mesh (JSON; see `rig embed --help`).
    #[arg(long)]
    pub landmarks: PathBuf,
    /// Mocap clips (BVH or AMC), one sequence each; repeatable.
    #[arg(long = "mocap", required = true, num_args = 1..)]
    pub mocap: Vec<PathBuf>,
    /// Output database directory.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Frame rate of the database.
    #[arg(long, default_value_t = 30.0, value_parser = super::frame_rate)]
    pub fps: f64,
    /// Use at most this many seconds of each clip.
    #[arg(long, value_parser = super::positive)]
    pub seconds: Option<f64>,
    /// Strength of the secondary dynamics (0: pure skinning).
    #[arg(long, default_value_t = 1.0, value_parser = super::non_negative)]
    pub dynamics: f64,
    /// Overwrite an existing manifest in the output.
    #[arg(long)]
    pub force: bool,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub clip: super::ClipOpts,
    #[command(flatten)]
    pub preview: super::render::PreviewOpts,
}

/// Runs `synth`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let dir = &a.output;
    if dir.join(surfmotion::db::MANIFEST).exists() && !a.force {
        bail!(
            "{}: a database exists there already; pass --force to overwrite it",
            dir.display()
        );
    }
    std::fs::create_dir_all(dir).with_context(|| dir.display().to_string())?;
    let t0 = Instant::now();
    let rest = load_sequence(&a.mesh, &LoadOptions::default())?.frame_mesh(0);
    let lm = Landmarks::load(&a.landmarks, rest.vertex_count())?;
    let rig = Embedding::new(&rest, &lm, None).map_err(|e| match e {
        e @ surfmotion::rig::embed::EmbedError::Mesh(_) => anyhow::anyhow!("{}: {e}", a.mesh),
        surfmotion::rig::embed::EmbedError::Landmarks(le) => {
            anyhow::anyhow!("{}: {le}", a.landmarks.display())
        }
        other => other.into(),
    })?;
    let embed_s = t0.elapsed().as_secs_f64();
    save_sequence(
        &MeshSequence::single(rest.clone()),
        &dir.join("topology.obj"),
        None,
    )?;
    surfmotion::fsutil::write_bytes_atomic(
        &dir.join("landmarks.json"),
        &surfmotion::fsutil::read_bytes(&a.landmarks)?,
    )?;
    let opts = a.clip.load_options()?;
    let dynamics = Dynamics {
        amount: a.dynamics.max(0.0),
        ..Dynamics::default()
    };
    let mut sequences = Vec::new();
    let mut report = Vec::new();
    let mut names = std::collections::BTreeSet::new();
    let bar = super::progress(a.mocap.len() as u64, "clips");
    let mut frames_total = 0usize;
    let (mut plaus_text, mut sheets) = (Vec::<String>::new(), Vec::new());
    let t1 = Instant::now();
    for path in &a.mocap {
        let clip = surfmotion::retarget::query::load_mocap(path, &opts, a.fps)?;
        let mut poses = clip.poses;
        if let Some(s) = a.seconds {
            poses.truncate(((s * a.fps).round() as usize).max(1));
        }
        // Skinned frames, their dynamics copy and the sequence: refuse a
        // clip that cannot fit before allocating (issue 18, item 12).
        surfmotion::budget::check_frames(
            &format!("{}", path.display()),
            poses.len(),
            rest.vertex_count(),
            3,
        )?;
        let out = synthesise(&rest, &rig, &poses, &clip.reference, a.fps, dynamics);
        // A unique sequence name from the clip's file stem.
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "clip".into());
        let mut name = stem.clone();
        let mut k = 2;
        while !names.insert(name.clone()) {
            name = format!("{stem}_{k}");
            k += 1;
        }
        let frames = out.poses.len();
        frames_total += frames;
        let seq = MeshSequence::new(rest.clone(), out.positions, Some(a.fps))?;
        let file = format!("{name}.pc2");
        save_sequence(&seq, &dir.join(&file), Some(a.fps))?;
        // Plausibility of the sequence against the rest frame (no capture
        // to compare with: absolute limits), and its contact sheet.
        let plaus = surfmotion::eval::Checker::new(
            rest.positions(),
            &rig,
            glam::DVec3::Y,
            None,
            a.fps,
            Default::default(),
        )
        .and_then(|c| c.measure(seq.all_positions(), rest.vertex_count(), None))
        .map_err(|e| tracing::warn!("{name}: plausibility not measured: {e}"))
        .ok();
        if let Some(p) = &plaus {
            plaus_text.push(format!("{name}: {}", p.text()));
        }
        if a.preview.preview.is_some() {
            sheets.extend(super::render::preview_image(
                seq.all_positions(),
                rest.vertex_count(),
                rest.triangles(),
                Some(&rig),
                None,
                plaus.as_ref().map(|p| p.floor_m),
                &a.preview,
            ));
        }
        let truth = serde_json::json!({
            "sequence": name,
            "fps": a.fps,
            "source": path,
            "joints": Canonical::ALL.iter().map(|c| c.name()).collect::<Vec<_>>(),
            "frames": out.poses.iter().map(|p| p.iter().map(|q| q.to_array()).collect::<Vec<_>>()).collect::<Vec<_>>(),
        });
        surfmotion::fsutil::write_bytes_atomic(
            &dir.join("truth").join(format!("{name}.skeleton.json")),
            serde_json::to_string(&truth)?.as_bytes(),
        )?;
        sequences.push(SequenceEntry {
            name: name.clone(),
            path: PathBuf::from(file),
            fps: None,
        });
        report.push(serde_json::json!({"sequence": name, "source": path, "frames": frames, "plausibility": plaus}));
        bar.inc(1);
    }
    bar.finish_and_clear();
    let synth_s = t1.elapsed().as_secs_f64();
    let m = Manifest {
        name: dir
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "synthetic".into()),
        topology: PathBuf::from("topology.obj"),
        fps: a.fps,
        units: "m".into(),
        up: "y".into(),
        colors: None,
        sequences,
        rig: RigSpec {
            landmarks: Some(PathBuf::from("landmarks.json")),
            parts: None,
            gltf_skin: None,
            rig_map: None,
        },
        graph: Default::default(),
        deform: Default::default(),
        spaces: Vec::new(),
    };
    m.save(dir)?;
    if a.json {
        let v = serde_json::json!({
            "output": dir,
            "embed_seconds": embed_s,
            "synth_seconds": synth_s,
            "frames": frames_total,
            "sequences": report,
        });
        crate::outln!("{}", serde_json::to_string_pretty(&v)?)?;
    } else {
        crate::outln!(
            "wrote {} ({} sequences, {} frames): rig embedded in {:.2} s, {} frames synthesised in {:.2} s ({:.0} frames/s)",
            dir.display(),
            report.len(),
            frames_total,
            embed_s,
            frames_total,
            synth_s,
            frames_total as f64 / synth_s.max(1e-9)
        )?;
        for r in &report {
            crate::outln!(
                "  {}: {} frames from {}",
                r["sequence"].as_str().unwrap_or(""),
                r["frames"],
                r["source"].as_str().unwrap_or("")
            )?;
        }
    }
    // The contact sheets of all sequences, one above the other; plausibility.
    if let (Some(p), Some(first)) = (&a.preview.preview, sheets.first()) {
        let img = sheets[1..]
            .iter()
            .fold(first.clone(), |acc, s| acc.above(s));
        img.save_png(p)?;
    }
    if !a.json {
        crate::outln!("{}", plaus_text.concat().trim_end())?;
    }
    Ok(())
}
