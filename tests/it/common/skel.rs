//! The compact skeleton description of the mocap-suite tests
//! (`tests/suites.rs`, `tests/rig_mapping.rs` and its
//! `tests/fixtures/suites/*.skel`), one format for both, and the helpers
//! both check a suite with (its expected map, the differences of a
//! detection from it, left/right mirroring).
//!
//! A description, line by line: `#` comments (the source); directives
//! `unit U` (the unit the file is written in: `mm`, `cm`, `dm`, `m`, `inch`,
//! `ft`, `mmd`: MikuMikuDance's 8 cm),
//! `axes A` (the file's frame: `y` Y-up facing +Z; `y-z` Y-up facing -Z;
//! `zup-y` Z-up facing -Y; `zup+y` Z-up facing +Y), `scale K` (file units
//! per unit written below), `order …` (the rotation channels), `all6` (six
//! channels on every joint, as Perception Neuron writes them), `crlf`,
//! `tabs`; then one joint per line, its depth the number of leading
//! spaces: `name x y z [| ex ey ez] [@ r1 r2 r3] [% [6] order]` (the
//! offset; an optional End Site; optional rotation channel values of the
//! two frames, else zero; `% 6` gives that joint position channels, `%
//! order` its own rotation order, else the `order` line's; names may hold
//! spaces); `mirror NAME FROM=>TO` at a depth stands for the subtree of
//! the joint NAME above with x negated and FROM replaced by TO in its
//! names (a right arm written as the left one). Offsets are written Y-up facing +Z with the body's left at +X
//! and turned into `axes` when the file is written, unless the description
//! is `raw` (the fixtures' files: offsets already in the file's frame).

use glam::{DQuat, DVec3};
use surfmotion::mocap::bvh::format_bvh;
use surfmotion::mocap::{Channel, Clip, Joint, JointId, PointConvention, Units, UpAxis};
use surfmotion::rig::Canonical;

/// A parsed description (module docs).
pub struct Skel {
    pub unit: String,
    pub axes: String,
    pub scale: f64,
    pub order: String,
    pub all6: bool,
    pub crlf: bool,
    pub tabs: bool,
    /// Offsets already in the file's frame, `axes` only saying which frame
    /// that is.
    pub raw: bool,
    pub rows: Vec<Row>,
}

/// One joint line.
pub struct Row {
    pub depth: usize,
    pub name: String,
    pub offset: DVec3,
    pub end: Option<DVec3>,
    /// Rotation channel values of both frames (`@`), in the joint's order.
    pub rot: Option<DVec3>,
    /// Position channels of its own (`% 6`).
    pub pos: bool,
    pub order: String,
}

fn v3(t: &str) -> DVec3 {
    let v: Vec<f64> = t
        .split_whitespace()
        .map(|x| x.parse().unwrap_or_else(|_| panic!("not a number: {x}")))
        .collect();
    assert_eq!(v.len(), 3, "expected three numbers: {t}");
    DVec3::new(v[0], v[1], v[2])
}

/// Parses a description (module docs).
pub fn parse_skel(text: &str) -> Skel {
    let mut s = Skel {
        unit: "cm".into(),
        axes: "y".into(),
        scale: 1.0,
        order: "Zrotation Xrotation Yrotation".into(),
        all6: false,
        crlf: false,
        tabs: false,
        raw: false,
        rows: Vec::new(),
    };
    for line in text.lines() {
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let (key, rest) = t.split_once(' ').unwrap_or((t, ""));
        match key {
            "unit" => s.unit = rest.trim().into(),
            "axes" => s.axes = rest.trim().into(),
            "scale" => s.scale = rest.trim().parse().unwrap(),
            "order" => s.order = rest.trim().into(),
            "all6" => s.all6 = true,
            "crlf" => s.crlf = true,
            "tabs" => s.tabs = true,
            "mirror" => {
                let depth = line.len() - line.trim_start_matches(' ').len();
                let rows = mirrored(&s.rows, rest, depth);
                s.rows.extend(rows);
            }
            _ => {
                let depth = line.len() - line.trim_start_matches(' ').len();
                let (t, own) = match t.split_once('%') {
                    Some((b, o)) => (b.trim(), Some(o.trim())),
                    None => (t, None),
                };
                let (pos, order) = match own {
                    Some(o) => match o.strip_prefix('6') {
                        Some(r) if r.trim().is_empty() => (true, s.order.clone()),
                        Some(r) => (true, r.trim().to_string()),
                        None => (false, o.to_string()),
                    },
                    None => (false, s.order.clone()),
                };
                let (t, rot) = match t.split_once('@') {
                    Some((b, r)) => (b.trim(), Some(v3(r))),
                    None => (t, None),
                };
                let (body, end) = match t.split_once('|') {
                    Some((b, e)) => (b.trim(), Some(v3(e))),
                    None => (t, None),
                };
                let toks: Vec<&str> = body.split_whitespace().collect();
                let k = toks.len() - 3;
                s.rows.push(Row {
                    depth,
                    name: toks[..k].join(" "),
                    offset: v3(&toks[k..].join(" ")),
                    end,
                    rot,
                    pos,
                    order,
                });
            }
        }
    }
    s
}

/// The rows of `mirror NAME FROM=>TO` at `depth`: the subtree of the
/// joint NAME given before, its left and right swapped (x negated, FROM
/// replaced by TO in every name), rooted at `depth`. Most rigs' right side
/// is their left side so mirrored.
fn mirrored(rows: &[Row], spec: &str, depth: usize) -> Vec<Row> {
    let (name, swap) = spec
        .trim()
        .rsplit_once(' ')
        .unwrap_or_else(|| panic!("mirror {spec}: expected NAME FROM=>TO"));
    let (from, to) = swap
        .split_once("=>")
        .unwrap_or_else(|| panic!("mirror {spec}: expected FROM=>TO"));
    let root = rows
        .iter()
        .rposition(|r| r.name == name)
        .unwrap_or_else(|| panic!("mirror {spec}: no joint {name} before it"));
    let d0 = rows[root].depth;
    let flip = |v: DVec3| DVec3::new(0.0 - v.x, v.y, v.z);
    let below = rows[root + 1..].iter().take_while(|r| r.depth > d0);
    std::iter::once(&rows[root])
        .chain(below)
        .map(|r| {
            assert!(r.rot.is_none(), "mirror {spec}: {} has rotations", r.name);
            Row {
                depth: r.depth - d0 + depth,
                name: r.name.replace(from, to),
                offset: flip(r.offset),
                end: r.end.map(flip),
                rot: None,
                pos: r.pos,
                order: r.order.clone(),
            }
        })
        .collect()
}

/// A BVH from a `tests/fixtures/suites` description (raw: offsets in the
/// file's frame): two frames of the rest pose (every rotation zero unless
/// given by `@`, the root at its offset), so only the hierarchy and the
/// rest geometry decide, unless rotations stand up a rest that does not
/// stand (LAFAN1).
pub fn skel_to_bvh(text: &str) -> String {
    let mut k = parse_skel(text);
    k.raw = true;
    k.bvh()
}

impl Skel {
    /// The rotation taking the description's frame (Y-up, facing +Z) to
    /// the file's.
    pub fn axes(&self) -> DQuat {
        use std::f64::consts::{FRAC_PI_2, PI};
        match self.axes.as_str() {
            "y" => DQuat::IDENTITY,
            "y-z" => DQuat::from_rotation_y(PI),
            // +Y → +Z, +Z → -Y, +X → +X.
            "zup-y" => DQuat::from_rotation_x(FRAC_PI_2),
            // +Y → +Z, +Z → +Y, +X → -X.
            "zup+y" => DQuat::from_rotation_z(PI) * DQuat::from_rotation_x(FRAC_PI_2),
            a => panic!("axes {a}"),
        }
    }

    pub fn z_up(&self) -> bool {
        self.axes.starts_with("zup")
    }

    pub fn metres_per_unit(&self) -> f64 {
        match self.unit.as_str() {
            "mm" => 0.001,
            "cm" => 0.01,
            "dm" => 0.1,
            "m" => 1.0,
            "inch" => 0.0254,
            "ft" => 0.3048,
            "mmd" => 0.08,
            u => panic!("unit {u}"),
        }
    }

    pub fn units(&self) -> Units {
        Units {
            metres_per_unit: self.metres_per_unit(),
            name: self.unit.clone(),
            reason: "stated".into(),
        }
    }

    /// The rotation taking a written offset into the file's frame and
    /// units (the identity for a raw description, but its scale).
    fn to_file(&self, v: DVec3) -> DVec3 {
        let a = if self.raw {
            DQuat::IDENTITY
        } else {
            self.axes()
        };
        a * v * self.scale
    }

    /// Parent of each row (by depth).
    fn parents(&self) -> Vec<Option<usize>> {
        let mut parents = Vec::new();
        let mut stack: Vec<(usize, usize)> = Vec::new();
        for (i, r) in self.rows.iter().enumerate() {
            while stack.last().is_some_and(|&(d, _)| d >= r.depth) {
                stack.pop();
            }
            parents.push(stack.last().map(|&(_, j)| j));
            stack.push((r.depth, i));
        }
        parents
    }

    /// Whether row `i` (with parent `parent`) has position channels.
    fn six(&self, i: usize, parent: Option<usize>) -> bool {
        parent.is_none() || self.rows[i].pos || self.all6
    }

    /// The joints, in file order and frame, with two frames of the rest.
    /// Rest rotations (`@`) are written by [`Skel::bvh`] only.
    pub fn clip(&self) -> Clip {
        assert!(
            self.rows.iter().all(|r| r.rot.is_none()),
            "a rest given by rotations (@): read Skel::bvh() instead"
        );
        let parents = self.parents();
        let mut joints = Vec::new();
        for (i, r) in self.rows.iter().enumerate() {
            let rot: Vec<Channel> = r
                .order
                .split_whitespace()
                .map(|c| Channel::parse(c).unwrap())
                .collect();
            let channels = if self.six(i, parents[i]) {
                let mut c = vec![Channel::Xposition, Channel::Yposition, Channel::Zposition];
                c.extend(rot);
                c
            } else {
                rot
            };
            joints.push(Joint {
                name: r.name.clone(),
                parent: parents[i].map(|p| JointId(p as u32)),
                offset: self.to_file(r.offset),
                channels,
                tail: r.end.map(|e| self.to_file(e)),
            });
        }
        let n = joints.len();
        let rot = vec![DQuat::IDENTITY; 2 * n];
        let tr: Vec<DVec3> = (0..2)
            .flat_map(|_| joints.iter().map(|j| j.offset))
            .collect();
        Clip::new(
            joints,
            1.0 / 30.0,
            rot,
            tr,
            self.units(),
            if self.z_up() { UpAxis::Z } else { UpAxis::Y },
            PointConvention::JointOrigins,
        )
        .unwrap()
    }

    /// The description written straight as BVH text: two frames of the
    /// rest, each rotation channel its `@` value (else zero), each position
    /// channel the joint's offset; this family's line ends and indentation.
    pub fn bvh(&self) -> String {
        let v = |p: DVec3| format!("{} {} {}", p.x, p.y, p.z);
        let parents = self.parents();
        let mut out = vec!["HIERARCHY".to_string()];
        let mut open: Vec<(usize, Option<DVec3>)> = Vec::new();
        let close = |open: &mut Vec<(usize, Option<DVec3>)>, out: &mut Vec<String>, to: usize| {
            while open.len() > to {
                let (d, end) = open.pop().unwrap();
                let ind = "  ".repeat(d);
                if let Some(e) = end {
                    out.push(format!(
                        "{ind}  End Site\n{ind}  {{\n{ind}    OFFSET {}\n{ind}  }}",
                        v(e)
                    ));
                }
                out.push(format!("{ind}}}"));
            }
        };
        let mut frame = Vec::new();
        for (i, r) in self.rows.iter().enumerate() {
            // Depth in the written file: the number of open ancestors.
            let d = std::iter::successors(parents[i], |&p| parents[p]).count();
            close(&mut open, &mut out, d);
            let ind = "  ".repeat(d);
            let kw = if d == 0 { "ROOT" } else { "JOINT" };
            let off = self.to_file(r.offset);
            out.push(format!(
                "{ind}{kw} {}\n{ind}{{\n{ind}  OFFSET {}",
                r.name,
                v(off)
            ));
            let rot = r.rot.map_or("0 0 0".to_string(), v);
            if self.six(i, parents[i]) {
                out.push(format!(
                    "{ind}  CHANNELS 6 Xposition Yposition Zposition {}",
                    r.order
                ));
                frame.push(format!("{} {rot}", v(off)));
            } else {
                out.push(format!("{ind}  CHANNELS 3 {}", r.order));
                frame.push(rot);
            }
            open.push((d, r.end.map(|e| self.to_file(e))));
        }
        close(&mut open, &mut out, 0);
        let frame = frame.join(" ");
        let text = format!(
            "{}\nMOTION\nFrames: 2\nFrame Time: 0.0333333\n{frame}\n{frame}\n",
            out.join("\n")
        );
        self.styled(text)
    }

    /// The BVH text of `c` with this family's line ends and indentation.
    pub fn text(&self, c: &Clip) -> String {
        self.styled(format_bvh(c))
    }

    /// `text` with this family's indentation (`tabs`) and line ends
    /// (`crlf`).
    fn styled(&self, mut t: String) -> String {
        if self.tabs {
            t = t
                .lines()
                .map(|l| {
                    let n = l.len() - l.trim_start_matches(' ').len();
                    format!("{}{}", "\t".repeat(n / 2), l.trim_start_matches(' '))
                })
                .collect::<Vec<_>>()
                .join("\n")
                + "\n";
        }
        if self.crlf {
            t = t.replace('\n', "\r\n");
        }
        t
    }
}

/// A family of real-world humanoid BVH: its skeleton, the convention name
/// `rigmap` must report, where left/right must come from (the start of
/// the detection's `sides`), and the full canonical map (`canonical=joint`
/// separated by `;`; `~` a joint the map derives: a toe from the ankle's
/// End Site, a head from the neck's; `a|b` either of two joints at one
/// place, e.g. in a zero-length chain).
pub struct Suite {
    pub name: &'static str,
    pub skel: &'static str,
    pub convention: &'static str,
    pub sides: &'static str,
    pub map: &'static str,
}

/// The expected map: canonical joint → accepted joint names (empty:
/// derived).
pub fn expected(s: &Suite) -> Vec<(Canonical, Vec<String>)> {
    let rows: Vec<(Canonical, Vec<String>)> = s
        .map
        .split(';')
        .map(|kv| {
            let (k, v) = kv.split_once('=').unwrap();
            let c = Canonical::from_name(k.trim()).unwrap_or_else(|| panic!("{k}"));
            let v = v.trim();
            let names = if v == "~" {
                Vec::new()
            } else {
                v.split('|').map(str::to_string).collect()
            };
            (c, names)
        })
        .collect();
    assert_eq!(rows.len(), Canonical::COUNT, "{}", s.name);
    rows
}

/// What differs between a detection and `want` (joint names, derived
/// joints), one line per canonical joint.
pub fn map_errors(
    d: &surfmotion::rig::Detection,
    want: &[(Canonical, Vec<String>)],
) -> Vec<String> {
    let mut out = Vec::new();
    for (c, names) in want {
        let got = d.map.joints.get(c);
        let ok = if names.is_empty() {
            got.is_none() && d.map.derived.contains_key(c)
        } else {
            got.is_some_and(|g| names.contains(g))
        };
        if !ok {
            out.push(format!(
                "{} = {} (want {})",
                c.name(),
                got.map_or("derived/missing", String::as_str),
                if names.is_empty() {
                    "derived".to_string()
                } else {
                    names.join("|")
                }
            ));
        }
    }
    if !d.missing.is_empty() {
        out.push(format!("missing {:?}", d.missing));
    }
    out
}

/// The canonical joint on the other side (`l_knee` ↔ `r_knee`; the
/// spine's own).
pub fn swap_side(c: Canonical) -> Canonical {
    let n = c.name();
    let o = if let Some(r) = n.strip_prefix("l_") {
        format!("r_{r}")
    } else if let Some(r) = n.strip_prefix("r_") {
        format!("l_{r}")
    } else {
        n.to_string()
    };
    Canonical::from_name(&o).unwrap_or(c)
}

/// The clip with every joint renamed `J<k>` (its index): no name hints.
pub fn unnamed(c: &Clip) -> Clip {
    c.clone()
        .edited(|p| {
            for (k, j) in p.joints.iter_mut().enumerate() {
                j.name = format!("J{k}");
            }
        })
        .unwrap()
}

/// The clip mirrored left/right (x negated in the file's frame; the names
/// kept).
pub fn mirror(c: &Clip) -> Clip {
    let m = DVec3::new(-1.0, 1.0, 1.0);
    let mut out = c.clone().into_parts();
    for j in &mut out.joints {
        j.offset *= m;
        if let Some(t) = &mut j.tail {
            *t *= m;
        }
    }
    for t in &mut out.translations {
        *t *= m;
    }
    for q in &mut out.rotations {
        *q = DQuat::from_xyzw(q.x, -q.y, -q.z, q.w);
    }
    Clip::from_parts(out).unwrap()
}

/// Every length of a clip (offsets, End Sites, translations) times `k`.
pub fn scaled(c: &Clip, k: f64) -> Clip {
    let mut out = c.clone().into_parts();
    for j in &mut out.joints {
        j.offset *= k;
        j.tail = j.tail.map(|t| t * k);
    }
    for t in &mut out.translations {
        *t *= k;
    }
    Clip::from_parts(out).unwrap()
}
