//! `surfmotion db init`: the arguments, the `NAME=PATH` pairs and the
//! unit parsed, [`init_database_with`] called, its notes and setup report
//! printed.

use anyhow::bail;
use std::path::PathBuf;
use surfmotion::db::init::InitOptions;
use surfmotion::jobs::db_init::{InitSetup, init_database_with};

/// Arguments of `db init`.
#[derive(clap::Args)]
pub struct InitArgs {
    /// The database directory (created if missing).
    pub dir: PathBuf,
    /// Topology mesh (its positions are the rest frame).
    #[arg(long)]
    pub mesh: PathBuf,
    /// A captured sequence as NAME=PATH (OBJ folder, .pc2, .mdd, .glb); repeatable.
    #[arg(long = "sequence", value_name = "NAME=PATH")]
    pub sequences: Vec<String>,
    /// Character name (default: the directory name).
    #[arg(long)]
    pub name: Option<String>,
    /// Frames per second of the captures.
    #[arg(long, default_value_t = InitOptions::default().fps, value_parser = super::frame_rate)]
    pub fps: f64,
    /// Length unit of the files (m, cm, mm, dm, inch, metres per unit, or
    /// auto: m, cm or mm, whichever makes the rest frame's largest side
    /// nearest 1.7 m), written as the manifest's `units`. (`--units` was its name
    /// before.)
    #[arg(
        long = "input-units",
        alias = "units",
        value_name = "UNIT",
        default_value_t = InitOptions::default().units
    )]
    pub units: String,
    /// Up axis of the files: y, z, or auto (the landmarks' groin→chin
    /// direction decides; y without landmarks). An explicit axis the
    /// landmarks contradict is written as given, with a warning.
    #[arg(long, default_value_t = InitOptions::default().up)]
    pub up: String,
    /// Landmarks JSON on the rest frame.
    #[arg(long)]
    pub landmarks: Option<PathBuf>,
    /// Explicit part labels JSON.
    #[arg(long)]
    pub parts: Option<PathBuf>,
    /// A rigged glTF whose vertices match the topology.
    #[arg(long = "gltf-skin")]
    pub gltf_skin: Option<PathBuf>,
    /// A rig map for the glTF skin's joint names (when not detected).
    #[arg(long = "rig-map", requires = "gltf_skin")]
    pub rig_map: Option<PathBuf>,
    /// The character is not a person's size (a figurine, a giant, an
    /// animal): its rest frame may measure outside 0.5-3 m in
    /// --input-units (written as the manifest's `human_sized = false`).
    /// Without it such a size is refused as a wrong unit.
    #[arg(long = "not-human-sized")]
    pub not_human_sized: bool,
    /// Overwrite an existing manifest.
    #[arg(long)]
    pub force: bool,
    /// Keep the topology's positions as the rest frame even when they have
    /// a contact. Without it, with --landmarks and sequences, a topology
    /// frame where the body touches itself far along the surface (a hand on
    /// the hip, forearms on the belly) is replaced by the clearest frame of
    /// the sequences for embedding the rig (written as `[rig] rest`): a
    /// contact in the rest frame wires the touching parts together.
    #[arg(long = "keep-rest-frame")]
    pub keep_rest_frame: bool,
    /// Write a picture of the rig (parts coloured, skeleton drawn), front
    /// and side, on the topology's frame and on the rest frame chosen.
    /// Needs a rig: --landmarks, or sequences to rig the character from.
    #[arg(long, value_name = "FILE.png")]
    pub png: Option<PathBuf>,
    /// Without --landmarks and --gltf-skin, write the manifest without a
    /// rig instead of rigging the character from its capture (the graph,
    /// key-frame search and web export need none; retarget needs a rig).
    #[arg(long = "no-rig", conflicts_with_all = ["landmarks", "gltf_skin"])]
    pub no_rig: bool,
    /// Print the manifest written as JSON, with the setup report under
    /// "setup" (also written as DIR/setup.json with --landmarks).
    #[arg(long)]
    pub json: bool,
    /// Then open a page on 127.0.0.1 (URL printed, Ctrl-C stops) on the rest frame: drag a landmark to re-embed; Save writes NAME.picked.landmarks.json beside the landmark file and the manifest names it when the page stops.
    #[arg(long, requires = "landmarks")]
    pub pick: bool,
}

/// Runs `db init` ([`init_database_with`]): the `NAME=PATH` pairs and the unit
/// are parsed here, everything else is the library's.
pub fn init(a: InitArgs) -> anyhow::Result<()> {
    let mut sequences = Vec::new();
    for s in &a.sequences {
        let Some((name, path)) = s.split_once('=') else {
            bail!("--sequence '{s}': expected NAME=PATH");
        };
        sequences.push((name.to_string(), PathBuf::from(path)));
    }
    if !a.units.eq_ignore_ascii_case("auto") {
        super::length_unit("--input-units", &a.units)?;
    }
    let opts = InitOptions {
        mesh: a.mesh,
        sequences,
        name: a.name,
        fps: a.fps,
        units: a.units,
        up: a.up,
        landmarks: a.landmarks,
        parts: a.parts,
        gltf_skin: a.gltf_skin,
        rig_map: a.rig_map,
        human_sized: !a.not_human_sized,
        force: a.force,
        choose_rest: !a.keep_rest_frame,
    };
    let setup = InitSetup {
        png: a.png,
        no_rig: a.no_rig,
        ..InitSetup::default()
    };
    let r = init_database_with(&a.dir, &opts, &setup)?;
    for n in &r.notes {
        crate::errln!("{}", super::flags::as_flags(n));
    }
    if a.json {
        let mut v = serde_json::to_value(&r.manifest)?;
        v["manifest"] = serde_json::to_value(&r.path)?;
        if let Some(s) = &r.setup {
            v["setup"] = serde_json::to_value(s)?;
            // The automatic rig's notes name flags, as on stderr.
            let notes = v["setup"]["rig_notes"].as_array_mut().into_iter().flatten();
            for n in notes {
                *n = super::flags::as_flags(n.as_str().unwrap_or_default()).into();
            }
        }
        super::emit_json(&v)?;
    } else if let Some(s) = &r.setup {
        crate::errln!("{}", super::flags::as_flags(&s.text()));
    }
    crate::errln!(
        "wrote {} ({}); check it with `surfmotion db info {}`",
        r.path.display(),
        surfmotion::batch::summary::count(r.manifest.sequences.len(), "sequence"),
        a.dir.display()
    );
    if a.pick {
        let o = surfmotion::jobs::pick::PickOptions::default();
        return super::pick::serve(surfmotion::jobs::pick::open_db(&a.dir, &o)?, false);
    }
    Ok(())
}
