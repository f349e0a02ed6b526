//! `synth`: a synthetic database from a rest mesh file, its landmarks and
//! clip files: the rig embedded (errors name the mesh or the landmarks
//! file), then [`write_synthetic_database`], with each sequence's
//! plausibility text and contact sheet.

use crate::embed::landmarks::Landmarks;
use crate::embed::{EmbedError, Embedding};
use crate::mesh::io::{LoadOptions, load_sequence};
use crate::tools::render::Image;
use crate::tools::render::preview::PreviewOptions;
use std::path::{Path, PathBuf};
use std::time::Instant;

use super::synth_db::SynthSequence;
use super::write_synthetic_database;
use super::{JobError, SynthCharacter, SynthClip, SynthOptions, SynthReport};

/// What `synth` made: the database's report, each sequence's
/// plausibility (`SEQ: text`, in order) and, when asked, the contact
/// sheets of all sequences one above the other.
pub struct SynthRun {
    /// The database written.
    pub report: SynthReport,
    /// Each sequence's plausibility text.
    pub plausibility: String,
    /// The contact sheets.
    pub sheet: Option<Image>,
}

/// Writes the database `dir` (refused when it holds a manifest, unless
/// `opts.force`) from the rest mesh `mesh` (a file, or `SEQ.pc2:FRAME`),
/// its `landmarks` and `clips`; `preview` draws contact sheets; `each` is
/// called after each clip.
pub fn synth_from_files(
    dir: &Path,
    mesh: &str,
    landmarks: &Path,
    clips: &[PathBuf],
    opts: &SynthOptions,
    preview: Option<&PreviewOptions>,
    each: &mut dyn FnMut(),
) -> Result<SynthRun, JobError> {
    super::outputs::check_output_folder(
        "-o",
        dir,
        "synth writes a database folder: the manifest, topology, sequences and truth/",
    )?;
    if dir.join(crate::db::MANIFEST).exists() && !opts.force {
        return Err(JobError::Input {
            path: dir.to_path_buf(),
            msg: "a database exists there already; pass `force` to overwrite it".into(),
        });
    }
    let t0 = Instant::now();
    let rest = load_sequence(mesh, &LoadOptions::default())?.frame_mesh(0);
    let lm = Landmarks::load(landmarks, rest.vertex_count())?;
    let rig = Embedding::new(&rest, &lm, None).map_err(|e| match e {
        e @ EmbedError::Mesh(_) => JobError::Usage(format!("{mesh}: {e}")),
        EmbedError::Landmarks(le) => JobError::Input {
            path: landmarks.to_path_buf(),
            msg: le.to_string(),
        },
        other => other.into(),
    })?;
    let embed_s = t0.elapsed().as_secs_f64();
    let character = SynthCharacter {
        rest,
        rig,
        landmarks_json: crate::util::fsutil::read_bytes(landmarks)?,
    };
    let (rest, rig) = (&character.rest, &character.rig);
    let opts = SynthOptions {
        force: true,
        ..opts.clone()
    };
    let clips: Vec<SynthClip> = clips.iter().cloned().map(SynthClip::File).collect();
    let (mut plaus_text, mut sheets) = (Vec::<String>::new(), Vec::new());
    let mut on_clip = |row: &SynthSequence, positions: &[[f64; 3]]| {
        if let Some(p) = &row.plausibility {
            plaus_text.push(format!("{}: {}", row.sequence, p.text()));
        }
        if let Some(o) = preview {
            sheets.extend(crate::tools::render::preview::preview_image(
                positions,
                rest.vertex_count(),
                rest.triangles(),
                Some(rig),
                None,
                row.plausibility.as_ref().map(|p| p.floor_m),
                o,
            ));
        }
        each();
    };
    let mut r = write_synthetic_database(dir, &character, &clips, &opts, &mut on_clip)?;
    r.embed_seconds = embed_s;
    let sheet = sheets
        .split_first()
        .map(|(first, rest)| rest.iter().fold(first.clone(), |acc, s| acc.above(s)));
    Ok(SynthRun {
        report: r,
        plausibility: plaus_text.concat(),
        sheet,
    })
}

impl SynthRun {
    /// `synth`'s summary of the database written to `dir`: its sequences
    /// and frames, the embedding and synthesis times, then each sequence
    /// and the clip it came from.
    pub fn text(&self, dir: &Path) -> String {
        use crate::batch::summary::count;
        let r = &self.report;
        let mut s = format!(
            "wrote {} ({}, {}): rig embedded in {:.2} s, {} synthesised in {:.2} s ({:.0} frames/s)\n",
            dir.display(),
            count(r.sequences.len(), "sequence"),
            count(r.frames, "frame"),
            r.embed_seconds,
            count(r.frames, "frame"),
            r.synth_seconds,
            r.frames as f64 / r.synth_seconds.max(1e-9)
        );
        for q in &r.sequences {
            s += &format!(
                "  {}: {} from {}\n",
                q.sequence,
                count(q.frames, "frame"),
                q.source.display()
            );
        }
        s
    }
}
