//! `render`: front and side views of meshes (or frames of sequences) in
//! one picture, each stood Y-up and faced from its own body, all at one
//! scale; with a rig, coloured by body part with the skeleton drawn in.

use crate::embed::Embedding;
use crate::embed::axes::nearest_axis;
use crate::mesh::io::{LoadOptions, load_sequence};
use crate::rig::Canonical;
use crate::tools::render::{
    Framing, Image, Scene, View, facing_of_frames, label_colour, render_framed, view_bounds,
};
use glam::{DQuat, DVec3};
use std::path::PathBuf;

use super::JobError;

/// Largest [`RenderOptions::size`] (pixels): a picture of two 8192-pixel
/// views is 400 MB of pixels.
pub const MAX_SIZE: u64 = 8192;

/// Largest preview panel size (pixels, each panel square).
pub const MAX_PREVIEW_SIZE: u64 = 4096;

/// Most frames on a preview contact sheet.
pub const MAX_PREVIEW_FRAMES: u64 = 100;

/// What to draw.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// Meshes or sequences (a file, or `SEQ.pc2:FRAME`), drawn side by side.
    pub meshes: Vec<String>,
    /// The PNG written.
    pub output: PathBuf,
    /// A rig embedding: vertices coloured by part, its skeleton drawn.
    pub rig: Option<PathBuf>,
    /// Frame of a sequence to draw (default 0).
    pub frame: usize,
    /// Direction the character faces (`x`, `-x`, `z`, `-z`) in the file's
    /// axes (default: each panel's own, see [`render`]).
    pub facing: Option<String>,
    /// The meshes' up axis (`+y`, `-z`, ...; default: the rig skeleton's
    /// up on the frame drawn, else +y).
    pub up: Option<String>,
    /// Picture height in pixels (each view is square; default 600).
    pub size: usize,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            meshes: Vec::new(),
            output: PathBuf::new(),
            rig: None,
            frame: 0,
            facing: None,
            up: None,
            size: 600,
        }
    }
}

/// One panel of a picture, in the file's own axes.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PanelReport {
    /// The mesh drawn.
    pub mesh: String,
    /// The direction it faces.
    pub facing: [f64; 3],
    /// Its up axis.
    pub up: [f64; 3],
    /// Height of the floor line (the lowest point of the sequence, stood up).
    pub floor: f64,
}

/// What `render` wrote.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RenderReport {
    /// The PNG.
    pub output: PathBuf,
    /// Its width in pixels.
    pub width: usize,
    /// Its height in pixels.
    pub height: usize,
    /// The meshes drawn.
    pub meshes: Vec<String>,
    /// The frame drawn.
    pub frame: usize,
    /// Each panel.
    pub panels: Vec<PanelReport>,
}

/// `x`, `-x`, `z`, `-z`, `y`, `-y` (`+` allowed) as an axis.
pub(crate) fn axis_named(s: &str) -> Option<DVec3> {
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
pub(crate) fn draw_framed(
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
        // A body without a head (`Embedding::absent`) has no head bone to
        // draw: its joint lies above the neck's stump.
        let headless = r.absent().iter().any(|a| a == "head");
        for c in Canonical::ALL {
            if headless && c == Canonical::Head {
                continue;
            }
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
            lines.insert(0, crate::tools::render::floor_line(views[k], f, y, size));
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
    seq: crate::mesh::MeshSequence,
    rig: Option<Embedding>,
    /// Facing (Y-up, horizontal).
    facing: DVec3,
    /// The frame drawn.
    pos: Vec<[f64; 3]>,
    /// Height of the floor line.
    floor: f64,
    /// The turn from the file's axes to Y-up.
    turn: DQuat,
}

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
fn facing_in_sequence(spec: &str, turn: DQuat) -> Option<DVec3> {
    let (path, Some(at)) = crate::mesh::io::split_frame_ref(spec) else {
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

/// Loads `mesh` (its frame `o.frame`) as a panel stood Y-up by `up` (else
/// by the rig's skeleton on that frame) and faced by `o.facing` (else from
/// its own body).
fn panel(mesh: &str, o: &RenderOptions, up: Option<DVec3>) -> Result<Panel, JobError> {
    let s = load_sequence(mesh, &LoadOptions::default())?;
    if o.frame >= s.frame_count() {
        return Err(JobError::Usage(format!(
            "{}: frame {} requested, the sequence has {}",
            mesh,
            o.frame,
            s.frame_count()
        )));
    }
    let rig = match &o.rig {
        Some(p) => Some(Embedding::load(p, s.mesh().vertex_count())?),
        None => None,
    };
    // The rig's skeleton on the frame drawn, in the file's axes.
    let joints = rig.as_ref().map(|r| r.frame_joints(s.frame(o.frame)));
    // Stood Y-up (the views assume it): by `up`, else by the rig's
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
    let turn = crate::tools::render::y_up_turn(up.unwrap_or(DVec3::Y));
    let stood = |f: usize| -> Vec<[f64; 3]> {
        s.frame(f)
            .iter()
            .map(|p| (turn * DVec3::from_array(*p)).to_array())
            .collect()
    };
    let pos = stood(o.frame);
    // Each panel faced from its own body: a result that turns is seen
    // from the front in every panel (one camera for all showed the
    // later frames of a turn from behind).
    let facing = match (&o.facing, &rig, &joints) {
        (Some(f), _, _) => turn * axis(f, "facing", "x, -x, y, -y, z or -z")?,
        (None, Some(r), Some(j)) => {
            let j = j.map(|p| turn * p);
            crate::tools::render::preview::rig_facing(r, &j)
                .unwrap_or(turn * DVec3::from_array(r.facing))
        }
        // A `SEQ:F` spec loads frame F alone: its facing is voted over
        // the frames around it in the whole sequence (one frame's vote
        // drew the back of a straight walk as its front, CMU 02_02 on
        // samba frame 60).
        _ => match facing_in_sequence(mesh, turn) {
            Some(f) => f,
            None => facing_around(s.frame_count(), o.frame, &stood),
        },
    };
    // The floor: the lowest point of the whole sequence, stood up (a
    // jump is drawn above it).
    let floor = (0..s.frame_count())
        .flat_map(|f| s.frame(f).iter().map(|p| (turn * DVec3::from_array(*p)).y))
        .fold(f64::INFINITY, f64::min);
    Ok(Panel {
        seq: s,
        rig,
        facing,
        pos,
        floor,
        turn,
    })
}

/// `value` of the option `name` as an axis, or a usage error listing `expected`.
fn axis(value: &str, name: &str, expected: &str) -> Result<DVec3, JobError> {
    axis_named(value).ok_or_else(|| {
        JobError::Usage(format!(
            "`RenderOptions::{name}` {value:?}: expected {expected}"
        ))
    })
}

/// Draws every mesh of `o` into one PNG: each panel at one scale (the
/// largest extent over all meshes and both views), each centred
/// horizontally on its own mesh, all sharing one vertical centre. The
/// picture's size is checked against the memory budget before anything is
/// read.
pub fn render(o: &RenderOptions) -> Result<RenderReport, JobError> {
    let size = o.size;
    let up = match &o.up {
        Some(u) => Some(axis(u, "up", "+y, -y, +z, -z, +x or -x")?),
        None => None,
    };
    // Front and side views of each mesh side by side (RGB), built panel
    // by panel (each joined copy is a new picture: twice the picture at
    // the peak), plus one panel's depth buffer.
    let (width, height) = (2 * o.meshes.len() as u128 * size as u128, size as u128);
    crate::util::budget::check(
        || {
            format!(
                "{}: a picture of {} mesh(es) at `RenderOptions::size` {size} ({width} × {height} pixels)",
                o.output.display(),
                o.meshes.len()
            )
        },
        2 * width * height * 3 + height * height * 11,
    )
    .map_err(|e| {
        JobError::Usage(format!(
            "{e}; lower `RenderOptions::size` or draw fewer meshes"
        ))
    })?;
    let loaded = o
        .meshes
        .iter()
        .map(|m| panel(m, o, up))
        .collect::<Result<Vec<_>, _>>()?;
    // One scale across all panels.
    let bounds: Vec<[([f64; 2], [f64; 2]); 2]> = loaded
        .iter()
        .map(|p| [View::front(p.facing), View::side(p.facing)].map(|v| view_bounds(&p.pos, v)))
        .collect();
    let flat: Vec<([f64; 2], [f64; 2])> = bounds.iter().flatten().copied().collect();
    let (framings, _) = crate::tools::render::shared_framing(&flat, size);
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
        return Err(JobError::Usage("no mesh given".into()));
    };
    img.save_png(&o.output)?;
    let panels = loaded
        .iter()
        .zip(&o.meshes)
        .map(|(p, m)| {
            // In the file's own axes.
            let back = p.turn.inverse();
            PanelReport {
                mesh: m.clone(),
                facing: (back * p.facing).to_array(),
                up: (back * DVec3::Y).to_array(),
                floor: p.floor,
            }
        })
        .collect();
    Ok(RenderReport {
        output: o.output.clone(),
        width: img.width,
        height: img.height,
        meshes: o.meshes.clone(),
        frame: o.frame,
        panels,
    })
}
