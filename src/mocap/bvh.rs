//! BVH (Biovision Hierarchy) reader and writer.
//!
//! The reader is our own rather than `bvh_anim`: real files are sloppy in
//! ways that crate either rejects (a `Frames:` count that disagrees with the
//! data) or panics on (malformed keywords), and we need every error to name
//! the file and line. It accepts per-joint channel orders, position channels
//! on any joint (Bandai Namco writes six on every joint: the position
//! channels then *replace* the offset, as in bvhio and Blender), lowercase
//! `End site`, CRLF, tabs, braces on the keyword's line, scientific notation,
//! and a truncated last frame (dropped with a warning). Memory is bounded by
//! the file size: header counts are never used to allocate.

use super::clip::{Channel, Clip, Joint, JointId, PointConvention, Units, UpAxis};
use super::error::MocapError;
use super::euler;
use crate::fsutil::raise_warning;
use glam::{DQuat, DVec3};
use std::fmt::Write as _;
use std::path::Path;

/// Options for reading BVH.
#[derive(Debug, Clone, Default)]
pub struct BvhOptions {
    /// Frames per second to use instead of the file's `Frame Time`.
    /// Default: `None` (use the file's).
    pub fps: Option<f64>,
}

struct Tokens<'a> {
    lines: Vec<(usize, &'a str)>,
    li: usize,
    toks: Vec<&'a str>,
    ti: usize,
    line_no: usize,
}

fn split_braces(line: &str) -> Vec<&str> {
    let mut out = Vec::new();
    for word in line.split_whitespace() {
        let mut rest = word;
        while !rest.is_empty() {
            match rest.find(['{', '}']) {
                Some(0) => {
                    out.push(&rest[..1]);
                    rest = &rest[1..];
                }
                Some(k) => {
                    out.push(&rest[..k]);
                    rest = &rest[k..];
                }
                None => {
                    out.push(rest);
                    rest = "";
                }
            }
        }
    }
    out
}

impl<'a> Tokens<'a> {
    fn new(text: &'a str) -> Self {
        let lines = text.lines().enumerate().map(|(i, l)| (i + 1, l)).collect();
        Tokens {
            lines,
            li: 0,
            toks: Vec::new(),
            ti: 0,
            line_no: 0,
        }
    }
    /// Next token, with its line; `None` at end of input.
    fn next(&mut self) -> Option<(&'a str, usize)> {
        loop {
            if self.ti < self.toks.len() {
                self.ti += 1;
                return Some((self.toks[self.ti - 1], self.line_no));
            }
            let (no, line) = *self.lines.get(self.li)?;
            self.li += 1;
            self.toks = split_braces(line);
            self.ti = 0;
            self.line_no = no;
        }
    }
    /// The rest of the current line's tokens.
    fn rest_of_line(&mut self) -> Vec<&'a str> {
        let r = self.toks[self.ti..].to_vec();
        self.ti = self.toks.len();
        r
    }
    /// Unconsumed whole lines after the current one.
    fn remaining_lines(&self) -> &[(usize, &'a str)] {
        &self.lines[self.li..]
    }
}

fn parse_f64(tok: &str, path: &Path, line: usize, what: &str) -> Result<f64, MocapError> {
    match tok.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(MocapError::parse(
            path,
            line,
            format!("expected a number for {what}, found '{tok}'"),
        )),
    }
}

/// Parses BVH text. `path` is used only to name the source in errors.
///
/// The steps, in order: `expect_hierarchy`, `Hierarchy::parse` (joints,
/// offsets, channels, end sites, up to `MOTION`), `MotionHeader::parse`
/// (`Frames:` and `Frame Time:`), `parse_frames` (one row of channel
/// values per frame into local rotations and translations) and
/// `MotionHeader::check_rate`; then the clip is assembled with the
/// warnings gathered on the way.
pub fn parse_bvh(text: &str, path: &Path, opts: &BvhOptions) -> Result<Clip, MocapError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut t = Tokens::new(text);
    let mut warnings = Vec::new();
    expect_hierarchy(&mut t, path)?;
    let (joints, motion_line) = Hierarchy::parse(&mut t, text, path)?;
    let rest = t.remaining_lines();
    let header = MotionHeader::parse(rest, path, motion_line, opts, &mut warnings)?;
    let (rotations, translations) =
        parse_frames(&joints, &rest[header.data_start..], path, &mut warnings)?;
    let frames = rotations.len() / joints.len();
    if frames == 0 {
        return Err(MocapError::invalid(path, "no motion frames"));
    }
    header.check_rate(frames, path, opts)?;
    match header.declared {
        Some(d) if d != frames as u64 => raise_warning(
            &mut warnings,
            path,
            format!("header says {d} frames, the data has {frames}; using the data"),
        ),
        _ => {}
    }
    if let (Some(fps), Some(ft)) = (opts.fps, header.file_frame_time)
        && (1.0 / ft - fps).abs() > 1e-6 * fps
    {
        raise_warning(
            &mut warnings,
            path,
            format!("file says {:.4} fps; overridden to {fps}", 1.0 / ft),
        );
    }
    let units = Units {
        metres_per_unit: 1.0,
        name: "file".into(),
        reason: "BVH has no unit; not yet decided".into(),
    };
    let mut clip = Clip::new(
        joints,
        header.frame_time,
        rotations,
        translations,
        units,
        UpAxis::Y,
        PointConvention::JointOrigins,
    )
    .map_err(|e| MocapError::invalid(path, e.to_string()))?;
    clip.warnings = warnings;
    Ok(clip)
}

/// Step 1 of [`parse_bvh`]: the file starts with `HIERARCHY`.
fn expect_hierarchy(t: &mut Tokens, path: &Path) -> Result<(), MocapError> {
    match t.next() {
        Some((k, _)) if k.eq_ignore_ascii_case("HIERARCHY") => Ok(()),
        Some((k, l)) => Err(MocapError::parse(
            path,
            l,
            format!("expected HIERARCHY, found '{k}'"),
        )),
        None => Err(MocapError::invalid(path, "empty file")),
    }
}

/// The joint hierarchy as it is read.
struct Hierarchy {
    joints: Vec<Joint>,
    /// Open blocks: `Some(joint)`, or `None` for an End Site block.
    stack: Vec<Option<usize>>,
    expecting_open: bool,
    done_root: bool,
}

impl Hierarchy {
    /// Step 2 of [`parse_bvh`]: the joints, up to the `MOTION` keyword
    /// (returned with its line).
    fn parse(t: &mut Tokens, text: &str, path: &Path) -> Result<(Vec<Joint>, usize), MocapError> {
        let mut h = Hierarchy {
            joints: Vec::new(),
            stack: Vec::new(),
            expecting_open: false,
            done_root: false,
        };
        loop {
            let Some((tok, line)) = t.next() else {
                let last = text.lines().count();
                return Err(MocapError::parse(
                    path,
                    last,
                    "file ends inside HIERARCHY (no MOTION section)",
                ));
            };
            if h.expecting_open {
                if tok != "{" {
                    return Err(MocapError::parse(
                        path,
                        line,
                        format!("expected '{{', found '{tok}'"),
                    ));
                }
                h.expecting_open = false;
                continue;
            }
            let key = tok.to_ascii_uppercase();
            match key.as_str() {
                "ROOT" | "JOINT" => h.joint(t, &key, path, line)?,
                "END" => h.end_site(t, path, line)?,
                "OFFSET" => h.offset(t, path, line)?,
                "CHANNELS" => h.channels(t, path, line)?,
                "{" => return Err(MocapError::parse(path, line, "unexpected '{'")),
                "}" => {
                    if h.stack.pop().is_none() {
                        return Err(MocapError::parse(path, line, "unmatched '}'"));
                    }
                    if h.stack.is_empty() {
                        h.done_root = true;
                    }
                }
                "MOTION" => {
                    if !h.stack.is_empty() {
                        return Err(MocapError::parse(
                            path,
                            line,
                            "MOTION before the hierarchy's braces are closed",
                        ));
                    }
                    if h.joints.is_empty() {
                        return Err(MocapError::parse(path, line, "MOTION before any ROOT"));
                    }
                    return Ok((h.joints, line));
                }
                _ => {
                    return Err(MocapError::parse(
                        path,
                        line,
                        format!("unknown keyword '{tok}'"),
                    ));
                }
            }
        }
    }

    /// `ROOT name` or `JOINT name` (`key` upper-cased).
    fn joint(
        &mut self,
        t: &mut Tokens,
        key: &str,
        path: &Path,
        line: usize,
    ) -> Result<(), MocapError> {
        if key == "ROOT" && (self.done_root || !self.stack.is_empty()) {
            return Err(MocapError::parse(
                path,
                line,
                "a second ROOT is not supported",
            ));
        }
        if key == "JOINT" && self.stack.is_empty() {
            return Err(MocapError::parse(path, line, "JOINT outside of ROOT"));
        }
        let mut words = t.rest_of_line();
        let open_here = words.last() == Some(&"{");
        if open_here {
            words.pop();
        }
        if words.is_empty() || words.contains(&"{") || words.contains(&"}") {
            return Err(MocapError::parse(
                path,
                line,
                format!("{key} without a name"),
            ));
        }
        let parent = match self.stack.last() {
            Some(Some(p)) => Some(JointId(*p as u32)),
            Some(None) => {
                return Err(MocapError::parse(path, line, "JOINT inside an End Site"));
            }
            None => None,
        };
        if self.joints.len() >= u32::MAX as usize / 2 {
            return Err(MocapError::parse(path, line, "too many joints"));
        }
        self.joints.push(Joint {
            name: words.join(" "),
            parent,
            offset: DVec3::ZERO,
            channels: Vec::new(),
            tail: None,
        });
        self.stack.push(Some(self.joints.len() - 1));
        self.expecting_open = !open_here;
        Ok(())
    }

    /// `End Site`.
    fn end_site(&mut self, t: &mut Tokens, path: &Path, line: usize) -> Result<(), MocapError> {
        let words = t.rest_of_line();
        let open_here = words.last() == Some(&"{");
        let ok = words
            .first()
            .is_some_and(|w| w.eq_ignore_ascii_case("SITE"));
        if !ok {
            return Err(MocapError::parse(path, line, "expected 'End Site'"));
        }
        match self.stack.last() {
            Some(Some(_)) => self.stack.push(None),
            _ => return Err(MocapError::parse(path, line, "End Site outside of a joint")),
        }
        self.expecting_open = !open_here;
        Ok(())
    }

    /// `OFFSET x y z` of the open joint, or of its End Site (its tail).
    fn offset(&mut self, t: &mut Tokens, path: &Path, line: usize) -> Result<(), MocapError> {
        let mut v = [0.0; 3];
        for (k, c) in v.iter_mut().enumerate() {
            let (tok, l) = t
                .next()
                .ok_or_else(|| MocapError::parse(path, line, "OFFSET needs 3 numbers"))?;
            *c = parse_f64(tok, path, l, &format!("OFFSET component {}", k + 1))?;
        }
        let v = DVec3::from(v);
        match self.stack.last() {
            Some(Some(j)) => self.joints[*j].offset = v,
            Some(None) => {
                // The End Site belongs to the joint below it on the stack.
                let owner = self.stack.iter().rev().find_map(|s| *s);
                if let Some(j) = owner {
                    self.joints[j].tail = Some(v);
                }
            }
            None => return Err(MocapError::parse(path, line, "OFFSET outside of a joint")),
        }
        Ok(())
    }

    /// `CHANNELS n name...` of the open joint (at most 6).
    fn channels(&mut self, t: &mut Tokens, path: &Path, line: usize) -> Result<(), MocapError> {
        let Some(Some(j)) = self.stack.last().copied() else {
            return Err(MocapError::parse(path, line, "CHANNELS outside of a joint"));
        };
        let (tok, l) = t
            .next()
            .ok_or_else(|| MocapError::parse(path, line, "CHANNELS needs a count"))?;
        let n: usize = tok
            .parse()
            .map_err(|_| MocapError::parse(path, l, format!("bad channel count '{tok}'")))?;
        if n > 6 {
            return Err(MocapError::parse(
                path,
                l,
                format!("{n} channels on one joint (at most 6)"),
            ));
        }
        let mut chans = Vec::with_capacity(n);
        for _ in 0..n {
            let (tok, l) = t
                .next()
                .ok_or_else(|| MocapError::parse(path, line, "file ends inside CHANNELS"))?;
            let c = Channel::parse(tok)
                .ok_or_else(|| MocapError::parse(path, l, format!("unknown channel '{tok}'")))?;
            chans.push(c);
        }
        self.joints[j].channels = chans;
        Ok(())
    }
}

/// The `Frames:` and `Frame Time:` lines after `MOTION`.
struct MotionHeader {
    /// The declared frame count, if readable.
    declared: Option<u64>,
    /// The file's frame time, if a positive finite number.
    file_frame_time: Option<f64>,
    /// The frame time used (the override's, else the file's).
    frame_time: f64,
    /// Line of `Frame Time:` and its value as written.
    time_line: usize,
    time_value: String,
    /// Index, in the lines after `MOTION`, of the first frame line.
    data_start: usize,
}

impl MotionHeader {
    /// Step 3 of [`parse_bvh`]: "Frames: N" then "Frame Time: t", leniently
    /// (an unreadable count is a warning; a frame-rate override replaces a
    /// bad or missing frame time).
    fn parse(
        rest: &[(usize, &str)],
        path: &Path,
        motion_line: usize,
        opts: &BvhOptions,
        warnings: &mut Vec<String>,
    ) -> Result<MotionHeader, MocapError> {
        let mut idx = 0;
        let next_line = |idx: &mut usize| -> Option<(usize, &str)> {
            while let Some(&(no, l)) = rest.get(*idx) {
                *idx += 1;
                if !l.trim().is_empty() {
                    return Some((no, l.trim()));
                }
            }
            None
        };
        let (fl, frames_line) = next_line(&mut idx)
            .ok_or_else(|| MocapError::parse(path, motion_line, "missing 'Frames:' line"))?;
        if !frames_line.to_ascii_lowercase().starts_with("frames") {
            return Err(MocapError::parse(
                path,
                fl,
                format!("expected 'Frames:', found '{frames_line}'"),
            ));
        }
        let declared = value_after(frames_line, 6);
        let declared: Option<u64> = declared.parse().ok();
        if declared.is_none() {
            raise_warning(
                warnings,
                path,
                format!("line {fl}: unreadable frame count; using the data"),
            );
        }
        let (tl, time_line) = next_line(&mut idx)
            .ok_or_else(|| MocapError::parse(path, fl, "missing 'Frame Time:' line"))?;
        if !time_line.to_ascii_lowercase().starts_with("frame time") {
            return Err(MocapError::parse(
                path,
                tl,
                format!("expected 'Frame Time:', found '{time_line}'"),
            ));
        }
        let time_value = value_after(time_line, 10);
        let file_ft: Option<f64> = time_value
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite() && *v > 0.0);
        let frame_time = match (opts.fps, file_ft) {
            (Some(fps), _) if crate::budget::is_frame_rate(fps) => 1.0 / fps,
            (Some(fps), _) => {
                return Err(MocapError::invalid(
                    path,
                    format!(
                        "--input-fps {fps}: expected a frame rate in [{}, {}]",
                        crate::budget::MIN_FPS,
                        crate::budget::MAX_FPS
                    ),
                ));
            }
            (None, Some(ft)) => ft,
            (None, None) => {
                return Err(MocapError::parse(
                    path,
                    tl,
                    format!("bad Frame Time '{time_value}'; give the frame rate with --input-fps"),
                ));
            }
        };
        Ok(MotionHeader {
            declared,
            file_frame_time: file_ft,
            frame_time,
            time_line: tl,
            time_value,
            data_start: idx,
        })
    }

    /// Step 5 of [`parse_bvh`]: a frame time outside 1-1000 fps (a Frame
    /// Time in milliseconds, or 1e300) would ask for absurd frame counts
    /// downstream (issue 18, items 12 and 17). A single frame has no rate
    /// to speak of; an override was checked when read.
    fn check_rate(&self, frames: usize, path: &Path, opts: &BvhOptions) -> Result<(), MocapError> {
        let frame_time = self.frame_time;
        if opts.fps.is_none() && frames > 1 && !crate::budget::is_frame_rate(1.0 / frame_time) {
            return Err(MocapError::parse(
                path,
                self.time_line,
                format!(
                    "Frame Time {} s is {:.4} frames per second, outside [{}, {}]{}; give the frame rate with --input-fps",
                    self.time_value,
                    1.0 / frame_time,
                    crate::budget::MIN_FPS,
                    crate::budget::MAX_FPS,
                    if frame_time > 1.0 && frame_time < 1000.0 {
                        " (milliseconds instead of seconds?)"
                    } else {
                        ""
                    }
                ),
            ));
        }
        Ok(())
    }
}

/// The value of a `Key: value` header line whose key is `key_len` bytes.
fn value_after(l: &str, key_len: usize) -> String {
    let v = l.get(key_len..).unwrap_or("");
    v.trim_start().trim_start_matches(':').trim().to_string()
}

/// Step 4 of [`parse_bvh`]: each non-empty line of `lines` is one frame of
/// channel values (degrees for rotations, applied in the joint's channel
/// order; position channels replace the offset). Returns the local
/// rotations and translations, frame-major; a short last line (truncated
/// file) is dropped with a warning.
fn parse_frames(
    joints: &[Joint],
    lines: &[(usize, &str)],
    path: &Path,
    warnings: &mut Vec<String>,
) -> Result<(Vec<DQuat>, Vec<DVec3>), MocapError> {
    let total: usize = joints.iter().map(|j| j.channels.len()).sum();
    if total == 0 {
        return Err(MocapError::invalid(path, "no joint has channels"));
    }
    let mut rotations = Vec::new();
    let mut translations = Vec::new();
    let mut row = Vec::with_capacity(total);
    let data: Vec<(usize, &str)> = lines
        .iter()
        .copied()
        .filter(|(_, l)| !l.trim().is_empty())
        .collect();
    for (k, &(no, l)) in data.iter().enumerate() {
        row.clear();
        for tok in l.split_whitespace() {
            row.push(parse_f64(tok, path, no, "a channel value")?);
        }
        if row.len() != total {
            if k + 1 == data.len() && row.len() < total {
                raise_warning(
                    warnings,
                    path,
                    format!(
                        "line {no}: last frame has {} of {total} values (truncated file?); dropped",
                        row.len()
                    ),
                );
                break;
            }
            return Err(MocapError::parse(
                path,
                no,
                format!("{} values on a frame line, expected {total}", row.len()),
            ));
        }
        let mut c = 0;
        for j in joints {
            let mut tr = j.offset;
            let mut q = DQuat::IDENTITY;
            for ch in &j.channels {
                let v = row[c];
                c += 1;
                if ch.is_rotation() {
                    q *= euler::axis_rotation(ch.axis(), v.to_radians());
                } else {
                    tr[ch.axis()] = v;
                }
            }
            rotations.push(q.normalize());
            translations.push(tr);
        }
    }
    Ok((rotations, translations))
}

/// Reads a BVH file.
pub fn read_bvh(path: &Path, opts: &BvhOptions) -> Result<Clip, MocapError> {
    let text = crate::fsutil::read_text(path)?;
    parse_bvh(&text, path, opts)
}

/// Formats a clip as BVH text. Rotations are written as Euler angles in each
/// joint's own channel order (Z Y X where the joint had no full 3-angle
/// order); joints with position channels get `Xposition Yposition Zposition`.
/// Numbers use the shortest exact decimal form, so reading the text back
/// gives the same rotations and translations to rounding.
pub fn format_bvh(clip: &Clip) -> String {
    let children = clip.children();
    let n = clip.joint_count();
    // Depth-first order of emission; the data rows follow it.
    let mut order = Vec::with_capacity(n);
    let mut s = String::new();
    s.push_str("HIERARCHY\n");
    fn emit(
        clip: &Clip,
        children: &[Vec<JointId>],
        j: usize,
        depth: usize,
        s: &mut String,
        order: &mut Vec<(usize, bool, [usize; 3])>,
    ) {
        let ind = "\t".repeat(depth);
        let joint = &clip.joints[j];
        let kw = if joint.parent.is_none() {
            "ROOT"
        } else {
            "JOINT"
        };
        let _ = writeln!(s, "{ind}{kw} {}\n{ind}{{", joint.name);
        let o = joint.offset;
        let _ = writeln!(s, "{ind}\tOFFSET {} {} {}", o.x, o.y, o.z);
        let pos = joint.parent.is_none() || joint.has_position_channels();
        let rot = euler::writable_rotation_order(&joint.channels);
        let names = ["Xrotation", "Yrotation", "Zrotation"];
        if pos {
            let _ = writeln!(
                s,
                "{ind}\tCHANNELS 6 Xposition Yposition Zposition {} {} {}",
                names[rot[0]], names[rot[1]], names[rot[2]]
            );
        } else {
            let _ = writeln!(
                s,
                "{ind}\tCHANNELS 3 {} {} {}",
                names[rot[0]], names[rot[1]], names[rot[2]]
            );
        }
        order.push((j, pos, rot));
        for c in &children[j] {
            emit(clip, children, c.idx(), depth + 1, s, order);
        }
        if children[j].is_empty() {
            let t = joint.tail.unwrap_or(DVec3::ZERO);
            let _ = writeln!(
                s,
                "{ind}\tEnd Site\n{ind}\t{{\n{ind}\t\tOFFSET {} {} {}\n{ind}\t}}",
                t.x, t.y, t.z
            );
        }
        let _ = writeln!(s, "{ind}}}");
    }
    emit(clip, &children, 0, 0, &mut s, &mut order);
    let _ = writeln!(
        s,
        "MOTION\nFrames: {}\nFrame Time: {}",
        clip.frame_count(),
        clip.frame_time
    );
    for f in 0..clip.frame_count() {
        let q = clip.frame_rotations(f);
        let t = clip.frame_translations(f);
        let mut first = true;
        for &(j, pos, rot) in &order {
            let mut vals = [0.0f64; 6];
            let mut k = 0;
            if pos {
                vals[..3].copy_from_slice(&t[j].to_array());
                k = 3;
            }
            let e = euler::decompose_degrees(q[j], rot);
            vals[k..k + 3].copy_from_slice(&e.to_array());
            for v in &vals[..k + 3] {
                if !first {
                    s.push(' ');
                }
                first = false;
                let _ = write!(s, "{v}");
            }
        }
        s.push('\n');
    }
    s
}

/// Writes a clip as BVH, atomically.
pub fn write_bvh(clip: &Clip, path: &Path) -> Result<(), MocapError> {
    let text = format_bvh(clip);
    crate::fsutil::write_bytes_atomic(path, text.as_bytes())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: &str = "HIERARCHY\r\nROOT Hips {\r\n\tOFFSET 0 0 0\r\n\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\r\n\tJOINT Leg\r\n\t{\r\n\t\tOFFSET 0 -1e0 0\r\n\t\tCHANNELS 3 Xrotation Yrotation Zrotation\r\n\t\tEnd site\r\n\t\t{\r\n\t\t\tOFFSET 0 -1 0\r\n\t\t}\r\n\t}\r\n}\r\nMOTION\r\nFrames: 5\r\nFrame Time: .5\r\n1 2 3 90 0 0 0 0 0\r\n1 2 3 0 0 0 90 0 0\r\n";

    #[test]
    fn lenient_small_file() {
        let c = parse_bvh(SMALL, Path::new("t.bvh"), &BvhOptions::default()).unwrap();
        assert_eq!(c.joint_count(), 2);
        assert_eq!(c.frame_count(), 2);
        assert_eq!(c.frame_time, 0.5);
        assert!(c.warnings.iter().any(|w| w.contains("header says 5")));
        assert_eq!(c.joints[1].tail, Some(DVec3::new(0.0, -1.0, 0.0)));
        // Frame 0: root turned 90° about z, leg hangs along -y → world +x.
        let p = c.world_positions(0);
        assert!((p[1] - DVec3::new(2.0, 2.0, 3.0)).length() < 1e-12, "{p:?}");
    }

    #[test]
    fn frame_times_in_milliseconds_or_absurd_are_refused() {
        for ft in ["33.3333", "1e300", "1e-9"] {
            let bad = SMALL.replace("Frame Time: .5", &format!("Frame Time: {ft}"));
            let e = parse_bvh(&bad, Path::new("t.bvh"), &BvhOptions::default())
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with("t.bvh:17:") && e.contains("--input-fps"),
                "{e}"
            );
        }
        let ms = SMALL.replace("Frame Time: .5", "Frame Time: 33.3");
        let e = parse_bvh(&ms, Path::new("t.bvh"), &BvhOptions::default()).unwrap_err();
        assert!(e.to_string().contains("milliseconds"), "{e}");
        // The override rescues it; an absurd override is refused.
        assert!(parse_bvh(&ms, Path::new("t.bvh"), &BvhOptions { fps: Some(30.0) }).is_ok());
        assert!(parse_bvh(&ms, Path::new("t.bvh"), &BvhOptions { fps: Some(1e-4) }).is_err());
    }

    #[test]
    fn errors_name_the_line() {
        let bad = SMALL.replace("Yrotation Zrotation", "Yrotation Wrotation");
        let e = parse_bvh(&bad, Path::new("t.bvh"), &BvhOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("t.bvh:8:"), "{e}");
        let bad = SMALL.replace("1 2 3 0 0 0 90 0 0", "1 2 x 0 0 0 90 0 0");
        let e = parse_bvh(&bad, Path::new("t.bvh"), &BvhOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("t.bvh:19:"), "{e}");
    }

    #[test]
    fn fps_override_and_bad_frame_time() {
        let bad = SMALL.replace("Frame Time: .5", "Frame Time: 0");
        assert!(parse_bvh(&bad, Path::new("t.bvh"), &BvhOptions::default()).is_err());
        let c = parse_bvh(&bad, Path::new("t.bvh"), &BvhOptions { fps: Some(30.0) }).unwrap();
        assert!((c.fps() - 30.0).abs() < 1e-9);
    }

    #[test]
    fn write_read_round_trip() {
        let c = parse_bvh(SMALL, Path::new("t.bvh"), &BvhOptions::default()).unwrap();
        let text = format_bvh(&c);
        let d = parse_bvh(&text, Path::new("w.bvh"), &BvhOptions::default()).unwrap();
        assert_eq!(d.joint_count(), c.joint_count());
        for (a, b) in c.rotations.iter().zip(&d.rotations) {
            assert!(a.dot(*b).abs() > 1.0 - 1e-12);
        }
        for (a, b) in c.translations.iter().zip(&d.translations) {
            assert!((*a - *b).length() < 1e-12);
        }
    }
}
