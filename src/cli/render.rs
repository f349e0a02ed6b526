//! `surfmotion render MESH -o OUT.png`: a quick look at a mesh, its rig
//! (part colours and skeleton) or a frame of a sequence.

use glam::DVec3;
use std::path::PathBuf;
use surfmotion::mesh::io::{LoadOptions, load_sequence};
use surfmotion::render::{Image, Scene, View, label_colour, render};
use surfmotion::rig::Canonical;
use surfmotion::rig::embed::Embedding;

/// Arguments of `render`.
#[derive(clap::Args)]
pub struct Args {
    /// Mesh or sequence (a file, or SEQ.pc2:FRAME for one frame); several
    /// are drawn side by side (e.g. the same frame of results made
    /// differently).
    #[arg(required = true, num_args = 1..)]
    pub mesh: Vec<String>,
    /// Output PNG.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Colour vertices by body part and draw the skeleton of this rig
    /// embedding (from `rig embed`); the skeleton follows the frame.
    #[arg(long)]
    pub rig: Option<PathBuf>,
    /// Frame of a sequence to draw.
    #[arg(long, default_value_t = 0)]
    pub frame: usize,
    /// Direction the character faces (x, -x, z, -z): sets the front view.
    /// Defaults to the rig's facing, else +z.
    #[arg(long, allow_hyphen_values = true)]
    pub facing: Option<String>,
    /// Image height in pixels (each view is square).
    #[arg(long, default_value_t = 600)]
    pub size: usize,
}

/// Parses `x`, `-x`, `z`, `-z`, `y`, `-y`.
pub fn parse_axis(s: &str) -> anyhow::Result<DVec3> {
    Ok(match s.trim().to_ascii_lowercase().as_str() {
        "x" | "+x" => DVec3::X,
        "-x" => DVec3::NEG_X,
        "y" | "+y" => DVec3::Y,
        "-y" => DVec3::NEG_Y,
        "z" | "+z" => DVec3::Z,
        "-z" => DVec3::NEG_Z,
        _ => anyhow::bail!("axis {s:?}: expected x, -x, y, -y, z or -z"),
    })
}

/// Front and side views of a frame, with part colours and bones when a rig is given.
pub fn draw(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    rig: Option<&Embedding>,
    facing: DVec3,
    size: usize,
) -> Image {
    let colours: Option<Vec<[u8; 3]>> =
        rig.map(|r| r.labels.iter().map(|&l| label_colour(l as usize)).collect());
    let mut lines = Vec::new();
    if let Some(r) = rig {
        let j = r.skeleton(positions);
        for c in Canonical::ALL {
            if let Some(p) = c.parent() {
                lines.push((j[p.index()].to_array(), j[c.index()].to_array(), [0, 0, 0]));
            }
        }
    }
    let scene = Scene {
        positions,
        triangles,
        colours: colours.as_deref(),
        lines: &lines,
    };
    let front = render(&scene, View::front(facing), size);
    let side = render(&scene, View::side(facing), size);
    front.beside(&side)
}

/// Runs `render`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let mut out: Option<surfmotion::render::Image> = None;
    for mesh in &a.mesh {
        let s = load_sequence(mesh, &LoadOptions::default())?;
        if a.frame >= s.frame_count() {
            anyhow::bail!(
                "{}: frame {} requested, the sequence has {}",
                mesh,
                a.frame,
                s.frame_count()
            );
        }
        let rig = match &a.rig {
            Some(p) => Some(Embedding::load(p, s.mesh().vertex_count())?),
            None => None,
        };
        let facing = match (&a.facing, &rig) {
            (Some(f), _) => parse_axis(f)?,
            (None, Some(r)) => DVec3::from_array(r.facing),
            (None, None) => DVec3::Z,
        };
        let img = draw(
            s.frame(a.frame),
            s.mesh().triangles(),
            rig.as_ref(),
            facing,
            a.size.clamp(16, 8192),
        );
        out = Some(match out {
            None => img,
            Some(o) => o.beside(&img),
        });
    }
    let Some(img) = out else {
        anyhow::bail!("no mesh given");
    };
    img.save_png(&a.output)?;
    crate::outln!(
        "wrote {} ({}x{}: front and left side of each)",
        a.output.display(),
        img.width,
        img.height
    )?;
    Ok(())
}
