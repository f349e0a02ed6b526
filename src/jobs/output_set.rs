//! A job's outputs as one value (issue 40): every file it writes,
//! labelled with the option its caller names it by (`output`, `report`;
//! the CLI's `-o`, `--report`), the files it reads, and its mesh output
//! with `force`. [`OutputSet::check`] runs the output policy of
//! [`super::outputs`] in one order before any work, with the caller's own
//! format check (the CLI's `--glb-*` and `--usd-no-normals` refusals)
//! passed in at its place; the steps are public for the jobs whose order
//! differs (`retarget` checks formats after collisions, `transfer` names
//! an output over its scan in the mesh writer's words first).

use super::outputs::{
    OutputError, check_folder_output, check_mesh_output, database_inputs, refuse_colliding,
};
use std::path::{Path, PathBuf};

/// The mesh output of a job: its option, its path and whether a folder
/// of OBJ frames that holds files may be written into (`force`).
#[derive(Debug, Clone)]
struct MeshOutput {
    option: String,
    path: PathBuf,
    force: bool,
}

/// The inputs and labelled outputs of one job, checked before any work.
#[derive(Debug, Clone, Default)]
pub struct OutputSet {
    inputs: Vec<PathBuf>,
    outputs: Vec<(String, PathBuf)>,
    mesh: Option<MeshOutput>,
}

impl OutputSet {
    /// No outputs yet, for a job that reads `inputs`.
    pub fn reading(inputs: impl IntoIterator<Item = PathBuf>) -> OutputSet {
        OutputSet {
            inputs: inputs.into_iter().collect(),
            ..OutputSet::default()
        }
    }

    /// No outputs yet, for a job that reads the database `db` (its
    /// manifest, topology, sequences and rig files: [`database_inputs`]).
    pub fn reading_database(db: &Path) -> OutputSet {
        OutputSet::reading(database_inputs(db))
    }

    /// More files the job reads (`None` adds none).
    pub fn input(mut self, inputs: impl IntoIterator<Item = PathBuf>) -> OutputSet {
        self.inputs.extend(inputs);
        self
    }

    /// The job's mesh output `path`, given as `option`: its files (a point
    /// cache's topology OBJ beside it) are outputs, and it is the one the
    /// format and folder checks apply to.
    pub fn mesh(mut self, option: &str, path: &Path, force: bool) -> OutputSet {
        let files = crate::mesh::io::output_files(path);
        self.outputs
            .extend(files.into_iter().map(|p| (option.to_string(), p)));
        self.mesh = Some(MeshOutput {
            option: option.to_string(),
            path: path.to_path_buf(),
            force,
        });
        self
    }

    /// Another output, given as `option` (`None`: not asked for).
    pub fn file(mut self, option: &str, path: Option<&Path>) -> OutputSet {
        self.outputs
            .extend(path.map(|p| (option.to_string(), p.to_path_buf())));
        self
    }

    /// The files the job reads, in the order they were added.
    pub fn inputs(&self) -> &[PathBuf] {
        &self.inputs
    }

    /// Refuses the mesh output's path (a folder named like a file, a
    /// format no writer has): [`check_mesh_output`]. No mesh output: none.
    pub fn check_mesh_format(&self) -> Result<(), OutputError> {
        match &self.mesh {
            Some(m) => check_mesh_output(&m.path),
            None => Ok(()),
        }
    }

    /// Refuses an output over an input or two outputs that are one file:
    /// [`refuse_colliding`], outputs in the order they were added.
    pub fn refuse_colliding(&self) -> Result<(), OutputError> {
        let outputs: Vec<(&str, PathBuf)> = self
            .outputs
            .iter()
            .map(|(o, p)| (o.as_str(), p.clone()))
            .collect();
        refuse_colliding(&self.inputs, &outputs)
    }

    /// Refuses a folder-of-OBJ-frames mesh output that holds files
    /// without `force`, or holds an input: [`check_folder_output`]
    /// (with `force`, it removes the earlier OBJ frames there).
    pub fn check_folder(&self) -> Result<(), OutputError> {
        match &self.mesh {
            Some(m) => check_folder_output(&m.option, &m.path, m.force, &self.inputs),
            None => Ok(()),
        }
    }

    /// The whole policy in its order: the mesh output's format, then
    /// `formats` (the caller's check of the mesh output's path, e.g.
    /// options that apply to one format only), then collisions, then the
    /// folder. The first refusal is returned.
    pub fn check<E: From<OutputError>>(
        &self,
        formats: impl FnOnce(&Path) -> Result<(), E>,
    ) -> Result<(), E> {
        if let Some(m) = &self.mesh {
            check_mesh_output(&m.path)?;
            formats(&m.path)?;
        }
        self.refuse_colliding()?;
        self.check_folder()?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::{OutputError, OutputSet};
    use std::path::Path;

    /// The refusals come in the set's order, each naming the option it
    /// was given: the mesh output's format first, then the caller's
    /// check, then an output over an input, then two outputs that are
    /// one file, then a folder that holds files without `force`.
    #[test]
    fn refusals_come_in_order_and_name_their_option() {
        let dir = tempfile::tempdir().unwrap();
        let clip = dir.path().join("clip.bvh");
        std::fs::write(&clip, "x").unwrap();
        let frames = dir.path().join("frames");
        std::fs::create_dir(&frames).unwrap();
        std::fs::write(frames.join("notes.txt"), "x").unwrap();
        let reading = || OutputSet::reading([clip.clone()]);
        let no_check = |_: &Path| Ok::<(), OutputError>(());
        let refuse = |_: &Path| Err(OutputError::Gltf("caller".into()));
        let err = |s: &OutputSet, f: &dyn Fn(&Path) -> Result<(), OutputError>| {
            s.check(f)
                .map(|_| String::new())
                .unwrap_or_else(|e| e.to_string())
        };
        // An unknown format is refused before the caller's check and the
        // report over the clip.
        let s = reading()
            .mesh("-o", &dir.path().join("out.xyz"), false)
            .file("--report", Some(&clip));
        assert!(err(&s, &refuse).contains("unknown output format"));
        // The caller's check, before the report over the clip.
        let s = reading()
            .mesh("-o", &dir.path().join("out.pc2"), false)
            .file("--report", Some(&clip));
        assert!(err(&s, &refuse).contains("caller"));
        let e = err(&s, &no_check);
        assert!(
            e.starts_with("--report ") && e.contains("overwrite the input"),
            "{e}"
        );
        // Two outputs that are one file: the later names the earlier; a
        // point cache's topology OBJ is the mesh output's.
        let s = reading()
            .mesh("-o", &dir.path().join("out.pc2"), false)
            .file("--plot", Some(&dir.path().join("out.obj")));
        let e = err(&s, &no_check);
        assert!(
            e.starts_with("--plot ") && e.contains("-o writes the same file"),
            "{e}"
        );
        // A folder holding files: refused without `force`, written with it.
        let s = reading().mesh("-o", &frames, false);
        assert!(err(&s, &no_check).contains("already holds 1 file"));
        assert_eq!(err(&reading().mesh("-o", &frames, true), &no_check), "");
        // A folder that holds an input is refused even with `force`.
        let s = OutputSet::reading([frames.join("notes.txt")]).mesh("-O", &frames, true);
        assert!(err(&s, &no_check).starts_with("-O "));
        // No mesh output: only collisions.
        let s = reading().file("--report", Some(&clip));
        assert!(err(&s, &refuse).contains("overwrite the input"));
        assert_eq!(s.inputs(), [clip.clone()].as_slice());
    }
}
