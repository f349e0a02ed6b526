//! `surfmotion render MESH -o OUT.png`: a quick look at a mesh, its rig
//! (part colours and skeleton) or a frame of a sequence.

use glam::DVec3;
use std::path::PathBuf;
use surfmotion::embed::Embedding;
use surfmotion::embed::axes::nearest_axis;
use surfmotion::mesh::io::{LoadOptions, load_sequence};
use surfmotion::rig::Canonical;
use surfmotion::tools::render::preview::PreviewOptions;
use surfmotion::tools::render::{
    Framing, Image, Scene, View, facing_of_frames, label_colour, render_framed, view_bounds,
};

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
    #[arg(long, default_value_t = 0)]
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
    #[arg(long, default_value_t = 600, value_parser = super::bounded_count(16, MAX_SIZE))]
    pub size: usize,
    /// Print what was written as JSON (picture, size, meshes, frame).
    #[arg(long)]
    pub json: bool,
}

/// Largest `--size` of `render` (pixels): a picture of two 8192-pixel
/// views is 400 MB of pixels.
pub const MAX_SIZE: u64 = 8192;

/// Largest `--preview-size` (pixels, each panel square).
pub const MAX_PREVIEW_SIZE: u64 = 4096;

/// Most frames on a contact sheet (`--preview-frames`).
pub const MAX_PREVIEW_FRAMES: u64 = 100;

/// Parses `x`, `-x`, `z`, `-z`, `y`, `-y` (`+` allowed).
pub fn parse_axis(s: &str) -> anyhow::Result<DVec3> {
    axis_named(s).ok_or_else(|| anyhow::anyhow!("--facing {s:?}: expected x, -x, y, -y, z or -z"))
}

fn axis_named(s: &str) -> Option<DVec3> {
    Some(match s.trim().to_ascii_lowercase().as_str() {
        "x" | "+x" => DVec3::X,
        "-x" => DVec3::NEG_X,
        "y" | "+y" => DVec3::Y,
        "-y" => DVec3::NEG_Y,
        "z" | "+z" => DVec3::Z,
        "-z" => DVec3::NEG_Z,
        _ => return None,
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
    draw_framed(positions, triangles, rig, facing, size, [None, None], None)
}

/// [`draw`] with each view placed by its framing (`None`: fitted to the frame).
pub fn draw_framed(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    rig: Option<&Embedding>,
    facing: DVec3,
    size: usize,
    framing: [Option<Framing>; 2],
    floor: Option<f64>,
) -> Image {
    let colours: Option<Vec<[u8; 3]>> =
        rig.map(|r| r.labels.iter().map(|&l| label_colour(l as usize)).collect());
    let mut lines = Vec::new();
    if let Some(r) = rig {
        let j = r.frame_joints(positions);
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
    let views = [View::front(facing), View::side(facing)];
    let [front, side] = [0, 1].map(|k| {
        let f = framing[k].unwrap_or_else(|| Framing::fit(positions, views[k], size));
        let mut lines = lines.clone();
        if let Some(y) = floor.filter(|y| y.is_finite()) {
            lines.insert(
                0,
                surfmotion::tools::render::floor_line(views[k], f, y, size),
            );
        }
        let scene = Scene {
            lines: &lines,
            ..scene
        };
        render_framed(&scene, views[k], size, f)
    });
    front.beside(&side)
}

/// One mesh of `render`, stood Y-up.
struct Panel {
    seq: surfmotion::mesh::MeshSequence,
    rig: Option<Embedding>,
    /// Facing (Y-up, horizontal).
    facing: DVec3,
    /// The frame drawn.
    pos: Vec<[f64; 3]>,
    /// Height of the floor line.
    floor: f64,
    /// The turn from the file's axes to Y-up.
    turn: glam::DQuat,
}

/// Runs `render`: every panel at one scale (the largest extent over all
/// meshes and both views), each centred horizontally on its own mesh, all
/// sharing one vertical centre.
/// The facing of frame `at`: each frame's shoulder axis over up to 150
/// frames either side, whose votes settle the sign (`facing_of_frames`).
fn facing_around(count: usize, at: usize, stood: &dyn Fn(usize) -> Vec<[f64; 3]>) -> DVec3 {
    let (from, to) = (at.saturating_sub(150), (at + 151).min(count));
    let around: Vec<Vec<[f64; 3]>> = (from..to).map(stood).collect();
    let refs: Vec<&[[f64; 3]]> = around.iter().map(Vec::as_slice).collect();
    facing_of_frames(&refs, at - from)
}

/// For a `SEQ:F` spec, the facing of frame F voted in the whole sequence
/// (stood up by `turn`); `None` for a file of its own or one that does not load.
fn facing_in_sequence(spec: &str, turn: glam::DQuat) -> Option<DVec3> {
    let (path, Some(at)) = surfmotion::mesh::io::split_frame_ref(spec) else {
        return None;
    };
    let whole = load_sequence(path.to_str()?, &LoadOptions::default()).ok()?;
    if at >= whole.frame_count() {
        return None;
    }
    let stood = |f: usize| -> Vec<[f64; 3]> {
        whole
            .frame(f)
            .iter()
            .map(|p| (turn * DVec3::from_array(*p)).to_array())
            .collect()
    };
    Some(facing_around(whole.frame_count(), at, &stood))
}

pub fn run(a: Args) -> anyhow::Result<()> {
    let size = a.size;
    let up = match &a.up {
        Some(u) => Some(
            axis_named(u)
                .ok_or_else(|| anyhow::anyhow!("--up {u:?}: expected +y, -y, +z, -z, +x or -x"))?,
        ),
        None => None,
    };
    // The picture's size against the memory budget, before anything is
    // read: front and side views of each mesh side by side (RGB), built
    // panel by panel (each joined copy is a new picture: twice the
    // picture at the peak), plus one panel's depth buffer.
    let (width, height) = (2 * a.mesh.len() as u128 * size as u128, size as u128);
    surfmotion::util::budget::check(
        || {
            format!(
                "{}: a picture of {} mesh(es) at --size {size} ({width} × {height} pixels)",
                a.output.display(),
                a.mesh.len()
            )
        },
        2 * width * height * 3 + height * height * 11,
    )
    .map_err(|e| anyhow::anyhow!("{e}; lower --size or draw fewer meshes"))?;
    let mut loaded = Vec::new();
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
        // The rig's skeleton on the frame drawn, in the file's axes.
        let joints = rig.as_ref().map(|r| r.frame_joints(s.frame(a.frame)));
        // Stood Y-up (the views assume it): by `--up`, else by the rig's
        // skeleton on this frame (pelvis to neck, snapped to an axis). The
        // rig's rest up held only for frames in the axes of the mesh it was
        // embedded in: a glTF's animation is in the scene's axes, its bind
        // pose in the mesh's (CesiumMan was drawn lying down).
        let up = up.or_else(|| {
            let (r, j) = (rig.as_ref()?, joints.as_ref()?);
            let spine = j[Canonical::Neck.index()] - j[Canonical::Pelvis.index()];
            Some(if spine.length() > 0.0 && spine.is_finite() {
                nearest_axis(spine)
            } else {
                nearest_axis(DVec3::from_array(r.up))
            })
        });
        let turn = surfmotion::tools::render::y_up_turn(up.unwrap_or(DVec3::Y));
        let stood = |f: usize| -> Vec<[f64; 3]> {
            s.frame(f)
                .iter()
                .map(|p| (turn * DVec3::from_array(*p)).to_array())
                .collect()
        };
        let pos = stood(a.frame);
        // Each panel faced from its own body: a result that turns is seen
        // from the front in every panel (one camera for all showed the
        // later frames of a turn from behind).
        let facing = match (&a.facing, &rig, &joints) {
            (Some(f), _, _) => turn * parse_axis(f)?,
            (None, Some(r), Some(j)) => {
                let j = j.map(|p| turn * p);
                surfmotion::tools::render::preview::rig_facing(r, &j)
                    .unwrap_or(turn * DVec3::from_array(r.facing))
            }
            // A `SEQ:F` spec loads frame F alone: its facing is voted over
            // the frames around it in the whole sequence (one frame's vote
            // drew the back of a straight walk as its front, CMU 02_02 on
            // samba frame 60).
            _ => match facing_in_sequence(mesh, turn) {
                Some(f) => f,
                None => facing_around(s.frame_count(), a.frame, &stood),
            },
        };
        // The floor: the lowest point of the whole sequence, stood up (a
        // jump is drawn above it).
        let floor = (0..s.frame_count())
            .flat_map(|f| s.frame(f).iter().map(|p| (turn * DVec3::from_array(*p)).y))
            .fold(f64::INFINITY, f64::min);
        loaded.push(Panel {
            seq: s,
            rig,
            facing,
            pos,
            floor,
            turn,
        });
    }
    // One scale across all panels.
    let bounds: Vec<[([f64; 2], [f64; 2]); 2]> = loaded
        .iter()
        .map(|p| [View::front(p.facing), View::side(p.facing)].map(|v| view_bounds(&p.pos, v)))
        .collect();
    let flat: Vec<([f64; 2], [f64; 2])> = bounds.iter().flatten().copied().collect();
    let (framings, _) = surfmotion::tools::render::shared_framing(&flat, size);
    let mut out: Option<Image> = None;
    for (i, p) in loaded.iter().enumerate() {
        let framing = [0, 1].map(|k| Some(framings[2 * i + k]));
        let img = draw_framed(
            &p.pos,
            p.seq.mesh().triangles(),
            p.rig.as_ref(),
            p.facing,
            size,
            framing,
            Some(p.floor),
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
    if a.json {
        let v = serde_json::json!({
            "output": a.output,
            "width": img.width,
            "height": img.height,
            "meshes": a.mesh,
            "frame": a.frame,
            "panels": loaded.iter().zip(&a.mesh).map(|(p, m)| {
                // In the file's own axes.
                let back = p.turn.inverse();
                serde_json::json!({
                    "mesh": m,
                    "facing": (back * p.facing).to_array(),
                    "up": (back * DVec3::Y).to_array(),
                    "floor": p.floor,
                })
            }).collect::<Vec<_>>(),
        });
        return crate::outln!("{}", serde_json::to_string_pretty(&v)?);
    }
    crate::outln!(
        "wrote {} ({}x{}: front and left side of each, one scale)",
        a.output.display(),
        img.width,
        img.height
    )?;
    Ok(())
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
    #[arg(long, default_value_t = 5, value_name = "N", value_parser = super::bounded_count(1, MAX_PREVIEW_FRAMES))]
    pub preview_frames: usize,
    /// Size of each panel of the contact sheet (pixels, square), 16 to 4096.
    #[arg(long, default_value_t = 300, value_name = "PX", value_parser = super::bounded_count(16, MAX_PREVIEW_SIZE))]
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
