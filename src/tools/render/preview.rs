//! Contact sheets of a result (`--preview` of retarget, synth and
//! transfer): a few evenly spaced frames, front views above and side views
//! below, all at one scale.

use super::{Image, label_colour};
use crate::embed::Embedding;
use crate::rig::Canonical;
use glam::DVec3;

/// What a contact sheet shows. The defaults are the CLI's.
#[derive(Clone, Debug)]
pub struct PreviewOptions {
    /// Frames on the sheet, evenly spaced (all frames when the result has
    /// fewer). Default 5.
    pub frames: usize,
    /// Size of each panel (pixels, square). Default 300.
    pub size: usize,
}

impl Default for PreviewOptions {
    fn default() -> Self {
        PreviewOptions {
            frames: 5,
            size: 300,
        }
    }
}

/// Why a contact sheet was not written.
#[derive(Debug, thiserror::Error)]
pub enum PreviewError {
    /// The sheet would not fit in memory (checked before drawing).
    #[error(transparent)]
    Budget(#[from] crate::util::budget::OverBudget),
    /// The picture could not be written.
    #[error(transparent)]
    Fs(#[from] crate::util::fsutil::FsError),
    /// The result has no frame.
    #[error("{}: nothing to preview", .0.display())]
    Empty(std::path::PathBuf),
}

/// The contact sheet of `positions` (frame-major, `n` vertices each, Y-up):
/// part colours from `rig`'s labels when given, the floor line at `floor`,
/// every panel facing `facing` when given, else each panel faced from its
/// own body by [`panel_facing`] (the rule of `surfmotion render`): a
/// result that turns is seen from the front in every panel.
#[allow(clippy::too_many_arguments)]
pub fn preview_image(
    positions: &[[f64; 3]],
    n: usize,
    triangles: &[[u32; 3]],
    rig: Option<&Embedding>,
    facing: Option<DVec3>,
    floor: Option<f64>,
    o: &PreviewOptions,
) -> Option<Image> {
    let count = positions.len() / n.max(1);
    if count == 0 {
        return None;
    }
    let frames: Vec<&[[f64; 3]]> = super::sheet_frames(count, o.frames)
        .into_iter()
        .map(|f| &positions[f * n..(f + 1) * n])
        .collect();
    let colours: Option<Vec<[u8; 3]>> = rig
        .filter(|r| r.labels.len() == n)
        .map(|r| r.labels.iter().map(|&l| label_colour(l as usize)).collect());
    let all: Vec<&[[f64; 3]]> = positions.chunks_exact(n.max(1)).collect();
    let facings: Vec<DVec3> = super::sheet_frames(count, o.frames)
        .into_iter()
        .map(|f| {
            facing.unwrap_or_else(|| panel_facing(&all, f, rig.filter(|r| r.labels.len() == n)))
        })
        .collect();
    Some(super::contact_sheet(
        &frames,
        triangles,
        colours.as_deref(),
        &facings,
        floor,
        o.size,
    ))
}

/// The facing of frame `at` of `frames` (Y-up), as `surfmotion render`
/// faces a panel: across the hips and shoulders of `rig`'s skeleton on the
/// frame ([`rig_facing`]), else (no rig, or a skeleton without width)
/// read off the mesh's shoulders, knees and feet over up to 150 frames
/// either side ([`super::facing_of_frames`]).
pub fn panel_facing(frames: &[&[[f64; 3]]], at: usize, rig: Option<&Embedding>) -> DVec3 {
    if let Some(f) = rig
        .zip(frames.get(at))
        .and_then(|(r, p)| rig_facing(r, &r.frame_joints(p)))
    {
        return f;
    }
    let (from, to) = (at.saturating_sub(150), (at + 151).min(frames.len()));
    super::facing_of_frames(&frames[from..to], at - from)
}

/// Writes [`preview_image`] to `path`; returns the image size.
#[allow(clippy::too_many_arguments)]
pub fn write_preview(
    path: &std::path::Path,
    positions: &[[f64; 3]],
    n: usize,
    triangles: &[[u32; 3]],
    rig: Option<&Embedding>,
    facing: Option<DVec3>,
    floor: Option<f64>,
    o: &PreviewOptions,
) -> Result<(usize, usize), PreviewError> {
    // Front and side views of each frame, RGB.
    let panels = o.frames.min(positions.len() / n.max(1)) as u128;
    let px = o.size as u128;
    crate::util::budget::check(
        || {
            format!(
                "{}: a contact sheet of {panels} frames at {px} px",
                path.display()
            )
        },
        panels * 2 * px * px * 3,
    )?;
    let img = preview_image(positions, n, triangles, rig, facing, floor, o)
        .ok_or_else(|| PreviewError::Empty(path.to_path_buf()))?;
    img.save_png(path)?;
    Ok((img.width, img.height))
}

/// The character's left-right line in `j` (hips and shoulders, each
/// normalised, across `up`).
fn left_of(j: &crate::pose::Pose, up: DVec3) -> DVec3 {
    let across = |l: Canonical, r: Canonical| {
        let d = j[l.index()] - j[r.index()];
        (d - up * d.dot(up)).normalize_or_zero()
    };
    across(Canonical::LHip, Canonical::RHip) + across(Canonical::LShoulder, Canonical::RShoulder)
}

/// The facing of a Y-up frame whose rig skeleton is `j`: across its hips
/// and shoulders (left × up), signed as the rig's own rest facing is
/// against its rest skeleton (so a rig whose sides are named the other
/// way round still faces forward). `None` when the skeleton has no width.
pub(crate) fn rig_facing(r: &Embedding, j: &crate::pose::Pose) -> Option<DVec3> {
    let rest_up = DVec3::from_array(r.up).normalize_or(DVec3::Y);
    let rest = left_of(&r.joints.map(DVec3::from_array), rest_up).cross(rest_up);
    let sign = if rest.dot(DVec3::from_array(r.facing)) < 0.0 {
        -1.0
    } else {
        1.0
    };
    let f = left_of(j, DVec3::Y).cross(DVec3::Y) * sign;
    (f.length() > 1e-9 && f.is_finite()).then(|| f.normalize())
}
