//! `surfmotion inspect FILE [--json]`.

use super::ClipOpts;
use std::path::PathBuf;
use surfmotion::tools::inspect::{InspectOptions, inspect};
use surfmotion::util::errtext;

/// Arguments of `inspect`.
#[derive(clap::Args)]
pub struct Args {
    /// A mocap clip (.bvh .amc .asf), a mesh / sequence (.obj .ply .pc2 .mdd
    /// .gltf .glb, a folder of .obj frames, or SEQ.pc2:FRAME), a database
    /// folder or its cache folder, or any file the tool writes (JSON
    /// reports, manifests, caches, .dot graphs, pictures, web sites).
    pub file: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Topology mesh for a point cache (default: the .obj of the same name beside it).
    #[arg(long, value_name = "MESH")]
    pub topology: Option<PathBuf>,
    #[command(flatten)]
    pub clip: ClipOpts,
}

/// Runs `inspect` (the library's option names in the report, such as the
/// units guess's, printed as flags).
pub fn run(a: Args) -> anyhow::Result<()> {
    let opts = InspectOptions {
        mocap: a.clip.load_options()?,
        mesh: surfmotion::mesh::io::LoadOptions {
            topology: a.topology,
            fps: None,
        },
    };
    let mut r = inspect(&a.file, &opts)?;
    if let surfmotion::tools::inspect::Report::Database(d) = &mut r {
        for p in &mut d.problems {
            *p = errtext::without_os_error_numbers(p);
        }
    }
    if a.json {
        let json = serde_json::to_string_pretty(&r)?;
        crate::outln!("{}", super::flags::as_flags(&json))?;
    } else {
        crate::cli::emit(&super::flags::as_flags(&r.to_text()))?;
    }
    Ok(())
}
