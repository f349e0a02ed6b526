//! Buffers and accessors: the file's buffers (GLB blob, data URIs, external
//! files beside the `.gltf`) and the bounds-checked accessor reads
//! (dense, sparse, normalized and quantised components) over them.

use crate::mesh::MeshError;
use base64::Engine as _;
use gltf::accessor::{DataType, Dimensions};
use std::path::Path;

/// Indices and values of a sparse accessor's substitutions.
type Substitutions = (Vec<usize>, Vec<f32>);

pub(super) struct Ctx<'a> {
    pub(super) path: &'a Path,
    pub(super) buffers: Vec<Vec<u8>>,
}

impl Ctx<'_> {
    pub(super) fn err(&self, msg: impl Into<String>) -> MeshError {
        MeshError::invalid(self.path, msg)
    }

    /// Reads a view's bytes region `[offset, offset + len)`, checked.
    fn view_bytes(&self, view: &gltf::buffer::View) -> Result<&[u8], MeshError> {
        let b = self.buffers.get(view.buffer().index()).ok_or_else(|| {
            self.err(format!(
                "bufferView {} names a missing buffer",
                view.index()
            ))
        })?;
        let (o, l) = (view.offset(), view.length());
        o.checked_add(l).and_then(|e| b.get(o..e)).ok_or_else(|| {
            self.err(format!(
                "bufferView {} (offset {o}, length {l}) exceeds its buffer ({} bytes)",
                view.index(),
                b.len()
            ))
        })
    }

    /// Reads `count` elements of `comps` scalars of type `dt` from a view.
    #[allow(clippy::too_many_arguments)]
    fn read_elements(
        &self,
        view: &gltf::buffer::View,
        offset: usize,
        count: usize,
        comps: usize,
        dt: DataType,
        normalized: bool,
        what: &str,
    ) -> Result<Vec<f32>, MeshError> {
        let bytes = self.view_bytes(view)?;
        let cs = dt.size();
        let elem = cs * comps;
        let stride = view.stride().unwrap_or(elem).max(elem);
        if count > 0 {
            let last = (count - 1)
                .checked_mul(stride)
                .and_then(|v| v.checked_add(offset))
                .and_then(|v| v.checked_add(elem));
            if last.is_none_or(|e| e > bytes.len()) {
                return Err(self.err(format!(
                    "{what}: {count} elements do not fit in bufferView {}",
                    view.index()
                )));
            }
        }
        let mut out = Vec::with_capacity(count * comps);
        for i in 0..count {
            let base = offset + i * stride;
            for c in 0..comps {
                let o = base + c * cs;
                let b = &bytes[o..o + cs];
                let v = match dt {
                    DataType::I8 => {
                        let x = b[0] as i8 as f32;
                        if normalized { (x / 127.0).max(-1.0) } else { x }
                    }
                    DataType::U8 => {
                        let x = b[0] as f32;
                        if normalized { x / 255.0 } else { x }
                    }
                    DataType::I16 => {
                        let x = i16::from_le_bytes([b[0], b[1]]) as f32;
                        if normalized {
                            (x / 32767.0).max(-1.0)
                        } else {
                            x
                        }
                    }
                    DataType::U16 => {
                        let x = u16::from_le_bytes([b[0], b[1]]) as f32;
                        if normalized { x / 65535.0 } else { x }
                    }
                    DataType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
                    DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                };
                out.push(v);
            }
        }
        Ok(out)
    }

    /// Reads an accessor as f32 scalars (integers converted), with sparse
    /// substitution. Returns (values, components per element).
    pub(super) fn read_f32(
        &self,
        acc: &gltf::Accessor,
        what: &str,
    ) -> Result<(Vec<f32>, usize), MeshError> {
        let comps = acc.dimensions().multiplicity();
        let count = acc.count();
        let dt = acc.data_type();
        let mut out = match acc.view() {
            Some(view) => self.read_elements(
                &view,
                acc.offset(),
                count,
                comps,
                dt,
                acc.normalized(),
                what,
            )?,
            None => {
                if count > 100_000_000 {
                    return Err(self.err(format!("{what}: absurd count {count}")));
                }
                // Zeros that no byte of the file backs: a few bytes of JSON
                // declared 6.4 GB (issue 46, item 5).
                crate::util::budget::check(
                    || format!("{what}: {count} elements of {comps} zeros (no bufferView)"),
                    count as u128 * comps as u128 * 4,
                )
                .map_err(|e| self.err(e.to_string()))?;
                vec![0.0; count * comps]
            }
        };
        if let Some(sp) = acc.sparse() {
            let (idx, vals) = self.read_sparse(&sp, comps, dt, acc.normalized(), what)?;
            for (k, &i) in idx.iter().enumerate() {
                if i >= count {
                    return Err(self.err(format!("{what}: sparse index {i} ≥ count {count}")));
                }
                out[i * comps..(i + 1) * comps].copy_from_slice(&vals[k * comps..(k + 1) * comps]);
            }
        }
        Ok((out, comps))
    }

    /// A sparse accessor's substitutions: its indices and its values
    /// (`comps` components of type `dt` each), indices read first.
    fn read_sparse(
        &self,
        sp: &gltf::accessor::sparse::Sparse,
        comps: usize,
        dt: DataType,
        normalized: bool,
        what: &str,
    ) -> Result<(Vec<usize>, Vec<f32>), MeshError> {
        let n = sp.count();
        let iv = sp.indices();
        let it = match iv.index_type() {
            gltf::accessor::sparse::IndexType::U8 => DataType::U8,
            gltf::accessor::sparse::IndexType::U16 => DataType::U16,
            gltf::accessor::sparse::IndexType::U32 => DataType::U32,
        };
        let idx = self.read_indices(&iv.view(), iv.offset(), n, it, what)?;
        let vals = self.read_elements(
            &sp.values().view(),
            sp.values().offset(),
            n,
            comps,
            dt,
            normalized,
            what,
        )?;
        Ok((idx, vals))
    }

    /// `count` unsigned integers of type `it` (exact: an f32 holds
    /// integers only up to 2²⁴, and sparse indices into an F×F weight table
    /// exceed that).
    pub(super) fn read_indices(
        &self,
        view: &gltf::buffer::View,
        offset: usize,
        count: usize,
        it: DataType,
        what: &str,
    ) -> Result<Vec<usize>, MeshError> {
        let bytes = self.view_bytes(view)?;
        let cs = it.size();
        let stride = view.stride().unwrap_or(cs).max(cs);
        let fits = count == 0
            || (count - 1)
                .checked_mul(stride)
                .and_then(|v| v.checked_add(offset + cs))
                .is_some_and(|e| e <= bytes.len());
        if !fits {
            return Err(self.err(format!(
                "{what}: {count} indices do not fit in bufferView {}",
                view.index()
            )));
        }
        Ok((0..count)
            .map(|i| {
                let b = &bytes[offset + i * stride..offset + i * stride + cs];
                match cs {
                    1 => b[0] as usize,
                    2 => u16::from_le_bytes([b[0], b[1]]) as usize,
                    _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
                }
            })
            .collect())
    }

    /// A scalar sparse accessor without a view (zeros but for its
    /// substitutions) as its (index, value) pairs, in O(substitutions)
    /// whatever its count; `None` for any other accessor.
    pub(super) fn read_sparse_zeros(
        &self,
        acc: &gltf::Accessor,
        what: &str,
    ) -> Result<Option<Substitutions>, MeshError> {
        let (None, Some(sp), Dimensions::Scalar) = (acc.view(), acc.sparse(), acc.dimensions())
        else {
            return Ok(None);
        };
        let (idx, vals) = self.read_sparse(&sp, 1, acc.data_type(), acc.normalized(), what)?;
        if idx.windows(2).any(|w| w[1] <= w[0]) || idx.last().is_some_and(|&i| i >= acc.count()) {
            return Err(self.err(format!(
                "{what}: sparse indices must increase and stay under the count {}",
                acc.count()
            )));
        }
        Ok(Some((idx, vals)))
    }

    pub(super) fn read_vec3(
        &self,
        acc: &gltf::Accessor,
        what: &str,
    ) -> Result<Vec<[f64; 3]>, MeshError> {
        if acc.dimensions() != Dimensions::Vec3 {
            return Err(self.err(format!("{what}: expected VEC3")));
        }
        let (v, _) = self.read_f32(acc, what)?;
        Ok(v.chunks_exact(3)
            .map(|c| [c[0] as f64, c[1] as f64, c[2] as f64])
            .collect())
    }
}

pub(super) fn load_buffers(
    doc: &gltf::Document,
    blob: Option<Vec<u8>>,
    path: &Path,
) -> Result<Vec<Vec<u8>>, MeshError> {
    let mut blob = blob;
    let mut out = Vec::new();
    for b in doc.buffers() {
        let data = match b.source() {
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                MeshError::invalid(path, "buffer refers to a missing GLB BIN chunk")
            })?,
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let b64 = rest.split_once(";base64,").map(|x| x.1).ok_or_else(|| {
                        MeshError::invalid(
                            path,
                            format!("buffer {}: only base64 data URIs are supported", b.index()),
                        )
                    })?;
                    base64::engine::general_purpose::STANDARD
                        .decode(b64)
                        .map_err(|e| {
                            MeshError::invalid(
                                path,
                                format!("buffer {}: bad base64: {e}", b.index()),
                            )
                        })?
                } else {
                    let p = buffer_path(path, b.index(), uri)?;
                    // Named with the glTF that refers to it ("missing.bin:
                    // No such file" named neither the .gltf nor the buffer).
                    crate::util::fsutil::read_bytes(&p).map_err(|e| {
                        MeshError::invalid(path, format!("buffer {}: {e}", b.index()))
                    })?
                }
            }
        };
        if data.len() < b.length() {
            return Err(MeshError::invalid(
                path,
                format!(
                    "buffer {} has {} bytes, declares {}",
                    b.index(),
                    data.len(),
                    b.length()
                ),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// The file a buffer's external URI names, or why it is not followed.
///
/// The rule (README, "Mesh formats"): a buffer URI is a relative reference
/// (glTF 2.0 spec, 2.8 "URIs"), percent-decoded and resolved against the
/// glTF's own folder. It may name a file in that folder, below it, or in a
/// sibling folder (`../buffers/x.bin`: one `..` above the glTF's folder at
/// most, counted after `a/../` pairs cancel). Refused, with the glTF, the
/// buffer and the URI named: an absolute path (`/x.bin`, `C:\x.bin`,
/// `\\server\x`), any scheme but `data:` (`file://`, `http://`), and a
/// path climbing two or more folders above the glTF's (`../../x.bin`). A
/// downloaded glTF thus cannot make a conversion read, and write into its
/// output, a file elsewhere on the disk.
fn buffer_path(gltf: &Path, buffer: usize, uri: &str) -> Result<std::path::PathBuf, MeshError> {
    use std::path::PathBuf;
    let refuse = |why: &str| MeshError::BufferUri {
        gltf: gltf.to_path_buf(),
        buffer,
        uri: uri.to_string(),
        why: why.to_string(),
    };
    // A scheme: letters, digits, '+', '-', '.' before the first ':',
    // starting with a letter (RFC 3986, 3.1). One letter is a drive.
    if let Some((scheme, _)) = uri.split_once(':')
        && scheme.starts_with(|c: char| c.is_ascii_alphabetic())
        && scheme
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.'))
    {
        return Err(if scheme.len() == 1 {
            refuse("is an absolute path (a drive letter); name the file relative to the glTF")
        } else {
            refuse("has a scheme; only data: URIs and paths relative to the glTF are read")
        });
    }
    let decoded = crate::util::fsutil::percent_decode(uri)
        .ok_or_else(|| refuse("has a bad percent escape (expected %XX of UTF-8 bytes)"))?;
    if decoded.starts_with(['/', '\\']) {
        return Err(refuse(
            "is an absolute path; name the file relative to the glTF",
        ));
    }
    // The path with `a/..` pairs cancelled (lexically, as the URI reads:
    // `a/c/../x.bin` needs no folder `c`), and how many `..` lead it.
    let mut parts: Vec<&str> = Vec::new();
    for part in decoded.split(['/', '\\']) {
        match part {
            "" | "." => {}
            ".." if parts.last().is_some_and(|p| *p != "..") => {
                parts.pop();
            }
            p => parts.push(p),
        }
    }
    let up = parts.iter().take_while(|p| **p == "..").count();
    let rel: PathBuf = parts.iter().collect();
    if up > 1 {
        return Err(refuse(
            "climbs more than one folder above the glTF's folder; \
             copy the buffer beside the glTF, or into a folder next to it",
        ));
    }
    Ok(gltf.parent().unwrap_or(Path::new(".")).join(rel))
}
