//! Options shared by several verbs.

/// Options shared by the verbs that read clips and show their result
/// (`retarget`, `transfer`, `synth`; flattened in place, so their help
/// lists them where each verb declared them before).
#[derive(clap::Args, Clone, Debug)]
pub struct RunOpts {
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub clip: ClipOpts,
    #[command(flatten)]
    pub preview: super::render::PreviewOpts,
}

/// Options shared by every command that reads a clip.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct ClipOpts {
    /// Frame rate of the input, overriding the file's (BVH with a wrong
    /// Frame Time; AMC files store none and default to CMU's 120).
    #[arg(long = "input-fps", value_name = "FPS", value_parser = super::frame_rate)]
    pub input_fps: Option<f64>,
    /// The ASF skeleton of an AMC clip (default: the only .asf beside it).
    #[arg(long, value_name = "PATH")]
    pub asf: Option<std::path::PathBuf>,
    /// The take (animation stack) of an FBX clip, by name (default: the
    /// first with keyed curves), or the animation of a glTF clip, by name
    /// or index (default: the first that moves the skin); `inspect` lists them.
    #[arg(long, value_name = "NAME")]
    pub take: Option<String>,
    /// Length unit of the input: m, cm, mm, dm, inch, cmu (1/0.45 inch) or a
    /// number of metres per unit. Default: from the ASF header, else guessed
    /// from the skeleton's size (see `inspect`).
    // Unit options are named alike on every verb: `--input-units` for the
    // files read (with `--input-fps`), `--output-units` for what is
    // written. `--assume-units` was this option's name before.
    #[arg(long = "input-units", alias = "assume-units", value_name = "UNIT")]
    pub input_units: Option<String>,
    /// Up axis of the input (y or z). Default: guessed from head above pelvis.
    #[arg(long, value_name = "AXIS")]
    pub up: Option<String>,
    /// A JSON rig map (canonical joint → joint name) for rigs whose naming
    /// is not detected; `mocap rigmap CLIP -o map.json` writes one to edit.
    #[arg(long = "rig-map", value_name = "JSON")]
    pub rig_map: Option<std::path::PathBuf>,
}

impl ClipOpts {
    /// The library's load options.
    pub fn load_options(&self) -> anyhow::Result<surfmotion::rig::LoadOptions> {
        let units = match &self.input_units {
            None => None,
            Some(u) => Some(super::length_unit("--input-units", u)?),
        };
        let up = match self.up.as_deref().map(str::to_ascii_lowercase).as_deref() {
            None => None,
            Some("y") => Some(surfmotion::mocap::UpAxis::Y),
            Some("z") => Some(surfmotion::mocap::UpAxis::Z),
            Some(o) => anyhow::bail!("--up '{o}': expected y or z"),
        };
        let rig_map = match &self.rig_map {
            Some(p) => Some(surfmotion::rig::RigMap::load(p)?),
            None => None,
        };
        Ok(surfmotion::rig::LoadOptions {
            fps: self.input_fps,
            asf: self.asf.clone(),
            take: self.take.clone(),
            units,
            up,
            rig_map,
        })
    }
}

/// The first frame of a mesh file, keeping only the named OBJ groups when
/// any are given ([`surfmotion::jobs::mesh::load_mesh_groups`]).
pub fn load_mesh_groups(spec: &str, groups: &[String]) -> anyhow::Result<surfmotion::mesh::Mesh> {
    Ok(surfmotion::jobs::mesh::load_mesh_groups(spec, groups)?)
}
