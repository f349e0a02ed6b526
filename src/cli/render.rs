//! `surfmotion render MESH -o OUT.png`: a quick look at a mesh, its rig
//! (part colours and skeleton) or a frame of a sequence.

use std::path::PathBuf;
use surfmotion::jobs::render::{RenderOptions, render};
use surfmotion::tools::render::preview::PreviewOptions;

/// Arguments of `render`.
#[derive(clap::Args)]
pub struct Args {
    /// Mesh or sequence (a file, or SEQ.pc2:FRAME for one frame); several
    /// are drawn side by side (e.g. the same frame of results made
    /// differently).
    #[arg(required = true, num_args = 1.., value_parser = super::mesh_spec)]
    pub mesh: Vec<String>,
    /// Output PNG.
    #[arg(short, long, value_parser = super::png_path)]
    pub output: PathBuf,
    /// Colour vertices by body part and draw the skeleton of this rig
    /// embedding (from `rig embed`); the skeleton follows the frame.
    #[arg(long)]
    pub rig: Option<PathBuf>,
    /// Frame of a sequence to draw.
    #[arg(long, default_value_t = RenderOptions::default().frame)]
    pub frame: usize,
    /// Direction the character faces (x, -x, z, -z): sets the front view
    /// of every panel. Defaults to each panel's own: across the hips and
    /// shoulders of the rig's skeleton on the frame drawn, else read off
    /// the mesh's shoulders and knees over the frames around the one drawn
    /// (see `surfmotion::tools::render::facing_of_frames`).
    #[arg(long, allow_hyphen_values = true)]
    pub facing: Option<String>,
    /// The mesh's up axis (+y, -y, +z, -z, +x, -x): the frames are turned
    /// to stand Y-up before they are drawn (a bare `.pc2` carries no up; a
    /// Z-up scan's is read as lying). Defaults to the up of the rig's skeleton
    /// on the frame drawn (pelvis to neck) snapped to the nearest axis
    /// when `--rig` is given, else +y. `--facing` is in
    /// the file's own axes.
    #[arg(long, allow_hyphen_values = true)]
    pub up: Option<String>,
    /// Image height in pixels, 16 to 8192 (each view is square).
    #[arg(long, default_value_t = RenderOptions::default().size, value_parser = super::bounded_count(16, MAX_SIZE))]
    pub size: usize,
    /// Print what was written as JSON (picture, size, meshes, frame).
    #[arg(long)]
    pub json: bool,
}

pub use surfmotion::jobs::render::{MAX_PREVIEW_FRAMES, MAX_PREVIEW_SIZE, MAX_SIZE};

/// Runs `render` ([`surfmotion::jobs::render::render`]).
pub fn run(a: Args) -> anyhow::Result<()> {
    let r = render(&RenderOptions {
        meshes: a.mesh,
        output: a.output,
        rig: a.rig,
        frame: a.frame,
        facing: a.facing,
        up: a.up,
        size: a.size,
    })?;
    super::report_sorted(a.json, &r, || surfmotion::jobs::short_text::render(&r))
}

/// Options of `--preview` (shared by retarget, synth and transfer).
#[derive(clap::Args, Debug, Clone)]
pub struct PreviewOpts {
    /// Write a contact sheet of the result: a few evenly spaced frames,
    /// front views above and left-side views below, all at one scale.
    #[arg(long, value_name = "PNG", value_parser = super::png_path)]
    pub preview: Option<PathBuf>,
    /// Frames on the contact sheet, 1 to 100 (all frames when the result
    /// has fewer).
    #[arg(long, default_value_t = PreviewOptions::default().frames, value_name = "N", value_parser = super::bounded_count(1, MAX_PREVIEW_FRAMES))]
    pub preview_frames: usize,
    /// Size of each panel of the contact sheet (pixels, square), 16 to 4096.
    #[arg(long, default_value_t = PreviewOptions::default().size, value_name = "PX", value_parser = super::bounded_count(16, MAX_PREVIEW_SIZE))]
    pub preview_size: usize,
}

impl PreviewOpts {
    /// The library's options.
    pub fn options(&self) -> PreviewOptions {
        PreviewOptions {
            frames: self.preview_frames,
            size: self.preview_size,
        }
    }
}
