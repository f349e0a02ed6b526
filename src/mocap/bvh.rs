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
use crate::util::fsutil::raise_warning;
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

/// Lines, numbered from 1, read lazily: memory stays that of the text
/// (collecting them cost 24 bytes a line: 100 MB of empty lines took
/// 2.4 GB).
type Lines<'a> = std::iter::Peekable<
    std::iter::Map<
        std::iter::Enumerate<std::str::Lines<'a>>,
        fn((usize, &'a str)) -> (usize, &'a str),
    >,
>;

fn numbered<'a>(text: &'a str) -> Lines<'a> {
    fn one_based(p: (usize, &str)) -> (usize, &str) {
        (p.0 + 1, p.1)
    }
    let f: fn((usize, &'a str)) -> (usize, &'a str) = one_based;
    text.lines().enumerate().map(f).peekable()
}

/// Tokens of the hierarchy: words, with `{` and `}` split off, read one at
/// a time (a line of a million braces is not split up front).
struct Tokens<'a> {
    lines: Lines<'a>,
    /// The unread part of the current line.
    rest: &'a str,
    line_no: usize,
}

/// The next token of `rest` (a word, or a lone brace), advancing it.
fn next_token<'a>(rest: &mut &'a str) -> Option<&'a str> {
    let s = rest.trim_start();
    if s.is_empty() {
        *rest = s;
        return None;
    }
    let k = if s.starts_with(['{', '}']) {
        1
    } else {
        s.find(|c: char| c.is_whitespace() || c == '{' || c == '}')
            .unwrap_or(s.len())
    };
    *rest = &s[k..];
    Some(&s[..k])
}

/// Most words a `JOINT` line's name may have.
const MAX_NAME_WORDS: usize = 64;

impl<'a> Tokens<'a> {
    fn new(text: &'a str) -> Self {
        Tokens {
            lines: numbered(text),
            rest: "",
            line_no: 0,
        }
    }
    /// Next token, with its line; `None` at end of input.
    fn next(&mut self) -> Option<(&'a str, usize)> {
        loop {
            if let Some(t) = next_token(&mut self.rest) {
                return Some((t, self.line_no));
            }
            let (no, line) = self.lines.next()?;
            self.rest = line;
            self.line_no = no;
        }
    }
    /// The next token of the current line only.
    fn next_on_line(&mut self) -> Option<&'a str> {
        next_token(&mut self.rest)
    }
    /// The rest of the current line's tokens (at most
    /// [`MAX_NAME_WORDS`] + 1: the caller refuses more).
    fn rest_of_line(&mut self) -> Vec<&'a str> {
        let mut r = Vec::new();
        while let Some(t) = next_token(&mut self.rest) {
            r.push(t);
            if r.len() > MAX_NAME_WORDS + 1 {
                break;
            }
        }
        self.rest = "";
        r
    }
}

/// Most characters of file text an error or warning quotes.
pub(crate) const QUOTE_CHARS: usize = 40;

/// File text as errors and warnings quote it, in single quotes: at most
/// [`QUOTE_CHARS`] characters (then `…`), and every character that does
/// not print (control characters, the replacement character that stands
/// for bytes that are not text, other format or unassigned-looking code
/// points) escaped as `\xNN` (below U+0100) or `\u{NNNN}`, a backslash
/// and a quote as `\\` and `\'`. Binary garbage read as a BVH is named, not
/// copied to the terminal.
pub fn quoted(s: &str) -> String {
    let mut out = String::from("'");
    for (n, c) in s.chars().enumerate() {
        if n == QUOTE_CHARS {
            out.push('…');
            break;
        }
        match c {
            '\\' => out.push_str("\\\\"),
            '\'' => out.push_str("\\'"),
            ' ' => out.push(' '),
            c if c.is_control()
                || c.is_whitespace()
                || c == char::REPLACEMENT_CHARACTER
                || ('\u{200b}'..='\u{200f}').contains(&c)
                || ('\u{2028}'..='\u{202e}').contains(&c)
                || ('\u{2060}'..='\u{206f}').contains(&c)
                || c == '\u{feff}'
                || ('\u{e000}'..='\u{f8ff}').contains(&c) =>
            {
                if (c as u32) < 0x100 {
                    out.push_str(&format!("\\x{:02x}", c as u32));
                } else {
                    out.push_str(&format!("\\u{{{:04x}}}", c as u32));
                }
            }
            c => out.push(c),
        }
    }
    out.push('\'');
    out
}

/// Largest magnitude of an offset or channel value (file units or
/// degrees): no capture comes near it, and beyond it sums overflow to
/// infinity downstream (an OFFSET of 1e308 was read, and its unit printed
/// as a 300-digit number).
pub(crate) const MAX_ABS_VALUE: f64 = 1e9;

fn parse_f64(tok: &str, path: &Path, line: usize, what: &str) -> Result<f64, MocapError> {
    match tok.parse::<f64>() {
        Ok(v) if v.is_finite() && v.abs() > MAX_ABS_VALUE => Err(MocapError::parse(
            path,
            line,
            format!("{what} is {}, beyond ±{MAX_ABS_VALUE:e}", quoted(tok)),
        )),
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(MocapError::parse(
            path,
            line,
            format!("expected a number for {what}, found {}", quoted(tok)),
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
    let (h, motion_line) = Hierarchy::parse(&mut t, text, path)?;
    warnings.extend(h.warnings);
    let joints = h.joints;
    let mut rest = t.lines;
    let mut header = MotionHeader::parse(&mut rest, path, motion_line, opts, &mut warnings)?;
    let (rotations, translations) = parse_frames(&joints, &h.slots, rest, path, &mut warnings)?;
    let frames = rotations.len() / joints.len();
    if frames == 0 {
        return Err(MocapError::parse(
            path,
            header.time_line,
            format!(
                "no motion frames after 'Frame Time:' (the header says Frames: {}): a skeleton without motion",
                header.declared.map_or("?".into(), |d| d.to_string())
            ),
        ));
    }
    header.check_rate(frames, path, opts, &mut warnings)?;
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
            format!("expected HIERARCHY, found {}", quoted(k)),
        )),
        None => Err(MocapError::invalid(path, "empty file")),
    }
}

/// The joint hierarchy as it is read.
struct Hierarchy {
    joints: Vec<Joint>,
    /// Each joint's channels as the frame lines hold them: `None` for a
    /// scale channel (read past, not used).
    slots: Vec<Vec<Option<Channel>>>,
    /// Open blocks: `Some(joint)`, or `None` for an End Site block.
    stack: Vec<Option<usize>>,
    expecting_open: bool,
    done_root: bool,
    /// Joint names taken, for renaming repeats, and the next suffix to
    /// try for each repeated name (a file of 200,000 joints called `b`
    /// must not search 1, 2, 3… for each).
    names: std::collections::HashSet<String>,
    next_suffix: std::collections::HashMap<String, usize>,
    /// Joints renamed so far (the first ten are warned of one by one).
    renamed: usize,
    warnings: Vec<String>,
    path: std::path::PathBuf,
}

impl Hierarchy {
    /// Step 2 of [`parse_bvh`]: the joints, up to the `MOTION` keyword
    /// (returned with its line).
    fn parse(t: &mut Tokens, text: &str, path: &Path) -> Result<(Hierarchy, usize), MocapError> {
        let mut h = Hierarchy {
            joints: Vec::new(),
            slots: Vec::new(),
            stack: Vec::new(),
            expecting_open: false,
            done_root: false,
            names: Default::default(),
            next_suffix: Default::default(),
            renamed: 0,
            warnings: Vec::new(),
            path: path.to_path_buf(),
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
                // `End Site` followed by its OFFSET without braces (seen
                // in hand-edited and some exported files).
                if h.stack.last() == Some(&None) && tok.eq_ignore_ascii_case("OFFSET") {
                    h.stack.pop();
                    h.expecting_open = false;
                    h.offset(t, path, line, true)?;
                    raise_warning(
                        &mut h.warnings,
                        path,
                        format!("line {line}: End Site without braces"),
                    );
                    continue;
                }
                if tok != "{" {
                    return Err(MocapError::parse(
                        path,
                        line,
                        format!("expected '{{', found {}", quoted(tok)),
                    ));
                }
                h.expecting_open = false;
                continue;
            }
            let key = tok.to_ascii_uppercase();
            match key.as_str() {
                "ROOT" | "JOINT" => h.joint(t, &key, path, line)?,
                "END" => h.end_site(t, path, line)?,
                "ENDSITE" => {
                    h.open_end_site(path, line)?;
                    h.expecting_open = !h.open_on_line(t);
                }
                "OFFSET" => h.offset(t, path, line, false)?,
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
                    return Ok((h, line));
                }
                _ => {
                    return Err(MocapError::parse(
                        path,
                        line,
                        format!("unknown keyword {}", quoted(tok)),
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
        if words.len() > MAX_NAME_WORDS {
            return Err(MocapError::parse(
                path,
                line,
                format!("{key} name of more than {MAX_NAME_WORDS} words"),
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
        let name = self.unique_name(words.join(" "), line);
        self.slots.push(Vec::new());
        self.joints.push(Joint {
            name,
            parent,
            offset: DVec3::ZERO,
            channels: Vec::new(),
            tail: None,
        });
        self.stack.push(Some(self.joints.len() - 1));
        self.expecting_open = !open_here;
        Ok(())
    }

    /// A joint name not used before: a repeat (two joints called `Spine`)
    /// gets a suffix, `Spine.001`, as Blender does, with a warning; rig
    /// maps and joint lookups go by name.
    fn unique_name(&mut self, name: String, line: usize) -> String {
        if self.names.insert(name.clone()) {
            return name;
        }
        let k = self.next_suffix.entry(name.clone()).or_insert(1);
        let renamed = loop {
            let n = format!("{name}.{:03}", *k);
            *k += 1;
            if !self.names.contains(&n) {
                break n;
            }
        };
        self.names.insert(renamed.clone());
        self.renamed += 1;
        let msg = match self.renamed {
            1..=10 => format!(
                "line {line}: a second joint called {}; renamed {}",
                quoted(&name),
                quoted(&renamed)
            ),
            11 => format!("line {line} and after: more repeated joint names renamed likewise"),
            _ => return renamed,
        };
        raise_warning(&mut self.warnings, &self.path, msg);
        renamed
    }

    /// `End Site` (also `End site`, and `EndSite` as one word).
    fn end_site(&mut self, t: &mut Tokens, path: &Path, line: usize) -> Result<(), MocapError> {
        let ok = t
            .next_on_line()
            .is_some_and(|w| w.eq_ignore_ascii_case("SITE"));
        if !ok {
            return Err(MocapError::parse(path, line, "expected 'End Site'"));
        }
        self.open_end_site(path, line)?;
        self.expecting_open = !self.open_on_line(t);
        Ok(())
    }

    fn open_end_site(&mut self, path: &Path, line: usize) -> Result<(), MocapError> {
        match self.stack.last() {
            Some(Some(_)) => self.stack.push(None),
            _ => return Err(MocapError::parse(path, line, "End Site outside of a joint")),
        }
        Ok(())
    }

    /// Whether the `End Site` line ends with its `{` (other words there,
    /// a name some exporters add, are ignored).
    fn open_on_line(&mut self, t: &mut Tokens) -> bool {
        t.rest_of_line().last() == Some(&"{")
    }

    /// `OFFSET x y z` of the open joint, or of its End Site (its tail;
    /// also when `tail`, an End Site without braces).
    fn offset(
        &mut self,
        t: &mut Tokens,
        path: &Path,
        line: usize,
        tail: bool,
    ) -> Result<(), MocapError> {
        let mut v = [0.0; 3];
        for (k, c) in v.iter_mut().enumerate() {
            let (tok, l) = t
                .next()
                .ok_or_else(|| MocapError::parse(path, line, "OFFSET needs 3 numbers"))?;
            *c = parse_f64(tok, path, l, &format!("OFFSET component {}", k + 1))?;
        }
        let v = DVec3::from(v);
        if tail {
            // A braceless End Site: its block was already closed.
            if let Some(Some(j)) = self.stack.last() {
                self.joints[*j].tail = Some(v);
            }
            return Ok(());
        }
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

    /// `CHANNELS n name...` of the open joint: at most 9, the position
    /// and rotation channels, and scale channels (`Xscale`..., written by
    /// some exporters), which are read past with a warning.
    fn channels(&mut self, t: &mut Tokens, path: &Path, line: usize) -> Result<(), MocapError> {
        let Some(Some(j)) = self.stack.last().copied() else {
            return Err(MocapError::parse(path, line, "CHANNELS outside of a joint"));
        };
        let (tok, l) = t
            .next()
            .ok_or_else(|| MocapError::parse(path, line, "CHANNELS needs a count"))?;
        let n: usize = tok.parse().map_err(|_| {
            MocapError::parse(path, l, format!("bad channel count {}", quoted(tok)))
        })?;
        if n > 9 {
            return Err(MocapError::parse(
                path,
                l,
                format!("{n} channels on one joint (at most 9)"),
            ));
        }
        let mut slots = Vec::with_capacity(n);
        for _ in 0..n {
            let (tok, l) = t
                .next()
                .ok_or_else(|| MocapError::parse(path, line, "file ends inside CHANNELS"))?;
            let c = Channel::parse(tok);
            let scale = ["xscale", "yscale", "zscale"]
                .iter()
                .any(|s| tok.eq_ignore_ascii_case(s));
            if c.is_none() && !scale {
                return Err(MocapError::parse(
                    path,
                    l,
                    format!("unknown channel {}", quoted(tok)),
                ));
            }
            // A channel named twice (`Xrotation Xrotation`) was read as two
            // rotations summed and two positions of which the last won.
            if c.is_some() && slots.contains(&c) {
                return Err(MocapError::parse(
                    path,
                    l,
                    format!(
                        "channel {} repeated on joint {}",
                        quoted(tok),
                        quoted(&self.joints[j].name)
                    ),
                ));
            }
            slots.push(c);
        }
        if slots.iter().any(Option::is_none) {
            raise_warning(
                &mut self.warnings,
                path,
                format!(
                    "line {line}: scale channels of joint {} ignored",
                    quoted(&self.joints[j].name)
                ),
            );
        }
        self.joints[j].channels = slots.iter().flatten().copied().collect();
        self.slots[j] = slots;
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
}

impl MotionHeader {
    /// Step 3 of [`parse_bvh`]: "Frames: N" then "Frame Time: t", leniently
    /// (an unreadable count is a warning; a frame-rate override replaces a
    /// bad or missing frame time).
    fn parse(
        rest: &mut Lines,
        path: &Path,
        motion_line: usize,
        opts: &BvhOptions,
        warnings: &mut Vec<String>,
    ) -> Result<MotionHeader, MocapError> {
        let mut next_line = || -> Option<(usize, &str)> {
            rest.by_ref()
                .find(|(_, l)| !l.trim().is_empty())
                .map(|(no, l)| (no, l.trim()))
        };
        let (fl, frames_line) = next_line()
            .ok_or_else(|| MocapError::parse(path, motion_line, "missing 'Frames:' line"))?;
        let Some(declared) = header_value(frames_line, &["frames"]) else {
            return Err(MocapError::parse(
                path,
                fl,
                format!("expected 'Frames:', found {}", quoted(frames_line)),
            ));
        };
        let declared: Option<u64> = declared.parse().ok();
        if declared.is_none() {
            raise_warning(
                warnings,
                path,
                format!("line {fl}: unreadable frame count; using the data"),
            );
        }
        let (tl, time_line) =
            next_line().ok_or_else(|| MocapError::parse(path, fl, "missing 'Frame Time:' line"))?;
        let Some(time_value) = header_value(time_line, &["frame", "time"])
            .or_else(|| header_value(time_line, &["frametime"]))
        else {
            return Err(MocapError::parse(
                path,
                tl,
                format!("expected 'Frame Time:', found {}", quoted(time_line)),
            ));
        };
        let file_ft: Option<f64> = time_value
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite() && *v > 0.0);
        let frame_time = match (opts.fps, file_ft) {
            (Some(fps), _) if crate::util::budget::is_frame_rate(fps) => 1.0 / fps,
            (Some(fps), _) => {
                return Err(MocapError::invalid(
                    path,
                    format!(
                        "`BvhOptions::fps` {fps}: expected a frame rate in [{}, {}]",
                        crate::util::budget::MIN_FPS,
                        crate::util::budget::MAX_FPS
                    ),
                ));
            }
            (None, Some(ft)) => ft,
            // A single pose (a bind or reference pose) has no rate to
            // speak of: exporters write `Frame Time: 0` for it.
            (None, None) if declared.is_some_and(|d| d <= 1) => {
                raise_warning(
                    warnings,
                    path,
                    format!(
                        "line {tl}: Frame Time {} with a single frame; 30 fps assumed",
                        quoted(&time_value)
                    ),
                );
                1.0 / 30.0
            }
            (None, None) => {
                return Err(MocapError::parse(
                    path,
                    tl,
                    format!(
                        "bad Frame Time {}; give the frame rate with `BvhOptions::fps`",
                        quoted(&time_value)
                    ),
                ));
            }
        };
        Ok(MotionHeader {
            declared,
            file_frame_time: file_ft,
            frame_time,
            time_line: tl,
            time_value,
        })
    }

    /// Step 5 of [`parse_bvh`]: a frame time outside 1-1000 fps (a Frame
    /// Time in milliseconds, or 1e300) would ask for absurd frame counts
    /// downstream (issue 18, items 12 and 17). A single frame has no rate
    /// to speak of; an override was checked when read.
    fn check_rate(
        &mut self,
        frames: usize,
        path: &Path,
        opts: &BvhOptions,
        warnings: &mut Vec<String>,
    ) -> Result<(), MocapError> {
        // A single pose with an absurd rate (`Frame Time 1e-30`) was kept,
        // and `mocap convert` wrote the absurd rate back out: take 30 fps,
        // as for a single pose's `Frame Time 0`.
        if opts.fps.is_none()
            && frames <= 1
            && !crate::util::budget::is_frame_rate(1.0 / self.frame_time)
        {
            raise_warning(
                warnings,
                path,
                format!(
                    "line {}: Frame Time {} with a single frame is outside [{}, {}] frames per second; 30 fps assumed",
                    self.time_line,
                    quoted(&self.time_value),
                    crate::util::budget::MIN_FPS,
                    crate::util::budget::MAX_FPS
                ),
            );
            self.frame_time = 1.0 / 30.0;
        }
        let frame_time = self.frame_time;
        if opts.fps.is_none() && frames > 1 && self.file_frame_time.is_none() {
            return Err(MocapError::parse(
                path,
                self.time_line,
                format!(
                    "bad Frame Time {} for {frames} frames; give the frame rate with `BvhOptions::fps`",
                    quoted(&self.time_value)
                ),
            ));
        }
        if opts.fps.is_none() && frames > 1 && !crate::util::budget::is_frame_rate(1.0 / frame_time)
        {
            return Err(MocapError::parse(
                path,
                self.time_line,
                format!(
                    "Frame Time {} s is {} frames per second, outside [{}, {}]{}; give the frame rate with `BvhOptions::fps`",
                    self.time_value,
                    crate::util::numfmt::Short(1.0 / frame_time),
                    crate::util::budget::MIN_FPS,
                    crate::util::budget::MAX_FPS,
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

/// The value of a `Key: value` header line whose key is the words `key`
/// (any case, any spaces or tabs between them, the colon optional:
/// `Frame Time: t`, `Frame\tTime:\tt`, `frame time t`, `Frames:120`).
fn header_value(l: &str, key: &[&str]) -> Option<String> {
    let mut rest = l.trim();
    for k in key {
        let w = rest.get(..k.len())?;
        if !w.eq_ignore_ascii_case(k) {
            return None;
        }
        rest = rest[k.len()..].trim_start();
    }
    let v = rest.strip_prefix(':').unwrap_or(rest).trim();
    Some(v.to_string())
}

/// Step 4 of [`parse_bvh`]: each non-empty line of `lines` is one frame of
/// channel values (degrees for rotations, applied in the joint's channel
/// order; position channels replace the offset). Returns the local
/// rotations and translations, frame-major; a short last line (truncated
/// file) is dropped with a warning.
fn parse_frames(
    joints: &[Joint],
    slots: &[Vec<Option<Channel>>],
    lines: Lines,
    path: &Path,
    warnings: &mut Vec<String>,
) -> Result<(Vec<DQuat>, Vec<DVec3>), MocapError> {
    let total: usize = slots.iter().map(Vec::len).sum();
    if joints.iter().all(|j| j.channels.is_empty()) {
        return Err(MocapError::invalid(path, "no joint has channels"));
    }
    // The clip's size, known from the line count before anything is held:
    // joints without channels cost memory in every frame but no text.
    let mut data = lines.filter(|(_, l)| !l.trim().is_empty()).peekable();
    let frames = data.clone().count();
    let per_frame = (joints.len() * (size_of::<DQuat>() + size_of::<DVec3>())) as u128;
    crate::util::budget::check(
        || {
            format!(
                "{} frames × {} joints",
                crate::util::budget::thousands(frames as u128),
                crate::util::budget::thousands(joints.len() as u128)
            )
        },
        frames as u128 * per_frame,
    )
    .map_err(|e| MocapError::invalid(path, e.to_string()))?;
    let mut rotations = Vec::with_capacity(frames * joints.len());
    let mut translations = Vec::with_capacity(frames * joints.len());
    let mut row = Vec::with_capacity(total);
    while let Some((no, l)) = data.next() {
        row.clear();
        let mut toks = l.split_whitespace();
        for tok in toks.by_ref() {
            row.push(parse_f64(tok, path, no, "a channel value")?);
            if row.len() > total {
                break;
            }
        }
        if row.len() != total {
            if data.peek().is_none() && row.len() < total && !rotations.is_empty() {
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
                format!(
                    "{} values on a frame line, expected {total}",
                    row.len() + toks.count()
                ),
            ));
        }
        let mut c = 0;
        for (j, js) in joints.iter().zip(slots) {
            let mut tr = j.offset;
            let mut q = DQuat::IDENTITY;
            for ch in js {
                let v = row[c];
                c += 1;
                match ch {
                    Some(ch) if ch.is_rotation() => {
                        q *= euler::axis_rotation(ch.axis(), v.to_radians())
                    }
                    Some(ch) => tr[ch.axis()] = v,
                    None => {}
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
    let text = crate::util::fsutil::read_text(path)?;
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
    // An explicit stack, not recursion: a chain of 100,000 joints (which
    // the reader accepts) overflowed the stack (`mocap convert` aborted);
    // the indentation stops deepening at MAX_INDENT tabs, as one tab per
    // level made such a file's text quadratic in its depth.
    const MAX_INDENT: usize = 32;
    enum Step {
        Open(usize, usize),
        Close(usize, usize),
    }
    let mut stack = vec![Step::Open(0, 0)];
    while let Some(step) = stack.pop() {
        match step {
            Step::Open(j, depth) => {
                let ind = "\t".repeat(depth.min(MAX_INDENT));
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
                stack.push(Step::Close(j, depth));
                for c in children[j].iter().rev() {
                    stack.push(Step::Open(c.idx(), depth + 1));
                }
            }
            Step::Close(j, depth) => {
                let ind = "\t".repeat(depth.min(MAX_INDENT));
                if children[j].is_empty() {
                    let t = clip.joints[j].tail.unwrap_or(DVec3::ZERO);
                    let _ = writeln!(
                        s,
                        "{ind}\tEnd Site\n{ind}\t{{\n{ind}\t\tOFFSET {} {} {}\n{ind}\t}}",
                        t.x, t.y, t.z
                    );
                }
                let _ = writeln!(s, "{ind}}}");
            }
        }
    }
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
    crate::util::fsutil::write_bytes_atomic(path, text.as_bytes())?;
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
                e.starts_with("t.bvh:17:") && e.contains("`BvhOptions::fps`"),
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

    /// Binary garbage read as a BVH: the error names the file and line and
    /// quotes at most 40 characters of what it found, escaped (no raw
    /// control bytes or undecodable bytes reach the terminal).
    #[test]
    fn binary_garbage_is_quoted_escaped_and_bounded() {
        let mut bytes: Vec<u8> = b"\x89PNG\x1b[2J\x07\x00".to_vec();
        let mut x = 12345u32;
        for _ in 0..5000 {
            x = x.wrapping_mul(1_103_515_245).wrapping_add(12345);
            let b = (x >> 16) as u8;
            let blank = b.is_ascii_whitespace() || matches!(b, 0x0b | b'{' | b'}');
            bytes.push(if blank { b'a' } else { b });
        }
        let text = crate::util::fsutil::decode_text(bytes);
        let e = parse_bvh(&text, Path::new("g.bvh"), &BvhOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("g.bvh:1: expected HIERARCHY, found '"), "{e}");
        assert!(!e.chars().any(|c| c.is_control()), "{e:?}");
        assert!(e.contains("\\u{fffd}PNG\\x1b[2J\\x07\\x00"), "{e}");
        // 40 characters quoted, each at most 8 once escaped (`\u{fffd}`).
        assert!(
            e.ends_with("…'") && e.chars().count() <= 40 + 8 * QUOTE_CHARS,
            "{e}"
        );
        // A garbage keyword and a garbage number inside a valid file, too.
        let bad = SMALL.replace("OFFSET", "\u{1}\u{fffd}OFF");
        let e = parse_bvh(&bad, Path::new("t.bvh"), &BvhOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown keyword '\\x01\\u{fffd}OFF'"), "{e}");
        let bad = SMALL.replace(
            "1 2 3 0 0 0 90 0 0",
            &format!("1 2 {} 0 0 0 90 0 0", "9".repeat(500)),
        );
        let e = parse_bvh(&bad, Path::new("t.bvh"), &BvhOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("t.bvh:19:") && e.len() < 200, "{e}");
        assert_eq!(quoted("a'b\\c\td"), "'a\\'b\\\\c\\x09d'");
        assert_eq!(quoted(&"é".repeat(40)), format!("'{}'", "é".repeat(40)));
    }

    #[test]
    fn fps_override_and_bad_frame_time() {
        let bad = SMALL.replace("Frame Time: .5", "Frame Time: 0");
        assert!(parse_bvh(&bad, Path::new("t.bvh"), &BvhOptions::default()).is_err());
        let c = parse_bvh(&bad, Path::new("t.bvh"), &BvhOptions { fps: Some(30.0) }).unwrap();
        assert!((c.fps() - 30.0).abs() < 1e-9);
    }

    /// A single pose written with `Frame Time: 0` (bind poses) reads at an
    /// assumed 30 fps with a warning; with two frames it is still an error.
    #[test]
    fn a_single_frame_needs_no_frame_time() {
        let one = SMALL
            .replace("Frames: 5", "Frames: 1")
            .replace("Frame Time: .5", "Frame Time: 0")
            .replace("1 2 3 0 0 0 90 0 0\r\n", "");
        let c = parse_bvh(&one, Path::new("t.bvh"), &BvhOptions::default()).unwrap();
        assert_eq!(c.frame_count(), 1);
        assert!((c.fps() - 30.0).abs() < 1e-9);
        assert!(
            c.warnings.iter().any(|w| w.contains("single frame")),
            "{:?}",
            c.warnings
        );
        let two = one.replace(
            "1 2 3 90 0 0 0 0 0\r\n",
            "1 2 3 90 0 0 0 0 0\r\n1 2 3 0 0 0 90 0 0\r\n",
        );
        let e = parse_bvh(&two, Path::new("t.bvh"), &BvhOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("t.bvh:") && e.contains("for 2 frames"), "{e}");
    }

    /// A file without frames (`Frames: 0`, or its only frame line short of
    /// values) is refused naming the line, not read as a truncated file.
    #[test]
    fn no_frames_and_a_short_only_frame_name_the_line() {
        let (head, _) = SMALL.split_once("MOTION").unwrap();
        let none = format!("{head}MOTION\nFrames: 0\nFrame Time: .5\n");
        let e = parse_bvh(&none, Path::new("t.bvh"), &BvhOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("t.bvh:17: no motion frames") && e.contains("Frames: 0"),
            "{e}"
        );
        let short = format!("{head}MOTION\nFrames: 1\nFrame Time: .5\n1 2 3 90 0 0 0 0\n");
        let e = parse_bvh(&short, Path::new("t.bvh"), &BvhOptions::default())
            .unwrap_err()
            .to_string();
        assert_eq!(e, "t.bvh:18: 8 values on a frame line, expected 9");
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
