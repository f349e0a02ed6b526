//! One transfer job: a prepared scan, a source, the markers both know, the
//! factorisations and the marker motion — everything before the per-frame
//! solves of [`super::transfer`].

use super::confluent::{Confluent, ConfluentError};
use super::markers::Marker;
use super::scan::PreparedScan;
use super::source::{FootGround, MarkerMotion, TemplateMarkers, from_skeleton, from_template};
use crate::embed::Embedding;
use crate::embed::parts::Part;
use crate::mesh::{Bounds, MeshSequence};
use crate::pose::Pose;
use crate::pose::retarget::{
    ClipNeutral, Toes, clip_support, ground_tilt, leg_length, retarget_toes,
};
use glam::{DMat3, DQuat, DVec3};
use std::collections::HashMap;

/// What drives the scan: a clip's poses or a moving template, borrowed
/// (`Source` names a live input stream, [`crate::live::source::Source`]).
pub enum Driving<'a> {
    /// Canonical poses of a clip (metres, Y-up) and its neutral reference,
    /// as [`crate::drive::query::load_mocap`] gives them.
    Mocap(&'a [Pose], &'a ClipNeutral),
    /// A moving template mesh with its markers (paired with the scan's by
    /// name) and the frame that is its reference pose.
    Template {
        /// The template sequence.
        frames: &'a MeshSequence,
        /// Its markers.
        markers: &'a [Marker],
        /// Its reference frame.
        reference: usize,
        /// Rotation from the template's body frame to the scan's (the paper
        /// assumes both reference poses roughly aligned; see [`alignment`]).
        align: DQuat,
    },
}

/// The rotation taking one rig's body frame (left, up, facing) onto
/// another's: applied to the template's marker rotations and displacements
/// when template and scan face different ways in their reference poses.
pub fn alignment(from: &Embedding, to: &Embedding) -> DQuat {
    let basis = |e: &Embedding| {
        let up = DVec3::from_array(e.up).normalize_or(DVec3::Y);
        let f = DVec3::from_array(e.facing);
        let f = (f - up * f.dot(up)).normalize_or(up.any_orthonormal_vector());
        DMat3::from_cols(up.cross(f), up, f)
    };
    DQuat::from_mat3(&(basis(to) * basis(from).transpose())).normalize()
}

/// A job ready to solve.
pub struct Job {
    /// The prefactored scan.
    pub confluent: Confluent,
    /// Marker rotations and targets per frame.
    pub motion: MarkerMotion,
    /// Names of the markers used, in the order of `motion`.
    pub used: Vec<String>,
    /// Scan markers without a counterpart in the source.
    pub unpaired: usize,
}

/// Why a job cannot be set up.
#[derive(Debug, thiserror::Error)]
pub enum SetupError {
    /// Mocap needs the scan's skeleton.
    #[error("a mocap source needs the scan's skeleton: give landmarks")]
    NoSkeleton,
    /// Nothing pairs the scan with the source.
    #[error("{0}")]
    NoMarkers(String),
    /// A template marker is not on the template.
    #[error(
        "template marker {name}: triangle {triangle} is out of range (the template has {count})"
    )]
    TemplateTriangle {
        /// The marker.
        name: String,
        /// Its triangle.
        triangle: u32,
        /// The template's triangles.
        count: usize,
    },
    /// The template's reference frame does not exist.
    #[error("template reference frame {frame} is out of range (0..{count})")]
    Reference {
        /// The frame asked for.
        frame: usize,
        /// Frames of the template.
        count: usize,
    },
    /// Factorisation failed.
    #[error(transparent)]
    Confluent(#[from] ConfluentError),
    /// The output would not fit in memory (checked before allocating).
    #[error(transparent)]
    Budget(#[from] crate::util::budget::OverBudget),
}

/// Bytes of one marker in one frame of a [`MarkerMotion`] (a quaternion
/// and a target, `f64`).
const MOTION_BYTES: u128 = 56;

/// The motion of a scan's bone markers (those with a bone, in file order:
/// the markers [`Job::new`] uses for a mocap source) from a clip's poses.
/// For many clips on one scan: factor once with [`Job::new`], then call
/// this per clip.
pub fn mocap_motion(
    scan: &PreparedScan,
    poses: &[Pose],
    reference: &ClipNeutral,
) -> Result<MarkerMotion, SetupError> {
    let rig = scan.rig.as_ref().ok_or(SetupError::NoSkeleton)?;
    // The motion holds a rotation and a target per marker and frame
    // (whatever holds the output checks its own frames; a streamed
    // transfer holds none): refuse a clip whose motion cannot fit before
    // anything is allocated (issue 18, item 12).
    let used_markers = scan.markers.iter().filter(|m| m.bone.is_some()).count();
    crate::util::budget::check(
        || {
            format!(
                "the marker motion: {} frames × {} markers",
                crate::util::budget::thousands(poses.len() as u128),
                used_markers
            )
        },
        (poses.len() as u128) * (used_markers as u128) * MOTION_BYTES,
    )?;
    let p = scan.mesh.positions();
    let used: Vec<&Marker> = scan.markers.iter().filter(|m| m.bone.is_some()).collect();
    let rest: Pose = rig.joints.map(DVec3::from_array);
    // The kernel works Y-up, as the clip's canonical poses are: a scan
    // standing along another axis is turned onto Y for it and the frames
    // turned back (until this, a Z-up scan's walk climbed 2.5 m into the
    // air in 40 frames).
    let up = up_axis(rig);
    let to_scan = DQuat::from_rotation_arc(DVec3::Y, up);
    let upright = |p: &Pose, q: DQuat| -> Pose { p.map(|j| q * j) };
    let rest_y = upright(&rest, to_scan.inverse());
    // The markers on the toes turn with the toe joint: the toes bend.
    let mut frames = retarget_toes(&rest_y, &rest_y, reference, poses, Toes::Bending);
    if up != DVec3::Y {
        // Positions turn with the world; each joint's turn from the rest
        // pose is conjugated (the markers' targets are `p + g (c − rest)`).
        for (pose, g) in &mut frames {
            *pose = upright(pose, to_scan);
            for q in g.iter_mut() {
                *q = to_scan * *q * to_scan.inverse();
            }
        }
    }
    let bones: Vec<_> = used.iter().filter_map(|m| m.bone).collect();
    let cs: Vec<DVec3> = used
        .iter()
        .map(|m| {
            scan.mesh.triangles()[m.triangle as usize]
                .iter()
                .map(|&v| DVec3::from_array(p[v as usize]))
                .sum::<DVec3>()
                / 3.0
        })
        .collect();
    let mut motion = from_skeleton(&rest, &frames, &bones, &cs);
    motion.feet = foot_ground(scan, rig, poses, reference);
    Ok(motion)
}

/// The axis the scan stands along: its embedding's up snapped to the
/// nearest of ±X, ±Y, ±Z (scans are stored axis-aligned; the embedding's
/// estimate leans with the pose, e.g. 9° on the samba scan).
pub fn up_axis(rig: &Embedding) -> DVec3 {
    crate::embed::axes::nearest_axis(DVec3::from_array(rig.up))
}

/// Where the scan's feet touch the floor per frame ([`FootGround`]):
/// the clip's contacts as the kernel reads them (levelled,
/// [`crate::pose::retarget::Support::touch`]), each foot's vertices from
/// the rig's parts. `None` when the rig's labels are not the mesh's or a
/// foot has no vertex.
fn foot_ground(
    scan: &PreparedScan,
    rig: &Embedding,
    poses: &[Pose],
    reference: &ClipNeutral,
) -> Option<FootGround> {
    let p = scan.mesh.positions();
    if rig.labels.len() != p.len() || poses.is_empty() {
        return None;
    }
    let vertices = [Part::LFoot, Part::RFoot].map(|part| {
        (0..p.len() as u32)
            .filter(|&v| rig.labels[v as usize] as usize == part.index())
            .collect::<Vec<u32>>()
    });
    let up = up_axis(rig);
    let rest_low = [0, 1].map(|f| {
        vertices[f]
            .iter()
            .map(|&v| DVec3::from_array(p[v as usize]).dot(up))
            .fold(f64::INFINITY, f64::min)
    });
    if rest_low.iter().any(|h| !h.is_finite()) {
        return None;
    }
    let tilt = ground_tilt(poses);
    let levelled: Vec<Pose> = poses.iter().map(|m| m.map(|q| tilt * q)).collect();
    let support = clip_support(&levelled, leg_length(&reference.pose));
    let touch = (0..poses.len())
        .map(|i| {
            let t = [0, 1].map(|f| support.touch[f][i]);
            // `clip_support` gives a floor contact the floor itself.
            let block = t.iter().flatten().any(|&g| g != support.floor);
            let on = t.map(|g| g.is_some());
            (!block && (on[0] || on[1])).then_some(on)
        })
        .collect();
    Some(FootGround {
        up: up.to_array(),
        vertices,
        rest_low,
        touch,
        fps: 30.0,
    })
}

impl Job {
    /// Factors the scan for a mocap source (the markers that name a bone),
    /// once for any number of clips ([`mocap_motion`] per clip); returns
    /// the names of the markers used.
    pub fn factor_mocap(scan: &PreparedScan) -> Result<(Confluent, Vec<String>), SetupError> {
        let used: Vec<&Marker> = scan.markers.iter().filter(|m| m.bone.is_some()).collect();
        if used.is_empty() {
            return Err(SetupError::NoMarkers(
                "no marker names a bone: a mocap source drives markers through bones".into(),
            ));
        }
        let tris: Vec<u32> = used.iter().map(|m| m.triangle).collect();
        Ok((
            Confluent::new(&scan.mesh, &tris)?,
            used.iter().map(|m| m.name.clone()).collect(),
        ))
    }

    /// Pairs markers, factors the scan and computes the marker motion.
    pub fn new(scan: &PreparedScan, source: Driving<'_>) -> Result<Job, SetupError> {
        let p = scan.mesh.positions();
        let centroid = |m: &Marker| {
            scan.mesh.triangles()[m.triangle as usize]
                .iter()
                .map(|&v| DVec3::from_array(p[v as usize]))
                .sum::<DVec3>()
                / 3.0
        };
        match source {
            Driving::Mocap(poses, reference) => {
                let (confluent, used) = Job::factor_mocap(scan)?;
                let motion = mocap_motion(scan, poses, reference)?;
                Ok(Job {
                    confluent,
                    motion,
                    unpaired: scan.markers.len() - used.len(),
                    used,
                })
            }
            Driving::Template {
                frames,
                markers,
                reference,
                align,
            } => {
                let tm = frames.mesh();
                let count = frames.frame_count();
                if reference >= count {
                    return Err(SetupError::Reference {
                        frame: reference,
                        count,
                    });
                }
                let by_name: HashMap<&str, u32> = markers
                    .iter()
                    .map(|m| (m.name.as_str(), m.triangle))
                    .collect();
                let mut used = Vec::new();
                let mut template_tris = Vec::new();
                for m in &scan.markers {
                    if let Some(&t) = by_name.get(m.name.as_str()) {
                        if t as usize >= tm.triangle_count() {
                            return Err(SetupError::TemplateTriangle {
                                name: m.name.clone(),
                                triangle: t,
                                count: tm.triangle_count(),
                            });
                        }
                        used.push(m);
                        template_tris.push(t);
                    }
                }
                if used.is_empty() {
                    return Err(SetupError::NoMarkers(
                        "no scan marker has a template marker of the same name".into(),
                    ));
                }
                let tmk = TemplateMarkers::new(tm.triangles(), tm.vertex_count(), &template_tris);
                let refp = frames.frame(reference);
                let scale = scan.mesh.bounds().diagonal() / Bounds::of(refp).diagonal().max(1e-300);
                let all: Vec<&[[f64; 3]]> = (0..count).map(|f| frames.frame(f)).collect();
                let cs: Vec<DVec3> = used.iter().map(|m| centroid(m)).collect();
                let tris: Vec<u32> = used.iter().map(|m| m.triangle).collect();
                Ok(Job {
                    confluent: Confluent::new(&scan.mesh, &tris)?,
                    motion: from_template(&all, refp, tm.triangles(), &tmk, &cs, scale, align),
                    used: used.iter().map(|m| m.name.clone()).collect(),
                    unpaired: scan.markers.len() - used.len(),
                })
            }
        }
    }
}
