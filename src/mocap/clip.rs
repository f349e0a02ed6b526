//! The in-memory form of a skeletal motion clip.

use glam::{DQuat, DVec3};
use serde::Serialize;

/// Index of a joint inside one [`Clip`] (file order, parents before children).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub struct JointId(pub u32);

impl JointId {
    /// The index as `usize`, for slicing.
    #[inline]
    pub fn idx(self) -> usize {
        self.0 as usize
    }
}

/// One animation channel of a BVH joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Channel {
    /// Translation along x.
    Xposition,
    /// Translation along y.
    Yposition,
    /// Translation along z.
    Zposition,
    /// Rotation about x, degrees in files.
    Xrotation,
    /// Rotation about y, degrees in files.
    Yrotation,
    /// Rotation about z, degrees in files.
    Zrotation,
}

impl Channel {
    /// The usual root channels: position, then Z Y X rotation.
    pub(crate) const ROOT6: [Channel; 6] = [
        Channel::Xposition,
        Channel::Yposition,
        Channel::Zposition,
        Channel::Zrotation,
        Channel::Yrotation,
        Channel::Xrotation,
    ];
    /// The usual joint channels: Z Y X rotation.
    pub const ROT_ZYX: [Channel; 3] = [Channel::Zrotation, Channel::Yrotation, Channel::Xrotation];

    /// Parses a BVH channel name, case-insensitively.
    pub fn parse(s: &str) -> Option<Channel> {
        Some(match s.to_ascii_lowercase().as_str() {
            "xposition" => Channel::Xposition,
            "yposition" => Channel::Yposition,
            "zposition" => Channel::Zposition,
            "xrotation" => Channel::Xrotation,
            "yrotation" => Channel::Yrotation,
            "zrotation" => Channel::Zrotation,
            _ => return None,
        })
    }
    /// The BVH spelling.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Xposition => "Xposition",
            Channel::Yposition => "Yposition",
            Channel::Zposition => "Zposition",
            Channel::Xrotation => "Xrotation",
            Channel::Yrotation => "Yrotation",
            Channel::Zrotation => "Zrotation",
        }
    }
    /// True for the three rotation channels.
    pub fn is_rotation(self) -> bool {
        matches!(
            self,
            Channel::Xrotation | Channel::Yrotation | Channel::Zrotation
        )
    }
    /// Axis index 0, 1, 2 for x, y, z.
    pub fn axis(self) -> usize {
        match self {
            Channel::Xposition | Channel::Xrotation => 0,
            Channel::Yposition | Channel::Yrotation => 1,
            Channel::Zposition | Channel::Zrotation => 2,
        }
    }
}

/// One joint of the hierarchy.
#[derive(Debug, Clone, Serialize)]
pub struct Joint {
    /// Name as in the file.
    pub name: String,
    /// Parent joint; `None` for the root. Always a lower index than this joint.
    pub parent: Option<JointId>,
    /// Rest offset from the parent joint, in the parent's frame (file units).
    pub offset: DVec3,
    /// Channels in file order (BVH), used when writing BVH again.
    pub channels: Vec<Channel>,
    /// The end point of the bone that starts at this joint, in its own frame:
    /// the BVH `End Site` offset of a leaf, or the ASF bone vector.
    pub tail: Option<DVec3>,
}

impl Joint {
    /// True when the joint has any position channel (its translation animates).
    pub fn has_position_channels(&self) -> bool {
        self.channels.iter().any(|c| !c.is_rotation())
    }
}

/// Which points a clip's native "joint positions" are (see `mocap positions`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum PointConvention {
    /// BVH: the origin of every joint (End Sites excluded).
    JointOrigins,
    /// ASF/AMC: the root position plus the end point of every bone.
    BoneEnds,
}

/// Length unit of a clip's numbers, and why it was assumed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Units {
    /// Metres per file unit.
    pub metres_per_unit: f64,
    /// Short name (`"cm"`, `"CMU (1/0.45 inch)"`, ...).
    pub name: String,
    /// How the unit was decided (header, rig convention, skeleton height, user).
    pub reason: String,
}

/// The file's up axis, and why it was assumed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum UpAxis {
    /// +Y is up (BVH and ASF convention).
    Y,
    /// +Z is up (3ds Max, iClone/CC exports).
    Z,
}

/// A skeletal motion clip: hierarchy plus, per frame, every joint's local
/// rotation and translation. Numbers are in file units until
/// [`Clip::to_metres_y_up`] is called.
///
/// Invariant (checked by [`Clip::new`] and [`Clip::from_parts`]): joints are
/// in depth-first order with parents before children, `rotations` and
/// `translations` hold `frames × joints` finite entries (frame-major), and
/// the frame time is a positive number of seconds. Outside the library the
/// fields are read through accessors; an edit goes through [`ClipParts`].
#[derive(Debug, Clone, Serialize)]
pub struct Clip {
    /// Joints, parents first.
    pub(crate) joints: Vec<Joint>,
    /// Seconds per frame.
    pub(crate) frame_time: f64,
    /// Local rotation of each joint, frame-major (`frame * joints + joint`).
    #[serde(skip)]
    pub(crate) rotations: Vec<DQuat>,
    /// Local translation of each joint (the offset unless it has position channels).
    #[serde(skip)]
    pub(crate) translations: Vec<DVec3>,
    /// Unit of lengths.
    pub(crate) units: Units,
    /// Up axis of the file.
    pub(crate) up: UpAxis,
    /// Why the up axis was chosen.
    pub(crate) up_reason: String,
    /// What `mocap positions` reports for this clip.
    pub(crate) points: PointConvention,
    /// Problems found while reading that did not stop it (frame count mismatch, ...).
    pub(crate) warnings: Vec<String>,
}

/// A clip's data as plain fields: what [`Clip::into_parts`] gives and
/// [`Clip::from_parts`] checks. A caller that edits a clip (cuts frames,
/// renames, moves or re-roots joints, builds a variant) edits these and gets
/// back a clip that holds [`Clip`]'s invariant again, or the reason it does
/// not.
#[derive(Debug, Clone)]
pub struct ClipParts {
    /// Joints, parents first.
    pub joints: Vec<Joint>,
    /// Seconds per frame.
    pub frame_time: f64,
    /// Local rotation of each joint, frame-major (`frame * joints + joint`).
    pub rotations: Vec<DQuat>,
    /// Local translation of each joint, frame-major.
    pub translations: Vec<DVec3>,
    /// Unit of lengths.
    pub units: Units,
    /// Up axis of the file.
    pub up: UpAxis,
    /// Why the up axis was chosen.
    pub up_reason: String,
    /// What `mocap positions` reports for this clip.
    pub points: PointConvention,
    /// Problems found while reading that did not stop it.
    pub warnings: Vec<String>,
}

/// Error of [`Clip::new`] for an inconsistent clip.
#[derive(Debug, thiserror::Error)]
pub enum ClipError {
    /// A joint's parent is not before it.
    #[error("joint {index} ('{name}') has parent {parent}, which is not before it")]
    BadParent {
        /// Joint index.
        index: usize,
        /// Joint name.
        name: String,
        /// The offending parent index.
        parent: u32,
    },
    /// The per-frame arrays do not have `frames × joints` entries.
    #[error("{what} has {len} entries, not a multiple of {joints} joints")]
    BadLength {
        /// Which array.
        what: &'static str,
        /// Its length.
        len: usize,
        /// Joint count.
        joints: usize,
    },
    /// No joints.
    #[error("the clip has no joints")]
    Empty,
    /// A non-finite number.
    #[error("non-finite {what} at frame {frame}, joint {joint}")]
    NonFinite {
        /// Which quantity.
        what: &'static str,
        /// Frame index.
        frame: usize,
        /// Joint index.
        joint: usize,
    },
    /// The frame time is not a positive finite number.
    #[error("frame time {0} is not a positive number of seconds")]
    BadFrameTime(f64),
}

impl Clip {
    /// Builds a clip and checks its invariants.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        joints: Vec<Joint>,
        frame_time: f64,
        rotations: Vec<DQuat>,
        translations: Vec<DVec3>,
        units: Units,
        up: UpAxis,
        points: PointConvention,
    ) -> Result<Clip, ClipError> {
        let n = joints.len();
        if n == 0 {
            return Err(ClipError::Empty);
        }
        for (i, j) in joints.iter().enumerate() {
            if let Some(p) = j.parent
                && p.idx() >= i
            {
                return Err(ClipError::BadParent {
                    index: i,
                    name: j.name.clone(),
                    parent: p.0,
                });
            }
            if i > 0 && j.parent.is_none() {
                return Err(ClipError::BadParent {
                    index: i,
                    name: j.name.clone(),
                    parent: u32::MAX,
                });
            }
        }
        if rotations.len() % n != 0 {
            return Err(ClipError::BadLength {
                what: "rotations",
                len: rotations.len(),
                joints: n,
            });
        }
        if translations.len() != rotations.len() {
            return Err(ClipError::BadLength {
                what: "translations",
                len: translations.len(),
                joints: n,
            });
        }
        if !(frame_time.is_finite() && frame_time > 0.0) {
            return Err(ClipError::BadFrameTime(frame_time));
        }
        for (k, (q, t)) in rotations.iter().zip(&translations).enumerate() {
            if !q.is_finite() {
                return Err(ClipError::NonFinite {
                    what: "rotation",
                    frame: k / n,
                    joint: k % n,
                });
            }
            if !t.is_finite() {
                return Err(ClipError::NonFinite {
                    what: "translation",
                    frame: k / n,
                    joint: k % n,
                });
            }
        }
        Ok(Clip {
            joints,
            frame_time,
            rotations,
            translations,
            units,
            up,
            up_reason: String::new(),
            points,
            warnings: Vec::new(),
        })
    }

    /// The clip from its parts, when they hold the invariant ([`Clip`]).
    pub fn from_parts(p: ClipParts) -> Result<Clip, ClipError> {
        let mut c = Clip::new(
            p.joints,
            p.frame_time,
            p.rotations,
            p.translations,
            p.units,
            p.up,
            p.points,
        )?;
        c.up_reason = p.up_reason;
        c.warnings = p.warnings;
        Ok(c)
    }

    /// The clip's data as plain fields, to edit and check again with
    /// [`Clip::from_parts`].
    pub fn into_parts(self) -> ClipParts {
        ClipParts {
            joints: self.joints,
            frame_time: self.frame_time,
            rotations: self.rotations,
            translations: self.translations,
            units: self.units,
            up: self.up,
            up_reason: self.up_reason,
            points: self.points,
            warnings: self.warnings,
        }
    }

    /// The clip edited by `edit` and checked again ([`Clip::from_parts`]).
    pub fn edited(self, edit: impl FnOnce(&mut ClipParts)) -> Result<Clip, ClipError> {
        let mut p = self.into_parts();
        edit(&mut p);
        Clip::from_parts(p)
    }

    /// Joints, parents first.
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    /// Seconds per frame.
    pub fn frame_time(&self) -> f64 {
        self.frame_time
    }

    /// Local rotation of each joint, frame-major (`frame * joints + joint`).
    pub fn rotations(&self) -> &[DQuat] {
        &self.rotations
    }

    /// Local translation of each joint, frame-major.
    pub fn translations(&self) -> &[DVec3] {
        &self.translations
    }

    /// Unit of lengths.
    pub fn units(&self) -> &Units {
        &self.units
    }

    /// Up axis of the file.
    pub fn up(&self) -> UpAxis {
        self.up
    }

    /// Why the up axis was chosen.
    pub fn up_reason(&self) -> &str {
        &self.up_reason
    }

    /// What `mocap positions` reports for this clip.
    pub fn points(&self) -> PointConvention {
        self.points
    }

    /// Problems found while reading that did not stop it.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Number of joints.
    pub fn joint_count(&self) -> usize {
        self.joints.len()
    }

    /// Number of frames.
    pub fn frame_count(&self) -> usize {
        self.rotations.len() / self.joints.len().max(1)
    }

    /// Frames per second.
    pub fn fps(&self) -> f64 {
        1.0 / self.frame_time
    }

    /// Duration in seconds from the first to the last frame.
    pub fn duration(&self) -> f64 {
        self.frame_count().saturating_sub(1) as f64 * self.frame_time
    }

    /// Finds a joint by exact name.
    pub fn joint(&self, name: &str) -> Option<JointId> {
        self.joints
            .iter()
            .position(|j| j.name == name)
            .map(|i| JointId(i as u32))
    }

    /// Local rotations of one frame.
    pub fn frame_rotations(&self, frame: usize) -> &[DQuat] {
        let n = self.joints.len();
        &self.rotations[frame * n..(frame + 1) * n]
    }

    /// Local translations of one frame.
    pub fn frame_translations(&self, frame: usize) -> &[DVec3] {
        let n = self.joints.len();
        &self.translations[frame * n..(frame + 1) * n]
    }

    /// Names of the points [`Clip::points_at`] returns, in order.
    pub fn point_names(&self) -> Vec<String> {
        self.joints.iter().map(|j| j.name.clone()).collect()
    }

    /// Children lists, by joint.
    pub fn children(&self) -> Vec<Vec<JointId>> {
        let mut ch = vec![Vec::new(); self.joints.len()];
        for (i, j) in self.joints.iter().enumerate() {
            if let Some(p) = j.parent {
                ch[p.idx()].push(JointId(i as u32));
            }
        }
        ch
    }

    /// Scales every length (offsets, tails, translations) by `s`.
    pub(crate) fn scale_lengths(&mut self, s: f64) {
        for j in &mut self.joints {
            j.offset *= s;
            if let Some(t) = &mut j.tail {
                *t *= s;
            }
        }
        for t in &mut self.translations {
            *t *= s;
        }
    }

    /// Rotates the whole clip's coordinate frame by `r` (a change of basis):
    /// offsets, tails and translations are rotated and local rotations are
    /// conjugated, so the rest pose keeps its meaning in the new frame.
    pub(crate) fn change_basis(&mut self, r: DQuat) {
        let inv = r.inverse();
        for j in &mut self.joints {
            j.offset = r * j.offset;
            if let Some(t) = &mut j.tail {
                *t = r * *t;
            }
        }
        for t in &mut self.translations {
            *t = r * *t;
        }
        for q in &mut self.rotations {
            *q = (r * *q * inv).normalize();
        }
    }

    /// Converts the clip to metres and Y-up, in place, using `units` and `up`.
    pub fn to_metres_y_up(&mut self) {
        let s = self.units.metres_per_unit;
        if s != 1.0 {
            self.scale_lengths(s);
        }
        if self.up == UpAxis::Z {
            // (x, y, z) z-up → (x, z, -y) y-up: a -90° rotation about x.
            self.change_basis(DQuat::from_rotation_x(-std::f64::consts::FRAC_PI_2));
        }
        self.units = Units {
            metres_per_unit: 1.0,
            name: "m".into(),
            reason: format!("converted from {} ({})", self.units.name, self.units.reason),
        };
        self.up = UpAxis::Y;
    }
}
