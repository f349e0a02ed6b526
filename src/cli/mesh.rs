//! `surfmotion mesh ...`.

use std::path::PathBuf;
use surfmotion::mesh::io::{LoadOptions, load_sequence, save_sequence};

/// Mesh subcommands.
#[derive(clap::Subcommand)]
pub enum Cmd {
    /// Convert between mesh formats: e.g. samba.pc2 (topology from samba.obj
    /// beside it) to samba.glb, an OBJ folder to .pc2, SEQ.pc2:12 to one .obj.
    /// Output by extension: .glb, .pc2 (+ .obj), .mdd (+ .obj), .obj, .ply,
    /// or a path without extension for a folder of OBJ frames.
    Convert(ConvertArgs),
}

/// Arguments of `mesh convert`.
#[derive(clap::Args)]
pub struct ConvertArgs {
    /// Input mesh or sequence (PATH:FRAME picks one frame).
    pub input: String,
    /// Output path.
    pub output: PathBuf,
    /// Topology for a point cache input.
    #[arg(long, value_name = "MESH")]
    pub topology: Option<PathBuf>,
    /// Frame rate where the input has none (default 30).
    #[arg(long, value_parser = super::frame_rate)]
    pub fps: Option<f64>,
}

/// Runs a mesh subcommand.
pub fn run(c: Cmd) -> anyhow::Result<()> {
    match c {
        Cmd::Convert(a) => {
            surfmotion::mesh::io::refuse_overwriting(
                &surfmotion::mesh::io::input_files(&a.input, a.topology.as_deref()),
                &a.output,
            )?;
            let seq = load_sequence(
                &a.input,
                &LoadOptions {
                    topology: a.topology,
                    fps: a.fps,
                },
            )?;
            let files = save_sequence(&seq, &a.output, a.fps)?;
            let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
            eprintln!(
                "wrote {}: {}, {}, {}",
                names.join(" and "),
                super::count(seq.mesh().vertex_count(), "vertex"),
                super::count(seq.mesh().triangle_count(), "triangle"),
                super::count(seq.frame_count(), "frame")
            );
        }
    }
    Ok(())
}
