//! `db init` as a job: a character's manifest (`character.toml`) written
//! from its files, every file read and checked first
//! ([`crate::db::init::assemble`]), nothing written on a refusal.
//!
//! Without landmarks (and without a glTF skin) the character is rigged
//! from its capture ([`crate::embed::auto`]): the automatic landmarks are
//! written beside the manifest as `auto.landmarks.json` and the manifest
//! names them, so that `db build` embeds the rig as from any landmarks
//! and the user can edit the file (and pass it back with `landmarks` as
//! an override).

use super::JobError;
use super::outputs::check_output_folder;
use crate::db::init::{InitOptions, assemble};
use crate::db::{MANIFEST, Manifest};
use crate::embed::auto::{AutoOptions, AutoRig, auto_rig};
use crate::mesh::io::{LoadOptions, load_sequence};
use std::path::{Path, PathBuf};

/// The file the automatic landmarks are written to, in the database folder.
pub const AUTO_LANDMARKS: &str = "auto.landmarks.json";

/// What [`init_database`] wrote.
#[derive(Clone, Debug, serde::Serialize)]
pub struct InitReport {
    /// The manifest written (paths inside the folder relative to it).
    pub manifest: Manifest,
    /// Where it was written (`DIR/character.toml`).
    pub path: PathBuf,
    /// What the `auto` guesses decided, one line each (the up axis read
    /// as Z, the unit read as cm or mm; the automatic rig's confidence and
    /// findings).
    pub notes: Vec<String>,
    /// The automatic rig, when the character was rigged from its capture.
    pub auto_rig: Option<AutoRig>,
}

/// Writes the manifest of `opts` into the database folder `dir` (created
/// if missing). Refused before anything is written: a `dir` that is a file,
/// an existing manifest without `force`, a file that does not read, a
/// sequence of another mesh, a rest frame not a person's size in its unit.
/// Without landmarks and glTF skin, the rig is found from the capture
/// ([`init_database_with`] with the default [`AutoOptions`]).
pub fn init_database(dir: &Path, opts: &InitOptions) -> Result<InitReport, JobError> {
    init_database_with(dir, opts, &AutoOptions::default())
}

/// [`init_database`] with the automatic rig's options (its rest frame).
/// A capture that cannot be rigged (one frame, not a humanoid) is refused
/// with the reason, nothing written.
pub fn init_database_with(
    dir: &Path,
    opts: &InitOptions,
    auto: &AutoOptions,
) -> Result<InitReport, JobError> {
    check_output_folder(
        "",
        dir,
        "db init writes the database's character.toml into a folder",
    )?;
    let mut notes = Vec::new();
    let wants_auto = opts.landmarks.is_none()
        && opts.gltf_skin.is_none()
        && !opts.sequences.is_empty()
        && (opts.force || !dir.join(MANIFEST).exists());
    if !wants_auto {
        let manifest = assemble(dir, opts, &mut notes)?;
        manifest.save(dir)?;
        return Ok(InitReport {
            manifest,
            path: dir.join(MANIFEST),
            notes,
            auto_rig: None,
        });
    }
    let file = dir.join(AUTO_LANDMARKS);
    if file.exists() && !opts.force {
        return Err(JobError::Input {
            path: file,
            msg: "automatic landmarks from an earlier `db init` are there: pass them as `InitOptions::landmarks` to keep them, or set `force` to find them again".into(),
        });
    }
    let (rig, vertex_count) = rig_capture(opts, auto)?;
    let mut o = opts.clone();
    let axis = crate::embed::axes::nearest_axis(glam::DVec3::from_array(rig.up));
    let up = if axis == glam::DVec3::Y {
        "y"
    } else if axis == glam::DVec3::Z {
        "z"
    } else {
        return Err(JobError::Input {
            path: opts.mesh.clone(),
            msg: format!(
                "automatic rigging: the body stands along ({:.0}, {:.0}, {:.0}); the database reads Y-up or Z-up files: turn the mesh and its sequences",
                axis.x, axis.y, axis.z
            ),
        });
    };
    if o.up.eq_ignore_ascii_case("auto") {
        o.up = up.into();
    } else if !o.up.eq_ignore_ascii_case(up) {
        notes.push(format!(
            "`InitOptions::up` {}, but the automatic rig finds the feet on a floor along +{}: is the capture {}-up?",
            o.up,
            up.to_ascii_uppercase(),
            up.to_ascii_uppercase()
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| JobError::Input {
        path: dir.to_path_buf(),
        msg: e.to_string(),
    })?;
    let json = rig.landmarks_json(vertex_count);
    crate::util::fsutil::write_bytes_atomic(&file, json.as_bytes())?;
    o.landmarks = Some(file.clone());
    let manifest = match assemble(dir, &o, &mut notes) {
        Ok(m) => m,
        Err(e) => {
            // Nothing written on a refusal: the file this call wrote goes.
            let _ = std::fs::remove_file(&file);
            return Err(e.into());
        }
    };
    if let Err(e) = manifest.save(dir) {
        let _ = std::fs::remove_file(&file);
        return Err(e.into());
    }
    notes.push(rig.summary());
    notes.extend(rig.notes.iter().map(|n| format!("automatic rig: {n}")));
    notes.push(format!(
        "automatic rig: landmarks written to {}; edit them and pass them with `InitOptions::landmarks` to override",
        file.display()
    ));
    Ok(InitReport {
        manifest,
        path: dir.join(MANIFEST),
        notes,
        auto_rig: Some(rig),
    })
}

/// The automatic rig of `opts`' mesh from all its sequences' frames, and
/// the mesh's vertex count.
fn rig_capture(opts: &InitOptions, auto: &AutoOptions) -> Result<(AutoRig, usize), JobError> {
    let spec = |p: &Path| p.to_string_lossy().into_owned();
    let topo = load_sequence(&spec(&opts.mesh), &LoadOptions::default())?;
    let mesh = topo.mesh();
    let load = LoadOptions {
        topology: Some(opts.mesh.clone()),
        fps: None,
    };
    let mut seqs = Vec::new();
    for (_, path) in &opts.sequences {
        seqs.push(load_sequence(&spec(path), &load)?);
    }
    let frames: Vec<&[[f64; 3]]> = seqs
        .iter()
        .flat_map(|s| (0..s.frame_count()).map(|f| s.frame(f)))
        .collect();
    Ok((auto_rig(mesh, &frames, auto)?, mesh.vertex_count()))
}
