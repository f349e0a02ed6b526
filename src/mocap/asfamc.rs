//! Acclaim ASF (skeleton) and AMC (motion) reader, as used by the CMU
//! Graphics Lab Motion Capture Database.
//!
//! Conventions (Acclaim; the same as CMU's own tools and AMCParser):
//! - Angles listed in an `axis` order string or a `dof`/`order` list are
//!   applied in the order listed: `axis a b c XYZ` means `C = Rz(c) Ry(b) Rx(a)`.
//! - A bone's world rotation is `W_b = W_parent · C_b · M_b · C_b⁻¹` with `M_b`
//!   the AMC rotation, and its end point is `start + W_b · (length · direction)`.
//!   A bone starts where its parent ends; root bones start at the root position.
//! - `:units length L` means file lengths are inches × L (CMU: 0.45, so one
//!   unit is 1/0.45 inch = 5.644 cm).
//!
//! In the [`Clip`] each bone becomes a joint at its start point, with the
//! parent's bone vector as offset and its own bone vector as `tail`; the clip's
//! points are the root position and the bone end points.

use super::bvh::quoted;
use super::clip::{Channel, Clip, Joint, JointId, PointConvention, Units, UpAxis};
use super::error::MocapError;
use super::euler;
use crate::util::fsutil::raise_warning;
use glam::{DQuat, DVec3};
use std::collections::HashMap;
use std::path::Path;

/// One bone of an ASF skeleton.
#[derive(Debug, Clone)]
pub struct AsfBone {
    /// Bone name (`root` for the root).
    pub name: String,
    /// Unit direction, in the global rest frame.
    pub direction: DVec3,
    /// Length in file units.
    pub length: f64,
    /// The local frame `C` (from `axis`).
    pub axis: DQuat,
    /// Degrees of freedom in AMC value order: 0..3 rotations rx, ry, rz;
    /// 3..6 translations tx, ty, tz; 6 the length channel `l`.
    pub dof: Vec<u8>,
    /// Parent bone index (`None` for the root).
    pub parent: Option<usize>,
}

/// A parsed ASF skeleton, bones in depth-first order with the root first.
#[derive(Debug, Clone)]
pub struct AsfSkeleton {
    /// Bones, root first, parents before children.
    pub bones: Vec<AsfBone>,
    /// Root position from `:root position`.
    pub root_position: DVec3,
    /// Inches per file unit multiplier from `:units length` (1.0 if absent).
    pub length_scale: f64,
    /// Whether `:units length` was present.
    pub length_declared: bool,
    /// True when angles are in degrees (`:units angle deg`, the default).
    pub degrees: bool,
}

fn dof_code(s: &str) -> Option<u8> {
    Some(match s.to_ascii_lowercase().as_str() {
        "rx" => 0,
        "ry" => 1,
        "rz" => 2,
        "tx" => 3,
        "ty" => 4,
        "tz" => 5,
        "l" => 6,
        _ => return None,
    })
}

fn order_axes(s: &str) -> Option<Vec<usize>> {
    let v: Option<Vec<usize>> = s
        .chars()
        .map(|c| match c.to_ascii_uppercase() {
            'X' => Some(0),
            'Y' => Some(1),
            'Z' => Some(2),
            _ => None,
        })
        .collect();
    v.filter(|v| v.len() == 3)
}

/// Rotation applying the listed axes in order: `R = R_last · ... · R_first`.
fn applied_in_order(axes: &[usize], radians: &[f64]) -> DQuat {
    let mut q = DQuat::IDENTITY;
    for (&a, &r) in axes.iter().zip(radians) {
        q = euler::axis_rotation(a, r) * q;
    }
    q
}

fn num(tok: &str, path: &Path, line: usize) -> Result<f64, MocapError> {
    let max = super::bvh::MAX_ABS_VALUE;
    match tok.parse::<f64>() {
        Ok(v) if v.is_finite() && v.abs() > max => Err(MocapError::parse(
            path,
            line,
            format!("value {tok} is beyond ±{max:e}"),
        )),
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(MocapError::parse(
            path,
            line,
            format!("expected a number, found {}", quoted(tok)),
        )),
    }
}

/// Parses ASF text.
///
/// The steps, in order: `AsfText::read_line` for every line (sections
/// `:units`, `:root`, `:bonedata`, `:hierarchy`), `index_bones` (names
/// unique, none called `root`), `link_hierarchy` (every edge names known
/// bones, one parent each) and `build_tree` (bones parents first, from
/// the root, with their axes in radians).
pub fn parse_asf(text: &str, path: &Path) -> Result<AsfSkeleton, MocapError> {
    let mut asf = AsfText::default();
    for (i, raw) in text.lines().enumerate() {
        asf.read_line(i + 1, raw, path)?;
    }
    if asf.cur.is_some() {
        return Err(MocapError::invalid(
            path,
            "file ends inside a bone's begin/end",
        ));
    }
    if asf.bones.is_empty() {
        return Err(MocapError::invalid(
            path,
            "no bones (no ':bonedata' section with begin/end blocks)",
        ));
    }
    let index = index_bones(&asf.bones, path)?;
    let children = link_hierarchy(&asf.edges, &index, asf.bones.len(), path)?;
    let bones = build_tree(&asf, &children, path)?;
    Ok(AsfSkeleton {
        bones,
        root_position: asf.root_position,
        length_scale: asf.length_scale,
        length_declared: asf.length_declared,
        degrees: asf.degrees,
    })
}

/// A section of an ASF file.
#[derive(PartialEq, Default)]
enum Sec {
    #[default]
    None,
    Units,
    Root,
    Bones,
    Hier,
    Other,
}

/// A bone of `:bonedata` as written.
struct RawBone {
    name: String,
    dir: DVec3,
    len: f64,
    axis: [f64; 3],
    order: Vec<usize>,
    dof: Vec<u8>,
    line: usize,
}

/// What the lines of an ASF file say, as they are read.
struct AsfText {
    sec: Sec,
    length_scale: f64,
    length_declared: bool,
    degrees: bool,
    root_axis_order: Vec<usize>,
    root_orient: [f64; 3],
    root_position: DVec3,
    root_dof: Vec<u8>,
    bones: Vec<RawBone>,
    /// The bone between `begin` and `end`.
    cur: Option<RawBone>,
    /// `(parent, child, line)` of `:hierarchy`.
    edges: Vec<(String, String, usize)>,
}

impl Default for AsfText {
    fn default() -> Self {
        AsfText {
            sec: Sec::None,
            length_scale: 1.0,
            length_declared: false,
            degrees: true,
            root_axis_order: vec![0, 1, 2],
            root_orient: [0.0; 3],
            root_position: DVec3::ZERO,
            root_dof: vec![3, 4, 5, 0, 1, 2],
            bones: Vec::new(),
            cur: None,
            edges: Vec::new(),
        }
    }
}

impl AsfText {
    /// One line (1-based `line`): comments after `#` dropped, `:section`
    /// switches, else the line goes to its section's reader.
    fn read_line(&mut self, line: usize, raw: &str, path: &Path) -> Result<(), MocapError> {
        let l = raw.split('#').next().unwrap_or("").trim();
        if l.is_empty() {
            return Ok(());
        }
        if let Some(k) = l.strip_prefix(':') {
            let key = k
                .split_whitespace()
                .next()
                .unwrap_or("")
                .to_ascii_lowercase();
            self.sec = match key.as_str() {
                "units" => Sec::Units,
                "root" => Sec::Root,
                "bonedata" => Sec::Bones,
                "hierarchy" => Sec::Hier,
                _ => Sec::Other,
            };
            return Ok(());
        }
        let toks: Vec<&str> = l.split_whitespace().collect();
        let key = toks[0].to_ascii_lowercase();
        match self.sec {
            Sec::Units => self.units_line(&key, &toks, line, path),
            Sec::Root => self.root_line(&key, &toks, l, line, path),
            Sec::Bones => self.bone_line(&key, &toks, line, path),
            Sec::Hier => {
                match key.as_str() {
                    "begin" | "end" => {}
                    _ => {
                        for c in &toks[1..] {
                            self.edges.push((toks[0].to_string(), c.to_string(), line));
                        }
                    }
                }
                Ok(())
            }
            Sec::None | Sec::Other => Ok(()),
        }
    }

    /// `length s` and `angle deg|rad` of `:units`.
    fn units_line(
        &mut self,
        key: &str,
        toks: &[&str],
        line: usize,
        path: &Path,
    ) -> Result<(), MocapError> {
        match key {
            "length" if toks.len() > 1 => {
                self.length_scale = num(toks[1], path, line)?;
                if self.length_scale <= 0.0 {
                    return Err(MocapError::parse(
                        path,
                        line,
                        "length unit must be positive",
                    ));
                }
                self.length_declared = true;
            }
            "angle" if toks.len() > 1 => {
                self.degrees = !toks[1].to_ascii_lowercase().starts_with("rad")
            }
            _ => {}
        }
        Ok(())
    }

    /// `order`, `axis`, `position` and `orientation` of `:root` (`l` the
    /// whole line, for the error).
    fn root_line(
        &mut self,
        key: &str,
        toks: &[&str],
        l: &str,
        line: usize,
        path: &Path,
    ) -> Result<(), MocapError> {
        match key {
            "order" => {
                let mut d = Vec::new();
                for t in &toks[1..] {
                    d.push(dof_code(t).ok_or_else(|| {
                        MocapError::parse(path, line, format!("unknown root channel {}", quoted(t)))
                    })?);
                }
                self.root_dof = d;
            }
            "axis" if toks.len() > 1 => {
                self.root_axis_order = order_axes(toks[1]).ok_or_else(|| {
                    MocapError::parse(path, line, format!("bad axis order {}", quoted(toks[1])))
                })?;
            }
            "position" | "orientation" if toks.len() >= 4 => {
                let v = [
                    num(toks[1], path, line)?,
                    num(toks[2], path, line)?,
                    num(toks[3], path, line)?,
                ];
                if key == "position" {
                    self.root_position = DVec3::from(v);
                } else {
                    self.root_orient = v;
                }
            }
            _ => {
                return Err(MocapError::parse(
                    path,
                    line,
                    format!("unexpected {} in :root", quoted(l)),
                ));
            }
        }
        Ok(())
    }

    /// `begin`, `end` and the fields of a bone in `:bonedata`.
    fn bone_line(
        &mut self,
        key: &str,
        toks: &[&str],
        line: usize,
        path: &Path,
    ) -> Result<(), MocapError> {
        match key {
            "begin" => {
                if self.cur.is_some() {
                    return Err(MocapError::parse(path, line, "'begin' inside a bone"));
                }
                self.cur = Some(RawBone {
                    name: String::new(),
                    dir: DVec3::ZERO,
                    len: 0.0,
                    axis: [0.0; 3],
                    order: vec![0, 1, 2],
                    dof: Vec::new(),
                    line,
                });
            }
            "end" => {
                let b = self
                    .cur
                    .take()
                    .ok_or_else(|| MocapError::parse(path, line, "'end' without 'begin'"))?;
                if b.name.is_empty() {
                    return Err(MocapError::parse(path, b.line, "bone without a name"));
                }
                if b.len > 0.0 && b.dir.length_squared() == 0.0 {
                    return Err(MocapError::parse(
                        path,
                        b.line,
                        format!("bone {} has a length but no direction", quoted(&b.name)),
                    ));
                }
                if self.bones.len() > 100_000 {
                    return Err(MocapError::parse(path, line, "too many bones"));
                }
                self.bones.push(b);
            }
            _ => {
                let Some(b) = self.cur.as_mut() else {
                    return Err(MocapError::parse(
                        path,
                        line,
                        format!("{} outside begin/end", quoted(toks[0])),
                    ));
                };
                match key {
                    "name" if toks.len() > 1 => b.name = toks[1].to_string(),
                    "direction" if toks.len() >= 4 => {
                        b.dir = DVec3::new(
                            num(toks[1], path, line)?,
                            num(toks[2], path, line)?,
                            num(toks[3], path, line)?,
                        )
                    }
                    "length" if toks.len() > 1 => {
                        b.len = num(toks[1], path, line)?;
                        if b.len < 0.0 {
                            return Err(MocapError::parse(
                                path,
                                line,
                                format!("negative bone length {}", toks[1]),
                            ));
                        }
                    }
                    "axis" if toks.len() >= 4 => {
                        b.axis = [
                            num(toks[1], path, line)?,
                            num(toks[2], path, line)?,
                            num(toks[3], path, line)?,
                        ];
                        if let Some(o) = toks.get(4) {
                            b.order = order_axes(o).ok_or_else(|| {
                                MocapError::parse(
                                    path,
                                    line,
                                    format!("bad axis order {}", quoted(o)),
                                )
                            })?;
                        }
                    }
                    "dof" => {
                        for t in &toks[1..] {
                            b.dof.push(dof_code(t).ok_or_else(|| {
                                MocapError::parse(path, line, format!("unknown dof {}", quoted(t)))
                            })?);
                        }
                    }
                    // id, limits, bodymass, cofmass, limit rows "(lo hi)" and
                    // anything else are not needed.
                    _ => {}
                }
            }
        }
        Ok(())
    }
}

/// Bone name → index in `bones`; refuses duplicates and a bone called
/// `root`.
fn index_bones<'a>(
    bones: &'a [RawBone],
    path: &Path,
) -> Result<HashMap<&'a str, usize>, MocapError> {
    let mut index: HashMap<&str, usize> = HashMap::new();
    for (i, b) in bones.iter().enumerate() {
        if b.name.eq_ignore_ascii_case("root") {
            return Err(MocapError::parse(
                path,
                b.line,
                "a bone may not be called 'root'",
            ));
        }
        if index.insert(b.name.as_str(), i).is_some() {
            return Err(MocapError::parse(
                path,
                b.line,
                format!("duplicate bone {}", quoted(&b.name)),
            ));
        }
    }
    Ok(index)
}

/// Children of each parent name (`root` or a bone) from the `:hierarchy`
/// edges, in the order listed; every bone has at most one parent.
fn link_hierarchy<'a>(
    edges: &'a [(String, String, usize)],
    index: &HashMap<&str, usize>,
    bone_count: usize,
    path: &Path,
) -> Result<HashMap<&'a str, Vec<usize>>, MocapError> {
    let mut children: HashMap<&str, Vec<usize>> = HashMap::new();
    let mut has_parent = vec![false; bone_count];
    for (p, c, line) in edges {
        let ci = *index.get(c.as_str()).ok_or_else(|| {
            MocapError::parse(
                path,
                *line,
                format!("hierarchy names unknown bone {}", quoted(c)),
            )
        })?;
        if p != "root" && !index.contains_key(p.as_str()) {
            return Err(MocapError::parse(
                path,
                *line,
                format!("hierarchy names unknown bone {}", quoted(p)),
            ));
        }
        if has_parent[ci] {
            return Err(MocapError::parse(
                path,
                *line,
                format!("bone {} has two parents", quoted(c)),
            ));
        }
        has_parent[ci] = true;
        children.entry(p.as_str()).or_default().push(ci);
    }
    Ok(children)
}

/// The bones from the root down (parents before children, the first listed
/// child first), directions normalised and axes turned to rotations; every
/// bone must be reached.
fn build_tree(
    asf: &AsfText,
    children: &HashMap<&str, Vec<usize>>,
    path: &Path,
) -> Result<Vec<AsfBone>, MocapError> {
    let bones = &asf.bones;
    let deg = |v: f64| if asf.degrees { v.to_radians() } else { v };
    let root = AsfBone {
        name: "root".into(),
        direction: DVec3::ZERO,
        length: 0.0,
        axis: applied_in_order(&asf.root_axis_order, &asf.root_orient.map(deg)),
        dof: asf.root_dof.clone(),
        parent: None,
    };
    let mut out = vec![root];
    let mut stack: Vec<(&str, usize)> = vec![("root", 0)];
    while let Some((name, out_idx)) = stack.pop() {
        if let Some(ch) = children.get(name) {
            // Reverse so the first listed child is visited first.
            for &ci in ch.iter().rev() {
                let b = &bones[ci];
                let dir = if b.dir.length_squared() > 0.0 {
                    b.dir.normalize()
                } else {
                    DVec3::ZERO
                };
                out.push(AsfBone {
                    name: b.name.clone(),
                    direction: dir,
                    length: b.len,
                    axis: applied_in_order(&b.order, &b.axis.map(deg)),
                    dof: b.dof.clone(),
                    parent: Some(out_idx),
                });
                stack.push((b.name.as_str(), out.len() - 1));
            }
        }
    }
    // The pop order above is depth-first but children were pushed after their
    // parent was emitted, so parents precede children. Check everything was reached.
    if out.len() != bones.len() + 1 {
        let missing: Vec<&str> = bones
            .iter()
            .filter(|b| !out.iter().any(|o| o.name == b.name))
            .map(|b| b.name.as_str())
            .collect();
        return Err(MocapError::invalid(
            path,
            format!(
                "bones not connected to the root in :hierarchy: {}",
                missing.join(", ")
            ),
        ));
    }
    Ok(out)
}

/// Reads an ASF file.
pub(crate) fn read_asf(path: &Path) -> Result<AsfSkeleton, MocapError> {
    parse_asf(&crate::util::fsutil::read_text(path)?, path)
}

impl AsfSkeleton {
    fn units(&self) -> Units {
        let inch = 0.0254;
        if self.length_declared {
            Units {
                metres_per_unit: inch / self.length_scale,
                name: format!("1/{} inch", self.length_scale),
                reason: format!(
                    "ASF ':units length {}' (Acclaim: inches × {})",
                    self.length_scale, self.length_scale
                ),
            }
        } else {
            Units {
                metres_per_unit: inch,
                name: "inch".into(),
                reason: "ASF has no ':units length'; assumed inches".into(),
            }
        }
    }

    /// Builds a clip from per-frame bone values (`values[frame][bone]` in dof
    /// order, angles already in radians).
    fn to_clip(
        &self,
        frames: &[Vec<Vec<f64>>],
        frame_time: f64,
        path: &Path,
    ) -> Result<Clip, MocapError> {
        let n = self.bones.len();
        let joints: Vec<Joint> = self
            .bones
            .iter()
            .map(|b| {
                let offset = match b.parent {
                    None => self.root_position,
                    Some(p) => self.bones[p].direction * self.bones[p].length,
                };
                let channels = if b.parent.is_none() {
                    Channel::ROOT6.to_vec()
                } else {
                    Channel::ROT_ZYX.to_vec()
                };
                Joint {
                    name: b.name.clone(),
                    parent: b.parent.map(|p| JointId(p as u32)),
                    offset,
                    channels,
                    tail: Some(b.direction * b.length),
                }
            })
            .collect();
        let mut rotations = Vec::with_capacity(frames.len() * n);
        let mut translations = Vec::with_capacity(frames.len() * n);
        for f in frames {
            for (bi, b) in self.bones.iter().enumerate() {
                let vals = &f[bi];
                let mut axes = Vec::with_capacity(3);
                let mut angles = Vec::with_capacity(3);
                let mut t = joints[bi].offset;
                for (&d, &v) in b.dof.iter().zip(vals) {
                    match d {
                        0..=2 => {
                            axes.push(d as usize);
                            angles.push(v);
                        }
                        3..=5 => {
                            t[(d - 3) as usize] = if b.parent.is_none() {
                                v
                            } else {
                                t[(d - 3) as usize] + v
                            }
                        }
                        _ => {}
                    }
                }
                let m = applied_in_order(&axes, &angles);
                rotations.push((b.axis * m * b.axis.inverse()).normalize());
                translations.push(t);
            }
        }
        let mut clip = Clip::new(
            joints,
            frame_time,
            rotations,
            translations,
            self.units(),
            UpAxis::Y,
            PointConvention::BoneEnds,
        )
        .map_err(|e| MocapError::invalid(path, e.to_string()))?;
        clip.up_reason = "ASF is Y-up".into();
        Ok(clip)
    }

    /// The skeleton in its rest pose, as a one-frame clip.
    pub(crate) fn rest_clip(&self, path: &Path) -> Result<Clip, MocapError> {
        let zero: Vec<Vec<f64>> = self.bones.iter().map(|b| vec![0.0; b.dof.len()]).collect();
        let mut frame = zero;
        frame[0] = self.bones[0]
            .dof
            .iter()
            .map(|&d| {
                if (3..6).contains(&d) {
                    self.root_position[(d - 3) as usize]
                } else {
                    0.0
                }
            })
            .collect();
        self.to_clip(&[frame], 1.0 / 120.0, path)
    }
}

/// Options for AMC reading.
#[derive(Debug, Clone, Default)]
pub struct AmcOptions {
    /// Frames per second (AMC files do not store it). Default: 120, CMU's rate.
    pub fps: Option<f64>,
}

/// Parses AMC text against a skeleton.
pub fn parse_amc(
    text: &str,
    path: &Path,
    skel: &AsfSkeleton,
    opts: &AmcOptions,
) -> Result<Clip, MocapError> {
    let index: HashMap<&str, usize> = skel
        .bones
        .iter()
        .enumerate()
        .map(|(i, b)| (b.name.as_str(), i))
        .collect();
    let frame_count = amc_frame_count(text, path, skel)?;
    let mut reader = AmcFrames::new(skel, path, frame_count);
    reader.read(text, &index)?;
    let AmcFrames {
        frames,
        mut warnings,
        ..
    } = reader;
    if frames.is_empty() {
        return Err(MocapError::invalid(path, "no frames"));
    }
    let fps = opts.fps.unwrap_or(120.0);
    if !crate::util::budget::is_frame_rate(fps) {
        return Err(MocapError::invalid(
            path,
            format!(
                "`AmcOptions::fps` {fps}: expected a frame rate in [{}, {}]",
                crate::util::budget::MIN_FPS,
                crate::util::budget::MAX_FPS
            ),
        ));
    }
    let mut clip = skel.to_clip(&frames, 1.0 / fps, path)?;
    if opts.fps.is_none() {
        raise_warning(
            &mut warnings,
            path,
            "AMC stores no frame rate; assumed 120 fps (CMU); override with `AmcOptions::fps`"
                .into(),
        );
    }
    clip.warnings = warnings;
    Ok(clip)
}

/// The clip's size, from the frame-number lines, checked against the
/// memory budget before anything is held: a 6 MB file of frame numbers
/// alone asked for 10 GB.
fn amc_frame_count(text: &str, path: &Path, skel: &AsfSkeleton) -> Result<usize, MocapError> {
    let is_frame_number = |raw: &str| {
        let l = raw.split('#').next().unwrap_or("").trim();
        !l.is_empty() && l.bytes().all(|b| b.is_ascii_digit())
    };
    let frame_count = text.lines().filter(|l| is_frame_number(l)).count();
    let per_frame: u128 = 24
        + skel
            .bones
            .iter()
            .map(|b| 24 + 8 * b.dof.len() as u128 + 56)
            .sum::<u128>();
    crate::util::budget::check(
        || {
            format!(
                "{} frames × {} bones",
                crate::util::budget::thousands(frame_count as u128),
                crate::util::budget::thousands(skel.bones.len() as u128)
            )
        },
        frame_count as u128 * per_frame,
    )
    .map_err(|e| MocapError::invalid(path, e.to_string()))?;
    Ok(frame_count)
}

/// The AMC frames as they are read: every bone's values per frame (its
/// ASF dof order, angles in radians), the frame being read and which
/// bones it has had, and the warnings.
struct AmcFrames<'a> {
    skel: &'a AsfSkeleton,
    path: &'a Path,
    degrees: bool,
    frames: Vec<Vec<Vec<f64>>>,
    cur: Option<Vec<Vec<f64>>>,
    seen: Vec<bool>,
    warnings: Vec<String>,
    missing_warned: bool,
    empty_frame: Vec<Vec<f64>>,
}

impl<'a> AmcFrames<'a> {
    fn new(skel: &'a AsfSkeleton, path: &'a Path, frame_count: usize) -> Self {
        AmcFrames {
            skel,
            path,
            degrees: skel.degrees,
            frames: Vec::with_capacity(frame_count),
            cur: None,
            seen: vec![false; skel.bones.len()],
            warnings: Vec::new(),
            missing_warned: false,
            empty_frame: skel.bones.iter().map(|b| vec![0.0; b.dof.len()]).collect(),
        }
    }

    /// Every line of `text` (`index`: the bones by name), then the last
    /// frame finished.
    fn read(&mut self, text: &str, index: &HashMap<&str, usize>) -> Result<(), MocapError> {
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let l = raw.split('#').next().unwrap_or("").trim();
            if l.is_empty() {
                continue;
            }
            if let Some(k) = l.strip_prefix(':') {
                let k = k.trim().to_ascii_uppercase();
                if k.starts_with("RADIANS") {
                    self.degrees = false;
                } else if k.starts_with("DEGREES") {
                    self.degrees = true;
                }
                continue;
            }
            let toks: Vec<&str> = l.split_whitespace().collect();
            if toks.len() == 1 && toks[0].bytes().all(|b| b.is_ascii_digit()) {
                self.finish();
                self.cur = Some(self.empty_frame.clone());
                continue;
            }
            self.bone_line(&toks, line, index)?;
        }
        self.finish();
        Ok(())
    }

    /// One bone's values (`toks`: its name, then one value per dof) into
    /// the current frame.
    fn bone_line(
        &mut self,
        toks: &[&str],
        line: usize,
        index: &HashMap<&str, usize>,
    ) -> Result<(), MocapError> {
        let path = self.path;
        let Some(f) = self.cur.as_mut() else {
            return Err(MocapError::parse(
                path,
                line,
                format!("{} before the first frame number", quoted(toks[0])),
            ));
        };
        let bi = *index.get(toks[0]).ok_or_else(|| {
            MocapError::parse(
                path,
                line,
                format!("bone {} is not in the ASF", quoted(toks[0])),
            )
        })?;
        let dof = &self.skel.bones[bi].dof;
        if toks.len() - 1 != dof.len() {
            return Err(MocapError::parse(
                path,
                line,
                format!(
                    "bone {} has {} values, its ASF dof lists {}",
                    quoted(toks[0]),
                    toks.len() - 1,
                    dof.len()
                ),
            ));
        }
        for (k, (&d, t)) in dof.iter().zip(&toks[1..]).enumerate() {
            let v = num(t, path, line)?;
            f[bi][k] = if d < 3 && self.degrees {
                v.to_radians()
            } else {
                v
            };
        }
        self.seen[bi] = true;
        Ok(())
    }

    /// The current frame (if any) pushed, with a warning (once) naming
    /// the bones it had no values for.
    fn finish(&mut self) {
        if let Some(f) = self.cur.take() {
            if !self.missing_warned && self.seen.iter().any(|s| !s) {
                let names: Vec<&str> = self
                    .skel
                    .bones
                    .iter()
                    .zip(self.seen.iter())
                    .filter(|(b, s)| !**s && !b.dof.is_empty())
                    .map(|(b, _)| b.name.as_str())
                    .collect();
                if !names.is_empty() {
                    raise_warning(
                        &mut self.warnings,
                        self.path,
                        format!(
                            "frame {} has no values for {}; zero used",
                            self.frames.len() + 1,
                            names.join(", ")
                        ),
                    );
                    self.missing_warned = true;
                }
            }
            self.frames.push(f);
            self.seen.iter_mut().for_each(|s| *s = false);
        }
    }
}

/// Reads an AMC file with its ASF.
pub(crate) fn read_amc(amc: &Path, asf: &Path, opts: &AmcOptions) -> Result<Clip, MocapError> {
    let skel = read_asf(asf)?;
    parse_amc(&crate::util::fsutil::read_text(amc)?, amc, &skel, opts)
}
