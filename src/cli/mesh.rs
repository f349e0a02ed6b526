//! `surfmotion mesh ...`.

use std::path::PathBuf;
use surfmotion::jobs::format_options;
use surfmotion::jobs::mesh::{MeshConvertOptions, convert_mesh};

/// Mesh subcommands.
#[derive(clap::Subcommand)]
pub enum Cmd {
    /// Convert between mesh formats: e.g. samba.pc2 (topology from samba.obj
    /// beside it) to samba.glb, an OBJ folder to .pc2, SEQ.pc2:12 to one .obj.
    /// Output by extension: .glb, .pc2 (+ .obj), .mdd (+ .obj), .obj, .ply,
    /// .usda, or a path without extension for a folder of OBJ frames.
    #[command(
        after_help = "Examples:\n  surfmotion mesh convert samba.pc2 samba.glb\n  surfmotion mesh convert samba.pc2:60 samba_60.obj"
    )]
    Convert(ConvertArgs),
}

/// Arguments of `mesh convert`.
#[derive(clap::Args)]
pub struct ConvertArgs {
    /// Input mesh or sequence (PATH:FRAME picks one frame).
    #[arg(value_parser = super::mesh_spec)]
    pub input: String,
    /// Output path; its extension picks the format (see above). A point
    /// cache also writes its topology OBJ beside it.
    pub output: PathBuf,
    /// Topology for a point cache input (default: the .obj of the same
    /// name beside it).
    #[arg(long, value_name = "MESH")]
    pub topology: Option<PathBuf>,
    /// Frame rate where the input has none (default 30).
    #[arg(long, value_parser = super::frame_rate)]
    pub fps: Option<f64>,
    /// Write into a folder of OBJ frames that already holds files (its OBJ
    /// frames are replaced).
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub glb: SequenceOutputArgs,
    /// Print what was written as JSON on stdout (files, vertices,
    /// triangles, frames, fps, and for --glb-quantize the measured error
    /// in metres) instead of the line on stderr.
    #[arg(long)]
    pub json: bool,
}

/// The sequence-output options (GLB and USD), flattened into every verb
/// that writes a mesh sequence.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct SequenceOutputArgs {
    /// GLB only: quantise positions to 16 and normal changes to 8 bits
    /// (KHR_mesh_quantization, a required extension): half the size, error
    /// under 0.1 mm on a human-sized character; see the README.
    #[arg(long)]
    pub glb_quantize: bool,
    /// GLB only: leave out the vertex normals (a third smaller; viewers
    /// then shade flat).
    #[arg(long)]
    pub glb_no_normals: bool,
    /// USD (.usda) only: leave out the per-frame vertex normals: half the
    /// file and half the write time (samba's 175 frames: 126 MB -> 58.5 MB);
    /// viewers then compute normals themselves each frame.
    #[arg(long)]
    pub usd_no_normals: bool,
}

impl SequenceOutputArgs {
    /// Refuses these flags for an output that is not a GLB (`output` names
    /// it, e.g. "out.pc2" or "--format pc2"):
    /// [`format_options::refuse_unless_glb`].
    pub fn refuse_unless_glb(&self, glb: bool, output: &str) -> anyhow::Result<()> {
        Ok(format_options::refuse_unless_glb(
            &self.options(),
            glb,
            output,
        )?)
    }

    /// Refuses `--usd-no-normals` for an output that is not a `.usda`
    /// (`output` names it): [`format_options::refuse_unless_usda`].
    pub fn refuse_unless_usda(&self, usda: bool, output: &str) -> anyhow::Result<()> {
        Ok(format_options::refuse_unless_usda(
            &self.usd_options(),
            usda,
            output,
        )?)
    }

    /// Both refusals for the output `path` (named as given).
    pub fn refuse_other_formats(&self, path: &std::path::Path) -> anyhow::Result<()> {
        let (glb, usd) = (self.options(), self.usd_options());
        Ok(format_options::refuse_other_formats(&glb, &usd, path)?)
    }

    /// The writer options these flags ask for.
    pub fn options(&self) -> surfmotion::mesh::io::glb::GlbOptions {
        surfmotion::mesh::io::glb::GlbOptions {
            quantize: self.glb_quantize,
            normals: !self.glb_no_normals,
        }
    }

    /// The `.usda` writer options these flags ask for.
    pub fn usd_options(&self) -> surfmotion::mesh::io::usd::UsdOptions {
        surfmotion::mesh::io::usd::UsdOptions {
            normals: !self.usd_no_normals,
        }
    }
}

/// Runs a mesh subcommand.
pub fn run(c: Cmd) -> anyhow::Result<()> {
    match c {
        Cmd::Convert(a) => {
            let usda = surfmotion::mesh::io::MeshFormat::of(&a.output)
                == Some(surfmotion::mesh::io::MeshFormat::Usda);
            a.glb
                .refuse_unless_usda(usda, &a.output.display().to_string())?;
            let r = convert_mesh(&MeshConvertOptions {
                input: a.input,
                output: a.output,
                topology: a.topology,
                fps: a.fps,
                force: a.force,
                glb: a.glb.options(),
                usd: a.glb.usd_options(),
            })?;
            if a.json {
                return super::emit_json(&serde_json::to_value(&r)?);
            }
            for line in r.lines() {
                crate::errln!("{}", super::flags::as_flags(&line));
            }
        }
    }
    Ok(())
}
