//! Stanford PLY, ascii and binary (little and big endian): vertex `x y z`
//! (+ optional `red green blue`), face `vertex_indices`/`vertex_index` lists
//! (fan-triangulated). Other elements and properties are skipped.

use crate::mesh::{Mesh, MeshError};
use std::path::Path;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

#[derive(Debug, Clone)]
struct Prop {
    name: String,
    ty: Scalar,
    list_len: Option<Scalar>,
}

#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Prop>,
}

#[derive(Clone, Copy, PartialEq)]
enum Format {
    Ascii,
    Le,
    Be,
}

/// Reads scalars from the body, ascii or binary.
struct Body<'a> {
    bytes: &'a [u8],
    pos: usize,
    fmt: Format,
    path: &'a Path,
    /// ascii: tokens and the line each sits on
    words: Vec<(&'a str, usize)>,
    wi: usize,
}

impl<'a> Body<'a> {
    fn read(&mut self, ty: Scalar) -> Result<f64, MeshError> {
        if self.fmt == Format::Ascii {
            let Some(&(w, line)) = self.words.get(self.wi) else {
                return Err(MeshError::invalid(
                    self.path,
                    "file ends before all elements were read",
                ));
            };
            self.wi += 1;
            return w
                .parse::<f64>()
                .map_err(|_| MeshError::parse(self.path, line, format!("bad number '{w}'")));
        }
        let n = ty.size();
        if self.pos + n > self.bytes.len() {
            return Err(MeshError::invalid(
                self.path,
                format!(
                    "truncated: binary data ends at byte {} before all elements were read",
                    self.bytes.len()
                ),
            ));
        }
        let b = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        let mut a = [0u8; 8];
        a[..n].copy_from_slice(b);
        if self.fmt == Format::Be {
            a[..n].reverse();
        }
        Ok(match ty {
            Scalar::I8 => a[0] as i8 as f64,
            Scalar::U8 => a[0] as f64,
            Scalar::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(a),
        })
    }
    /// Bytes (binary) or tokens (ascii) left.
    fn left(&self) -> usize {
        match self.fmt {
            Format::Ascii => self.words.len() - self.wi,
            _ => self.bytes.len() - self.pos,
        }
    }
}

/// A PLY header: its elements, the body's format, where the body starts
/// and the header's last line number.
struct Header {
    elements: Vec<Element>,
    fmt: Format,
    body_start: usize,
    line_no: usize,
}

/// Parses PLY bytes: the header, the body's elements, the mesh.
pub fn parse_ply(bytes: &[u8], path: &Path) -> Result<Mesh, MeshError> {
    let header = parse_header(bytes, path)?;
    let mut body = Body::new(bytes, &header, path)?;
    let mut out = Parsed::default();
    for el in &header.elements {
        read_element(el, &mut body, path, &mut out)?;
    }
    out.into_mesh(path)
}

/// The header: text up to and including the "end_header" line.
fn parse_header(bytes: &[u8], path: &Path) -> Result<Header, MeshError> {
    let mut elements: Vec<Element> = Vec::new();
    let mut fmt = None;
    let mut pos = 0usize;
    let mut line_no = 0usize;
    let mut ended = false;
    while pos < bytes.len() {
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |k| pos + k + 1);
        let line = String::from_utf8_lossy(&bytes[pos..end]);
        let line = line.trim();
        pos = end;
        line_no += 1;
        let toks: Vec<&str> = line.split_whitespace().collect();
        if line_no == 1 {
            if line != "ply" {
                return Err(MeshError::invalid(
                    path,
                    "not a PLY file (first line is not 'ply')",
                ));
            }
            continue;
        }
        match toks.first().copied() {
            Some("format") => {
                fmt = Some(match toks.get(1).copied() {
                    Some("ascii") => Format::Ascii,
                    Some("binary_little_endian") => Format::Le,
                    Some("binary_big_endian") => Format::Be,
                    other => {
                        return Err(MeshError::parse(
                            path,
                            line_no,
                            format!("unknown format {other:?}"),
                        ));
                    }
                })
            }
            Some("element") => {
                let (Some(name), Some(count)) = (toks.get(1), toks.get(2)) else {
                    return Err(MeshError::parse(
                        path,
                        line_no,
                        "element needs a name and a count",
                    ));
                };
                let count: usize = count
                    .parse()
                    .map_err(|_| MeshError::parse(path, line_no, format!("bad count '{count}'")))?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => push_property(&mut elements, &toks, line, line_no, path)?,
            Some("end_header") => {
                ended = true;
                break;
            }
            Some("comment") | Some("obj_info") | None => {}
            Some(other) => {
                return Err(MeshError::parse(
                    path,
                    line_no,
                    format!("unknown header keyword '{other}'"),
                ));
            }
        }
    }
    if !ended {
        return Err(MeshError::invalid(path, "no end_header"));
    }
    let fmt = fmt.ok_or_else(|| MeshError::invalid(path, "no format line"))?;
    Ok(Header {
        elements,
        fmt,
        body_start: pos,
        line_no,
    })
}

/// A `property` line (`toks`, line `line_no`): a scalar or a list property
/// of the last element.
fn push_property(
    elements: &mut [Element],
    toks: &[&str],
    line: &str,
    line_no: usize,
    path: &Path,
) -> Result<(), MeshError> {
    let Some(el) = elements.last_mut() else {
        return Err(MeshError::parse(
            path,
            line_no,
            "property before any element",
        ));
    };
    let bad = || MeshError::parse(path, line_no, format!("bad property line '{line}'"));
    if toks.get(1) == Some(&"list") {
        let lt = toks.get(2).and_then(|s| Scalar::parse(s)).ok_or_else(bad)?;
        let it = toks.get(3).and_then(|s| Scalar::parse(s)).ok_or_else(bad)?;
        let name = toks.get(4).ok_or_else(bad)?;
        el.props.push(Prop {
            name: name.to_string(),
            ty: it,
            list_len: Some(lt),
        });
    } else {
        let ty = toks.get(1).and_then(|s| Scalar::parse(s)).ok_or_else(bad)?;
        let name = toks.get(2).ok_or_else(bad)?;
        el.props.push(Prop {
            name: name.to_string(),
            ty,
            list_len: None,
        });
    }
    Ok(())
}

impl<'a> Body<'a> {
    /// The body after `header` (ascii: split into tokens with their lines).
    fn new(bytes: &'a [u8], header: &Header, path: &'a Path) -> Result<Body<'a>, MeshError> {
        let (pos, fmt, line_no) = (header.body_start, header.fmt, header.line_no);
        let mut body = Body {
            bytes,
            pos,
            fmt,
            path,
            words: Vec::new(),
            wi: 0,
        };
        if fmt == Format::Ascii {
            let text = std::str::from_utf8(&bytes[pos..])
                .map_err(|_| MeshError::invalid(path, "ascii body is not text"))?;
            for (k, l) in text.lines().enumerate() {
                for w in l.split_whitespace() {
                    body.words.push((w, line_no + k + 1));
                }
            }
        }
        Ok(body)
    }
}

/// What the body's elements gave.
#[derive(Default)]
struct Parsed {
    positions: Vec<[f64; 3]>,
    colors: Vec<[f64; 3]>,
    tris: Vec<[u32; 3]>,
    /// The current face's vertices.
    poly: Vec<u32>,
    has_vertex: bool,
}

/// Reads the items of element `el`: vertices (positions, colours) and
/// faces (fan-triangulated) are kept, other elements skipped.
fn read_element(
    el: &Element,
    body: &mut Body,
    path: &Path,
    out: &mut Parsed,
) -> Result<(), MeshError> {
    // Every item needs at least one scalar per property: bound the count
    // by the data left before looping or allocating.
    if !el.props.is_empty() && el.count > body.left() / el.props.len() {
        return Err(MeshError::invalid(
            path,
            format!(
                "element '{}' claims {} items, more than the data holds",
                el.name, el.count
            ),
        ));
    }
    if el.props.is_empty() {
        return Ok(());
    }
    let is_vertex = el.name == "vertex";
    let is_face = el.name == "face";
    let xi = el.props.iter().position(|p| p.name == "x");
    let yi = el.props.iter().position(|p| p.name == "y");
    let zi = el.props.iter().position(|p| p.name == "z");
    let ci = ["red", "green", "blue"].map(|n| el.props.iter().position(|p| p.name == n));
    let fi = el.props.iter().position(|p| {
        (p.name == "vertex_indices" || p.name == "vertex_index") && p.list_len.is_some()
    });
    if is_vertex {
        out.has_vertex = true;
        if xi.is_none() || yi.is_none() || zi.is_none() {
            return Err(MeshError::invalid(path, "vertex element without x, y, z"));
        }
        out.positions.reserve(el.count);
    }
    let mut vals = vec![0.0f64; el.props.len()];
    for item in 0..el.count {
        for (k, p) in el.props.iter().enumerate() {
            match p.list_len {
                None => vals[k] = body.read(p.ty)?,
                Some(lt) => {
                    let take_face = is_face && Some(k) == fi;
                    read_list(el, item, p.ty, lt, take_face, body, out)?;
                }
            }
        }
        if is_vertex {
            let (x, y, z) = (xi.unwrap_or(0), yi.unwrap_or(0), zi.unwrap_or(0));
            out.positions.push([vals[x], vals[y], vals[z]]);
            if let [Some(r), Some(g), Some(b)] = ci {
                let scale = if el.props[r].ty == Scalar::U8 {
                    1.0 / 255.0
                } else {
                    1.0
                };
                out.colors
                    .push([vals[r] * scale, vals[g] * scale, vals[b] * scale]);
            }
        }
    }
    Ok(())
}

/// Reads one list property (length type `lt`, items `ty`) of item `item`;
/// `take_face`: it is the face's vertex list, fan-triangulated into `out`.
fn read_list(
    el: &Element,
    item: usize,
    ty: Scalar,
    lt: Scalar,
    take_face: bool,
    body: &mut Body,
    out: &mut Parsed,
) -> Result<(), MeshError> {
    let path = body.path;
    let n = body.read(lt)?;
    if !(0.0..=1.0e6).contains(&n) || n.fract() != 0.0 {
        return Err(MeshError::invalid(
            path,
            format!("{} {item}: bad list length {n}", el.name),
        ));
    }
    let n = n as usize;
    let poly = &mut out.poly;
    if take_face {
        poly.clear();
    }
    for _ in 0..n {
        let v = body.read(ty)?;
        if take_face {
            if !(0.0..u32::MAX as f64).contains(&v) || v.fract() != 0.0 {
                return Err(MeshError::invalid(
                    path,
                    format!("face {item}: bad vertex index {v}"),
                ));
            }
            poly.push(v as u32);
        }
    }
    if take_face {
        if poly.len() < 3 {
            return Err(MeshError::invalid(
                path,
                format!("face {item} has {} vertices", poly.len()),
            ));
        }
        for j in 1..poly.len() - 1 {
            out.tris.push([poly[0], poly[j], poly[j + 1]]);
        }
    }
    Ok(())
}

impl Parsed {
    /// The mesh (with its colours, if any).
    fn into_mesh(self, path: &Path) -> Result<Mesh, MeshError> {
        if !self.has_vertex {
            return Err(MeshError::invalid(path, "no vertex element"));
        }
        super::format::refuse_huge_coordinates(&self.positions, path)?;
        let mut mesh =
            Mesh::new(self.positions, self.tris).map_err(|e| MeshError::from(e).in_file(path))?;
        if !self.colors.is_empty() {
            mesh = mesh
                .with_colors(self.colors)
                .map_err(|e| MeshError::from(e).in_file(path))?;
        }
        Ok(mesh)
    }
}

/// Reads a PLY file.
pub(crate) fn read_ply(path: &Path) -> Result<Mesh, MeshError> {
    parse_ply(&crate::util::fsutil::read_bytes(path)?, path)
}

/// Encodes a mesh as binary little-endian PLY (float xyz, uchar colours).
pub fn encode_ply(mesh: &Mesh, positions: Option<&[[f64; 3]]>) -> Vec<u8> {
    let p = positions.unwrap_or(mesh.positions());
    let mut h = format!(
        "ply\nformat binary_little_endian 1.0\ncomment written by surfmotion\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n",
        p.len()
    );
    if mesh.colors().is_some() {
        h.push_str("property uchar red\nproperty uchar green\nproperty uchar blue\n");
    }
    h.push_str(&format!(
        "element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
        mesh.triangle_count()
    ));
    let mut out = h.into_bytes();
    for (i, v) in p.iter().enumerate() {
        for c in v {
            out.extend_from_slice(&(*c as f32).to_le_bytes());
        }
        if let Some(col) = mesh.colors() {
            out.extend(
                col[i]
                    .iter()
                    .map(|c| (c * 255.0).round().clamp(0.0, 255.0) as u8),
            );
        }
    }
    for t in mesh.triangles() {
        out.push(3);
        for v in t {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// Writes a binary PLY atomically.
pub(crate) fn write_ply(
    mesh: &Mesh,
    positions: Option<&[[f64; 3]]>,
    path: &Path,
) -> Result<(), MeshError> {
    crate::util::fsutil::write_bytes_atomic(path, &encode_ply(mesh, positions))?;
    Ok(())
}
