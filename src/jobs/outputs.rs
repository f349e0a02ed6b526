//! The output policy of every job, checked before any work: no output
//! replaces an input, no two outputs are one file, a mesh output has a
//! writer, a folder of OBJ frames is empty or replaced on request only,
//! and a batch never writes among its clips.
//!
//! Each check takes the name its caller gives the option of each output
//! (`output`, `report`; the CLI passes its flags, `-o`, `--report`), so a
//! refusal names what the caller asked for. Options of the library are
//! named in backticks (`` `force` ``, `` `mocap_dir` ``).

use crate::batch::Format;
use crate::db::{MANIFEST, Manifest};
use crate::mesh::MeshError;
use crate::mesh::io::MeshFormat;
use std::path::{Path, PathBuf};

/// An output refused before any work.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// An output would replace an input.
    #[error(
        "{option} {}: writing it would overwrite the input {}; choose another name",
        output.display(),
        input.display()
    )]
    OverInput {
        /// The output's option.
        option: String,
        /// The output.
        output: PathBuf,
        /// The input it names.
        input: PathBuf,
    },
    /// Two outputs are one file.
    #[error("{option} {}: {other} writes the same file; choose another name", output.display())]
    Twice {
        /// The output's option.
        option: String,
        /// The output.
        output: PathBuf,
        /// The option of the earlier output that writes it.
        other: String,
    },
    /// A mesh output of no format a writer has.
    #[error(
        "{}: unknown output format (use .glb .pc2 .mdd .obj .ply .usda or a folder)",
        .0.display()
    )]
    UnknownFormat(PathBuf),
    /// A `.gltf` mesh output (only `.glb` is written).
    #[error("{}: writing .gltf is not supported; use .glb", .0.display())]
    Gltf(PathBuf),
    /// A mesh output that is not a file name.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A folder of OBJ frames that holds an input.
    #[error(
        "{option} {}: the folder holds the input {}; write the frames to another folder (`force` replaces earlier outputs, never inputs)",
        folder.display(),
        input.display()
    )]
    FolderHoldsInput {
        /// The output's option.
        option: String,
        /// The folder.
        folder: PathBuf,
        /// The input in it.
        input: PathBuf,
    },
    /// A folder of OBJ frames that holds files, without `force`.
    #[error(
        "{option} {}: the folder already holds {}; pass `force` to replace its OBJ frames, or choose an empty or new folder",
        folder.display(),
        crate::batch::summary::count(*files, "file")
    )]
    FolderNotEmpty {
        /// The output's option.
        option: String,
        /// The folder.
        folder: PathBuf,
        /// How many files it holds.
        files: usize,
    },
    /// A batch's output folder that is its clip folder.
    #[error(
        "{option} {}: the clip folder itself (`mocap_dir`); the outputs and batch.json, .html and .svg would be written among the clips: give another folder, e.g. {option} {}",
        output.display(),
        instead.display()
    )]
    ClipFolder {
        /// The output folder's option.
        option: String,
        /// The output folder.
        output: PathBuf,
        /// A folder beside the clips to suggest.
        instead: PathBuf,
    },
    /// A batch's output folder inside its clip folder.
    #[error(
        "{option} {}: inside the clip folder `mocap_dir` {}; the outputs would become part of the library the batch reads: give a folder outside it, e.g. {option} {}",
        output.display(),
        clips.display(),
        instead.display()
    )]
    InClipFolder {
        /// The output folder's option.
        option: String,
        /// The output folder.
        output: PathBuf,
        /// The clip folder, as given.
        clips: PathBuf,
        /// A folder beside the clips to suggest.
        instead: PathBuf,
    },
    /// A batch clip whose output would replace an input.
    #[error("clip {}: {source}", clip.display())]
    Clip {
        /// The clip.
        clip: PathBuf,
        /// Why its output is refused.
        source: Box<OutputError>,
    },
    /// An output folder that is a file or lies under one.
    #[error(
        "{}: {}, not a folder ({writes})",
        named(option, folder),
        if file == folder { "a file".to_string() } else { format!("{} is a file", file.display()) }
    )]
    NotAFolder {
        /// The folder's option (empty for one named without an option).
        option: String,
        /// The folder.
        folder: PathBuf,
        /// The file: the folder itself or one of its parents.
        file: PathBuf,
        /// What goes into the folder.
        writes: String,
    },
    /// A folder that could not be listed or a file that could not be removed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The folder or file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
}

/// `option folder`, or the folder alone when `option` is empty.
fn named(option: &str, folder: &Path) -> String {
    if option.is_empty() {
        folder.display().to_string()
    } else {
        format!("{option} {}", folder.display())
    }
}

/// Refuses an output folder that is a file or lies under one, before any
/// work (it said "X: File exists (os error 17)" or "Not a directory" after
/// it). `option` names it (empty for one named without an option), `writes`
/// says what goes into the folder.
pub(crate) fn check_output_folder(
    option: &str,
    dir: &Path,
    writes: &str,
) -> Result<(), OutputError> {
    for p in dir.ancestors().filter(|p| !p.as_os_str().is_empty()) {
        if p.exists() && !p.is_dir() {
            return Err(OutputError::NotAFolder {
                option: option.to_string(),
                folder: dir.to_path_buf(),
                file: p.to_path_buf(),
                writes: writes.to_string(),
            });
        }
    }
    Ok(())
}

/// Whether `a` and `b` name one file on disk, existing or not (compared by
/// their canonical folder and file name).
fn same_file(a: &Path, b: &Path) -> bool {
    let key = |p: &Path| -> Option<PathBuf> {
        if let Ok(c) = p.canonicalize() {
            return Some(c);
        }
        let dir = p
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        Some(dir.canonicalize().ok()?.join(p.file_name()?))
    };
    matches!((key(a), key(b)), (Some(x), Some(y)) if x == y)
}

/// Refuses a job that would write over one of its `inputs`, or
/// write two of its `outputs` (option, path) to one file, before any work.
/// (`retarget --report CLIP.bvh` replaced the clip with the report,
/// `--report out.glb` the result, `--preview CLIP.bvh` the clip with a
/// PNG; each exited 0.)
pub fn refuse_colliding(
    inputs: &[PathBuf],
    outputs: &[(&str, PathBuf)],
) -> Result<(), OutputError> {
    for (k, (option, o)) in outputs.iter().enumerate() {
        if let Some(i) = inputs.iter().find(|i| same_file(i, o)) {
            return Err(OutputError::OverInput {
                option: option.to_string(),
                output: o.clone(),
                input: i.clone(),
            });
        }
        if let Some((other, _)) = outputs[..k].iter().find(|(_, p)| same_file(p, o)) {
            return Err(OutputError::Twice {
                option: option.to_string(),
                output: o.clone(),
                other: other.to_string(),
            });
        }
    }
    Ok(())
}

/// Refuses a mesh output path before any work: a folder named like a
/// file, or an extension no writer has (found only after the whole job).
pub fn check_mesh_output(out: &Path) -> Result<(), OutputError> {
    crate::mesh::io::refuse_folder_as_file(out)?;
    match MeshFormat::of(out) {
        None => Err(OutputError::UnknownFormat(out.to_path_buf())),
        Some(MeshFormat::Gltf) => Err(OutputError::Gltf(out.to_path_buf())),
        Some(f @ MeshFormat::Fbx) => Err(crate::mesh::io::format::not_written(out, f).into()),
        Some(_) => Ok(()),
    }
}

/// Refuses a folder-of-OBJ-frames output `out` (a name without extension,
/// given as `option`) that exists and already holds files, unless `force`,
/// as `synth -o` and `db init` refuse an existing database: frames written among other files, or
/// over a longer run's frames (whose last ones stayed behind and read back
/// as part of the new sequence), made a folder that is not this run's
/// result (`keyframe -o DIR` wrote into a folder of files, exit 0). With
/// `force` the OBJ frames a previous run wrote there (`frame_*.obj`) are
/// removed first; other files stay.
///
/// `force` never extends to inputs: a folder that is or holds one of
/// `inputs` (the job's input files and folders, resolved before this is
/// called) is
/// refused, naming it, before anything is removed (issue 46, item 3:
/// `keyframe -o DB --force` removed the database's own `frame_*.obj`
/// sequence and topology, then failed to load it).
pub fn check_folder_output(
    option: &str,
    out: &Path,
    force: bool,
    inputs: &[PathBuf],
) -> Result<(), OutputError> {
    if out.extension().is_some() || !out.is_dir() {
        return Ok(());
    }
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| OutputError::Io { path, source }
    };
    let entries: Vec<PathBuf> = std::fs::read_dir(out)
        .map_err(io(out))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    if entries.is_empty() {
        return Ok(());
    }
    if let Ok(dir) = out.canonicalize() {
        let inside = |i: &&PathBuf| {
            i.canonicalize()
                .is_ok_and(|c| c == dir || c.parent() == Some(dir.as_path()))
        };
        // An input among the frames `force` would remove is named first.
        let frame = |p: &PathBuf| {
            p.file_name()
                .and_then(|n| n.to_str())
                .and_then(|n| n.strip_prefix("frame_"))
                .is_some_and(|n| n.to_ascii_lowercase().ends_with(".obj"))
        };
        if let Some(i) = inputs.iter().filter(inside).min_by_key(|p| !frame(p)) {
            return Err(OutputError::FolderHoldsInput {
                option: option.to_string(),
                folder: out.to_path_buf(),
                input: i.clone(),
            });
        }
    }
    if !force {
        return Err(OutputError::FolderNotEmpty {
            option: option.to_string(),
            folder: out.to_path_buf(),
            files: entries.len(),
        });
    }
    let is_frame = |p: &Path| {
        p.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj"))
            && p.file_stem()
                .and_then(|s| s.to_str())
                .and_then(|s| s.strip_prefix("frame_"))
                .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
    };
    for p in entries.iter().filter(|p| is_frame(p) && p.is_file()) {
        std::fs::remove_file(p).map_err(io(p))?;
    }
    Ok(())
}

/// The files a database is read from (its manifest, topology, sequences
/// and rig files), which no output may replace.
pub fn database_inputs(db: &Path) -> Vec<PathBuf> {
    let mut v = vec![db.join(MANIFEST)];
    if let Ok(m) = Manifest::load(db) {
        v.push(Manifest::resolve(db, &m.topology));
        for s in &m.sequences {
            let p = Manifest::resolve(db, &s.path);
            v.extend(crate::mesh::io::input_files(&p.to_string_lossy(), None));
        }
        let r = &m.rig;
        for p in [&r.landmarks, &r.parts, &r.gltf_skin, &r.rig_map]
            .into_iter()
            .flatten()
        {
            v.push(Manifest::resolve(db, p));
        }
    }
    v
}

/// Refuses a batch output folder `output` (given as `option`) equal to
/// the clip folder `clips` or inside it: the outputs,
/// batch.json/.html/.svg and batch.lock were written among the user's
/// clips (and a later batch of the library walked the outputs' tree as
/// part of it). Paths are compared resolved (links, `.`, `..`), an output
/// that does not exist yet by its nearest existing parent.
pub(crate) fn refuse_output_in_clip_folder(
    option: &str,
    output: &Path,
    clips: &Path,
) -> Result<(), OutputError> {
    let Ok(resolved_clips) = clips.canonicalize() else {
        return Ok(()); // the batch itself reports a missing folder
    };
    let out = resolved(output);
    if out == resolved_clips {
        return Err(OutputError::ClipFolder {
            option: option.to_string(),
            output: output.to_path_buf(),
            instead: sibling(&resolved_clips),
        });
    }
    if out.starts_with(&resolved_clips) {
        return Err(OutputError::InClipFolder {
            option: option.to_string(),
            output: output.to_path_buf(),
            clips: clips.to_path_buf(),
            instead: sibling(&resolved_clips),
        });
    }
    Ok(())
}

/// `p` with links, `.` and `..` resolved; a path that does not exist yet
/// by its nearest existing ancestor, the rest appended.
fn resolved(p: &Path) -> PathBuf {
    let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let mut rest = Vec::new();
    let mut at = abs.as_path();
    loop {
        if let Ok(c) = at.canonicalize() {
            let mut out = c;
            for part in rest.iter().rev() {
                out.push(part);
            }
            return out;
        }
        match (at.parent(), at.file_name()) {
            (Some(parent), Some(name)) => {
                rest.push(name.to_os_string());
                at = parent;
            }
            _ => return abs,
        }
    }
}

/// `DIR-out` beside the clip folder, for the refusal's example.
fn sibling(clips: &Path) -> PathBuf {
    let mut name = clips.file_name().unwrap_or_default().to_os_string();
    name.push("-out");
    clips.with_file_name(name)
}

/// Refuses, before any work, a clip under `clips` whose output in
/// `output` (given as `option`, in `format`) would replace one of the
/// batch's `inputs`: an output folder that is the database folder made clip `walk.bvh`'s output
/// the database's own `walk.pc2` (reported as "already done", exit 0, or
/// replaced with `force`), and the scan's folder would have a
/// clip's topology OBJ written over the scan of the same name.
pub(crate) fn refuse_outputs_over_inputs(
    inputs: &[PathBuf],
    clips: &Path,
    option: &str,
    output: &Path,
    format: Format,
) -> Result<(), OutputError> {
    let Ok(found) = crate::batch::find_clips(clips) else {
        return Ok(()); // the batch itself reports an unreadable folder
    };
    for rel in &found {
        let out = crate::batch::output_path(output, rel, format);
        let mut outputs = vec![(option, out.clone())];
        if format == Format::Pc2 {
            outputs.push((option, out.with_extension("obj")));
        }
        refuse_colliding(inputs, &outputs).map_err(|e| OutputError::Clip {
            clip: clips.join(rel),
            source: Box::new(e),
        })?;
    }
    Ok(())
}

/// Refuses a `db skeleton` output folder `out` (given as `option`) that is
/// a file, or whose rig.json, SEQ.skeleton.json or SEQ.bvh would replace
/// one of the database's inputs; checked before the skeletons are
/// extracted (`-o FILE` said "FILE/rig.json: File exists (os error 17)"
/// after the work).
pub fn check_skeleton_outputs(option: &str, db: &Path, out: &Path) -> Result<(), OutputError> {
    check_output_folder(
        option,
        out,
        "db skeleton writes rig.json and each sequence's SEQ.skeleton.json and SEQ.bvh into a folder",
    )?;
    if let Ok(m) = Manifest::load(db) {
        let mut outputs = vec![(option, out.join("rig.json"))];
        for s in &m.sequences {
            outputs.push((option, out.join(format!("{}.skeleton.json", s.name))));
            outputs.push((option, out.join(format!("{}.bvh", s.name))));
        }
        refuse_colliding(&database_inputs(db), &outputs)?;
    }
    Ok(())
}
