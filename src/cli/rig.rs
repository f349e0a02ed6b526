//! `surfmotion rig embed`: landmarks on a rest mesh → joints, skin weights,
//! body parts and joint regressors.

use std::path::PathBuf;
use surfmotion::jobs::rig::{RigEmbedOptions, embed_rig};

/// `rig` subcommands.
#[derive(clap::Subcommand)]
pub enum Cmd {
    /// Embed a rig in a rest mesh from landmarks (chin, groin, wrists,
    /// elbows, knees; optionally shoulders, ankles, toes, head_top) given as
    /// JSON points or vertex indices, or found automatically when none are
    /// given. Writes joints, bone-heat skin weights,
    /// contiguous body parts with overlapping regions and joint regressors.
    #[command(
        after_help = "Example:\n  surfmotion rig embed samba.obj --landmarks samba.landmarks.json -o samba.rig.json --png samba_rig.png\n  surfmotion rig embed human_man.obj -o smpl.rig.json --write-landmarks smpl.auto.landmarks.json"
    )]
    Embed(EmbedArgs),
}

/// Arguments of `rig embed`.
#[derive(clap::Args)]
pub struct EmbedArgs {
    /// Rest mesh (a file, or SEQ.pc2:FRAME).
    #[arg(value_parser = super::mesh_spec)]
    pub mesh: String,
    /// Only these OBJ groups of the mesh (repeatable), e.g. `body`; the
    /// embedding is for the groups' vertices alone (renumbered in order).
    #[arg(long, value_name = "NAME")]
    pub group: Vec<String>,
    /// Landmark JSON. Without it (and without --skin) the landmarks are
    /// found automatically from the mesh's geometry (symmetry plane,
    /// geodesic extremities, limb sections), each with a confidence; below
    /// --min-confidence the embedding is refused with the reason. Given,
    /// it overrides them, and landmarks far from confident automatic ones
    /// (e.g. left and right swapped) are reported.
    #[arg(long, conflicts_with = "skin")]
    pub landmarks: Option<PathBuf>,
    /// The confidence (0..1) below which automatic landmarks are refused.
    #[arg(long, default_value_t = surfmotion::embed::scan_landmarks::ScanOptions::default().min_confidence, value_name = "C")]
    pub min_confidence: f64,
    /// Write the automatic landmarks as a landmark file to edit and give
    /// back with --landmarks.
    #[arg(long, value_name = "PATH", conflicts_with_all = ["landmarks", "skin"])]
    pub write_landmarks: Option<PathBuf>,
    /// Or take the rig from a rigged glTF (.glb/.gltf) or FBX (.fbx) of
    /// this character: its skin's joints and weights, matched to the mesh
    /// by vertex position (an FBX at the unit its animation reads at: its
    /// UnitScaleFactor unless the limbs' stature says otherwise, as for its
    /// clip; Y up). Give the same file as MESH to take its bind pose.
    #[arg(long)]
    pub skin: Option<PathBuf>,
    /// A rig map (canonical joint → skin joint name) for a skin whose
    /// joint names are not detected (e.g. unnamed `joint_N` nodes).
    #[arg(long = "rig-map", requires = "skin")]
    pub rig_map: Option<PathBuf>,
    /// Explicit part labels, JSON {part: [vertex ids]}, overriding the computed ones.
    #[arg(long)]
    pub parts: Option<PathBuf>,
    /// Output embedding (JSON).
    #[arg(short, long, required_unless_present = "pick")]
    pub output: Option<PathBuf>,
    /// Also draw the mesh coloured by part with the skeleton (PNG).
    #[arg(long, value_parser = super::png_path)]
    pub png: Option<PathBuf>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    /// Open a page on 127.0.0.1 instead (URL printed, Ctrl-C stops): the mesh coloured by part with the skeleton and the landmarks; drag a landmark to re-embed, Save writes NAME.picked.landmarks.json beside the landmark file (or the mesh, or a path typed on the page). Without --landmarks the page starts from the automatic landmarks; below --min-confidence it still opens, with what was found and the reason shown.
    #[arg(long, conflicts_with_all = ["output", "png", "group", "parts", "write_landmarks"])]
    pub pick: bool,
}

/// Runs a `rig` subcommand.
pub fn run(c: Cmd) -> anyhow::Result<()> {
    match c {
        Cmd::Embed(a) => embed(a),
    }
}

fn embed(a: EmbedArgs) -> anyhow::Result<()> {
    if a.pick {
        return pick(a);
    }
    let Some(output) = a.output else {
        return Err(super::Usage.into());
    };
    // No output over an input, checked before any work (`-o LANDMARKS.json`
    // replaced the landmarks with the embedding, exit 0).
    let mut inputs = surfmotion::mesh::io::input_files(&a.mesh, None);
    inputs.extend(
        [&a.landmarks, &a.skin, &a.rig_map, &a.parts]
            .into_iter()
            .flatten()
            .cloned(),
    );
    let set = surfmotion::jobs::output_set::OutputSet::reading(inputs)
        .file("-o", Some(&output))
        .file("--png", a.png.as_deref())
        .file("--write-landmarks", a.write_landmarks.as_deref());
    super::confidence(a.min_confidence)?;
    set.refuse_colliding()?;
    let mesh = super::load_mesh_groups(&a.mesh, &a.group)?;
    let r = embed_rig(
        mesh,
        &RigEmbedOptions {
            mesh: a.mesh,
            groups: !a.group.is_empty(),
            landmarks: a.landmarks,
            skin: a.skin,
            rig_map: a.rig_map,
            parts: a.parts,
            output,
            png: a.png,
            min_confidence: a.min_confidence,
            write_landmarks: a.write_landmarks.clone(),
        },
    )?;
    let landmarks = a.write_landmarks.as_deref();
    super::report_sorted(a.json, &r, || r.summary_text(landmarks))
}

/// `rig embed --pick`: the page on the mesh and its landmarks.
fn pick(a: EmbedArgs) -> anyhow::Result<()> {
    let mut inputs = surfmotion::mesh::io::input_files(&a.mesh, None);
    inputs.extend(a.skin.iter().chain(&a.rig_map).cloned());
    super::confidence(a.min_confidence)?;
    let mesh = super::load_mesh_groups(&a.mesh, &[])?;
    let o = surfmotion::jobs::pick::PickOptions {
        mesh: a.mesh,
        landmarks: a.landmarks,
        min_confidence: a.min_confidence,
        inputs,
        ..Default::default()
    };
    super::pick::serve(surfmotion::jobs::pick::open(mesh, &o)?, a.json)
}
