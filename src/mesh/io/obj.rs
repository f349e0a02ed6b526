//! Wavefront OBJ: positions, optional vertex colours (`v x y z r g b`),
//! polygons (fan-triangulated), groups (`g`/`o`). Texture coordinates,
//! normals, materials and smoothing groups are ignored. A `\` at the end
//! of a line continues the statement on the next line (the format's line
//! continuation); errors name the statement's first line.

use crate::mesh::{Group, Mesh, MeshError};
use std::borrow::Cow;
use std::fmt::Write as _;
use std::path::Path;

/// The statements of OBJ text with comments removed: each with its first
/// line (1-based), lines ending in `\` (after any comment is removed)
/// joined with the next. Borrowed unless a continuation joined lines; a
/// `\` on the last line ends the statement.
fn statements(text: &str) -> impl Iterator<Item = (usize, Cow<'_, str>)> {
    let mut lines = text.lines().enumerate();
    std::iter::from_fn(move || {
        let mut joined: Option<(usize, String)> = None;
        for (i, raw) in lines.by_ref() {
            let code = raw.split('#').next().unwrap_or("");
            match (code.trim_end().strip_suffix('\\'), &mut joined) {
                (Some(head), Some((_, s))) => {
                    s.push_str(head);
                    s.push(' ');
                }
                (Some(head), None) => joined = Some((i + 1, format!("{head} "))),
                (None, Some((first, s))) => {
                    s.push_str(code);
                    return Some((*first, Cow::Owned(std::mem::take(s))));
                }
                (None, None) => return Some((i + 1, Cow::Borrowed(code))),
            }
        }
        joined.map(|(first, s)| (first, Cow::Owned(s)))
    })
}

/// Parses OBJ text; `path` names the source in errors.
pub fn parse_obj(text: &str, path: &Path) -> Result<Mesh, MeshError> {
    let mut pos: Vec<[f64; 3]> = Vec::new();
    let mut col: Vec<[f64; 3]> = Vec::new();
    let mut tris: Vec<[u32; 3]> = Vec::new();
    let mut groups: Vec<Group> = Vec::new();
    let mut poly: Vec<u32> = Vec::with_capacity(8);
    for (line, code) in statements(text) {
        let l = code.trim();
        let mut it = l.split_whitespace();
        let Some(key) = it.next() else { continue };
        match key {
            "v" => {
                let mut v = [0.0f64; 7];
                let mut k = 0;
                for tok in it {
                    if k == 7 {
                        return Err(MeshError::parse(
                            path,
                            line,
                            "too many values on a 'v' line",
                        ));
                    }
                    v[k] = tok
                        .parse::<f64>()
                        .ok()
                        .filter(|x| x.is_finite())
                        .ok_or_else(|| {
                            MeshError::parse(path, line, format!("bad coordinate '{tok}'"))
                        })?;
                    if v[k].abs() > super::format::MAX_ABS_COORDINATE {
                        return Err(MeshError::parse(
                            path,
                            line,
                            format!(
                                "coordinate {tok} is beyond ±{:e}",
                                super::format::MAX_ABS_COORDINATE
                            ),
                        ));
                    }
                    k += 1;
                }
                if k < 3 {
                    return Err(MeshError::parse(path, line, "a vertex needs 3 coordinates"));
                }
                pos.push([v[0], v[1], v[2]]);
                if k >= 6 {
                    let c = if k == 7 {
                        [v[4], v[5], v[6]]
                    } else {
                        [v[3], v[4], v[5]]
                    };
                    // Some writers store colours 0..255.
                    col.push(c);
                } else if !col.is_empty() {
                    return Err(MeshError::parse(
                        path,
                        line,
                        "vertex without a colour after coloured vertices",
                    ));
                }
                if !col.is_empty() && col.len() != pos.len() {
                    return Err(MeshError::parse(
                        path,
                        line,
                        "coloured vertex after uncoloured vertices",
                    ));
                }
            }
            "f" => {
                poly.clear();
                let n = pos.len() as i64;
                for tok in it {
                    let first = tok.split('/').next().unwrap_or("");
                    let idx: i64 = first.parse().map_err(|_| {
                        MeshError::parse(path, line, format!("bad face index '{tok}'"))
                    })?;
                    let v = if idx > 0 { idx - 1 } else { n + idx };
                    if idx == 0 || v < 0 || v >= n {
                        return Err(MeshError::parse(
                            path,
                            line,
                            format!("face index {idx} out of range ({n} vertices so far)"),
                        ));
                    }
                    poly.push(v as u32);
                }
                if poly.len() < 3 {
                    return Err(MeshError::parse(
                        path,
                        line,
                        "a face needs at least 3 vertices",
                    ));
                }
                for k in 1..poly.len() - 1 {
                    tris.push([poly[0], poly[k], poly[k + 1]]);
                }
            }
            "g" | "o" => {
                let name = it.collect::<Vec<_>>().join(" ");
                let start = tris.len() as u32;
                if let Some(last) = groups.last_mut() {
                    last.end = start;
                }
                groups.push(Group {
                    name: if name.is_empty() {
                        "default".into()
                    } else {
                        name
                    },
                    start,
                    end: start,
                });
            }
            _ => {}
        }
    }
    if let Some(last) = groups.last_mut() {
        last.end = tris.len() as u32;
    }
    if pos.is_empty() {
        return Err(MeshError::invalid(path, "no vertices"));
    }
    let mut mesh = Mesh::new(pos, tris).map_err(|e| MeshError::from(e).in_file(path))?;
    if !col.is_empty() {
        if col.iter().flatten().any(|&c| c > 1.0) {
            col.iter_mut()
                .for_each(|c| c.iter_mut().for_each(|v| *v /= 255.0));
        }
        mesh = mesh
            .with_colors(col)
            .map_err(|e| MeshError::from(e).in_file(path))?;
    }
    Ok(mesh.with_groups(groups))
}

/// Reads an OBJ file.
pub fn read_obj(path: &Path) -> Result<Mesh, MeshError> {
    parse_obj(&crate::util::fsutil::read_text(path)?, path)
}

/// Formats a mesh as OBJ with the given positions (the mesh's own if `None`).
/// Floats use the shortest exact decimal form, so reading back is lossless.
pub fn format_obj(mesh: &Mesh, positions: Option<&[[f64; 3]]>) -> String {
    let p = positions.unwrap_or(mesh.positions());
    let mut s = String::with_capacity(p.len() * 40 + mesh.triangle_count() * 24);
    s.push_str("# written by surfmotion\n");
    match mesh.colors() {
        Some(c) => {
            for (v, c) in p.iter().zip(c) {
                let _ = writeln!(s, "v {} {} {} {} {} {}", v[0], v[1], v[2], c[0], c[1], c[2]);
            }
        }
        None => {
            for v in p {
                let _ = writeln!(s, "v {} {} {}", v[0], v[1], v[2]);
            }
        }
    }
    let groups = mesh.groups();
    let mut gi = 0;
    for (t, tri) in mesh.triangles().iter().enumerate() {
        while gi < groups.len() && groups[gi].start as usize == t {
            let _ = writeln!(s, "g {}", groups[gi].name);
            gi += 1;
        }
        let _ = writeln!(s, "f {} {} {}", tri[0] + 1, tri[1] + 1, tri[2] + 1);
    }
    s
}

/// Writes an OBJ file atomically.
pub fn write_obj(
    mesh: &Mesh,
    positions: Option<&[[f64; 3]]>,
    path: &Path,
) -> Result<(), MeshError> {
    crate::util::fsutil::write_bytes_atomic(path, format_obj(mesh, positions).as_bytes())?;
    Ok(())
}
