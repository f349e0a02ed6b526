//! `surfmotion synth`: a multi-motion 4D database from a rest mesh, its
//! landmarks and mocap clips (skinning plus secondary dynamics).

use anyhow::bail;
use std::path::PathBuf;
use std::time::Instant;
use surfmotion::embed::Embedding;
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::jobs::synth_db::SynthSequence;
use surfmotion::jobs::{SynthCharacter, SynthClip, SynthOptions, write_synthetic_database};
use surfmotion::mesh::io::{LoadOptions, load_sequence};
use surfmotion::synth::database::Dynamics;

/// Arguments of `synth`.
#[derive(clap::Args)]
pub struct Args {
    /// Rest mesh of the character (a file, or SEQ.pc2:FRAME), metres, Y-up.
    #[arg(long, value_parser = super::mesh_spec)]
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
    /// Strength of the secondary dynamics: the scale of the softness map
    /// (0: pure skinning, 1: the default, at most 2; from about 3 the
    /// springs tear the surface at the waist).
    #[arg(long, default_value_t = 1.0, value_parser = dynamics_amount)]
    pub dynamics: f64,
    /// Overwrite an existing manifest in the output.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub run: super::RunOpts,
}

/// `--dynamics`: a scale in `[0, 2]`. Renders of the demo character's walk
/// at 1 are smooth; at 3 a seam tears at the waist, at 10 the torso and
/// arms are jagged.
fn dynamics_amount(s: &str) -> Result<f64, String> {
    let v = super::non_negative(s)?;
    if v <= 2.0 {
        Ok(v)
    } else {
        Err(format!(
            "{s}: the dynamics scale is at most 2 (from about 3 the springs tear the surface)"
        ))
    }
}

/// Runs `synth`: the rig embedded here (errors name the mesh or the
/// landmarks file), then [`write_synthetic_database`].
pub fn run(a: Args) -> anyhow::Result<()> {
    super::warnings_in_summary(!a.run.json);
    let dir = &a.output;
    surfmotion::jobs::outputs::check_output_folder(
        "-o",
        dir,
        "synth writes a database folder: the manifest, topology, sequences and truth/",
    )?;
    if dir.join(surfmotion::db::MANIFEST).exists() && !a.force {
        bail!(
            "{}: a database exists there already; pass --force to overwrite it",
            dir.display()
        );
    }
    let t0 = Instant::now();
    let rest = load_sequence(&a.mesh, &LoadOptions::default())?.frame_mesh(0);
    let lm = Landmarks::load(&a.landmarks, rest.vertex_count())?;
    let rig = Embedding::new(&rest, &lm, None).map_err(|e| match e {
        e @ surfmotion::embed::EmbedError::Mesh(_) => anyhow::anyhow!("{}: {e}", a.mesh),
        surfmotion::embed::EmbedError::Landmarks(le) => {
            anyhow::anyhow!("{}: {le}", a.landmarks.display())
        }
        other => other.into(),
    })?;
    let embed_s = t0.elapsed().as_secs_f64();
    let character = SynthCharacter {
        rest,
        rig,
        landmarks_json: surfmotion::util::fsutil::read_bytes(&a.landmarks)?,
    };
    let (rest, rig) = (&character.rest, &character.rig);
    let opts = SynthOptions {
        fps: a.fps,
        seconds: a.seconds,
        dynamics: Dynamics {
            amount: a.dynamics.max(0.0),
            ..Dynamics::default()
        },
        force: true,
        load: a.run.clip.load_options()?,
        ..Default::default()
    };
    let clips: Vec<SynthClip> = a.mocap.iter().cloned().map(SynthClip::File).collect();
    let bar = super::progress(a.mocap.len() as u64, "clips");
    let (mut plaus_text, mut sheets) = (Vec::<String>::new(), Vec::new());
    let mut each = |row: &SynthSequence, positions: &[[f64; 3]]| {
        if let Some(p) = &row.plausibility {
            plaus_text.push(format!("{}: {}", row.sequence, p.text()));
        }
        if a.run.preview.preview.is_some() {
            sheets.extend(surfmotion::tools::render::preview::preview_image(
                positions,
                rest.vertex_count(),
                rest.triangles(),
                Some(rig),
                None,
                row.plausibility.as_ref().map(|p| p.floor_m),
                &a.run.preview.options(),
            ));
        }
        bar.inc(1);
    };
    let mut r = write_synthetic_database(dir, &character, &clips, &opts, &mut each)?;
    bar.finish_and_clear();
    r.embed_seconds = embed_s;
    if a.run.json {
        crate::outln!(
            "{}",
            serde_json::to_string_pretty(&serde_json::to_value(&r)?)?
        )?;
    } else {
        crate::outln!(
            "wrote {} ({}, {}): rig embedded in {:.2} s, {} synthesised in {:.2} s ({:.0} frames/s)",
            dir.display(),
            super::count(r.sequences.len(), "sequence"),
            super::count(r.frames, "frame"),
            embed_s,
            super::count(r.frames, "frame"),
            r.synth_seconds,
            r.frames as f64 / r.synth_seconds.max(1e-9)
        )?;
        for s in &r.sequences {
            crate::outln!(
                "  {}: {} from {}",
                s.sequence,
                super::count(s.frames, "frame"),
                s.source.display()
            )?;
        }
    }
    // The contact sheets of all sequences, one above the other; plausibility.
    if let (Some(p), Some(first)) = (&a.run.preview.preview, sheets.first()) {
        let img = sheets[1..]
            .iter()
            .fold(first.clone(), |acc, s| acc.above(s));
        img.save_png(p)?;
    }
    if !a.run.json {
        crate::outln!("{}", plaus_text.concat().trim_end())?;
    }
    Ok(())
}
