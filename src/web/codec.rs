//! The compact 4D geometry format of the web viewer (`.sm4d`, version 1):
//! one topology and any number of vertex-position sequences, quantised on a
//! uniform grid and predicted from the previous frame and a neighbour, the
//! integer residuals deflated. Volino, Huang & Hilton 2015 (Sec. 4, Table 1)
//! stream 4D characters at 47-92 KB per frame; this layout aims at a tenth
//! of that at a guaranteed maximum vertex error.
//!
//! # Layout (little-endian)
//!
//! ```text
//! offset size  field
//!  0     8     magic "SM4DGEO\0"
//!  8     4     u32 version = 1
//! 12     4     u32 predictor: 0 = temporal, 1 = spatio-temporal
//! 16     4     u32 V, vertices
//! 20     4     u32 T, triangles
//! 24     4     u32 S, sequences
//! 28     4     f32 step: metres per quantisation unit
//! 32    12     3 × f32 origin (metres; the bounds' minimum corner)
//! 44    12     3 × u32 levels per axis (each ≤ 65,536: positions fit u16)
//! 56     4     f32 measured maximum vertex error (metres)
//! 60     4     u32 bytes of the topology block
//! 64   8·S     per sequence: u32 frames, u32 bytes of its block
//! then the topology block, then the S sequence blocks, in order.
//! ```
//!
//! Every block is raw DEFLATE (RFC 1951; the browser's
//! `DecompressionStream("deflate-raw")` inflates it) of a stream of unsigned
//! LEB128 varints holding zigzag-coded integers (`z = (x << 1) ^ (x >> 31)`).
//!
//! - Topology: the 3T vertex indices as differences from the previous index
//!   (the first from 0).
//! - Sequence: for every frame `t`, for every axis `c` (x, y, z), for every
//!   vertex `v` in index order, the residual `q[t][v][c] − pred`, where `q`
//!   is the quantised position (`round((p − origin) / step)`) and, with the
//!   vertex's *parent* `u` = the smallest index sharing a triangle with `v`
//!   when that is smaller than `v` (else none):
//!   - `t = 0`: `pred = q[0][u][c]` (0 without a parent);
//!   - temporal, `t > 0`: `pred = q[t−1][v][c]`;
//!   - spatio-temporal, `t > 0`: `pred = q[t−1][v][c] + q[t][u][c] − q[t−1][u][c]`
//!     (temporal without a parent): the vertex moves like its neighbour.
//!
//! A decoded position is `origin + step · q` (f32). The encoder verifies the
//! bound after encoding (in f32, as the GPU evaluates it) and shrinks the
//! step until it holds.

use crate::util::numfmt::Short;
use flate2::Compression;
use flate2::read::DeflateDecoder;
use flate2::write::DeflateEncoder;
use rayon::prelude::*;
use std::io::{Read, Write};

/// The file's first eight bytes.
pub const MAGIC: &[u8; 8] = b"SM4DGEO\0";
/// The layout version this code writes and reads.
pub const VERSION: u32 = 1;
/// Bytes of the fixed header (before the per-sequence table).
pub const HEADER_BYTES: usize = 64;
/// The most quantisation levels per axis (positions fit a `u16`).
pub(crate) const MAX_LEVELS: u32 = 65_536;

/// How a frame is predicted from what is already decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Predictor {
    /// The same vertex in the previous frame.
    Temporal,
    /// The previous frame plus the parent vertex's motion in this frame.
    SpatioTemporal,
}

impl Predictor {
    fn code(self) -> u32 {
        match self {
            Predictor::Temporal => 0,
            Predictor::SpatioTemporal => 1,
        }
    }
    fn from_code(c: u32) -> Option<Predictor> {
        match c {
            0 => Some(Predictor::Temporal),
            1 => Some(Predictor::SpatioTemporal),
            _ => None,
        }
    }
}

/// Options of [`encode`].
#[derive(Debug, Clone, Copy)]
pub struct EncodeOptions {
    /// Largest allowed distance between an input and a decoded vertex, in
    /// metres. Default: 0.001 (1 mm).
    pub max_error: f64,
    /// The predictor. Default: [`Predictor::SpatioTemporal`] (the smaller
    /// output on samba, crane and synthetic databases; see the README).
    pub predictor: Predictor,
    /// DEFLATE level 0-9 (flate2 on its zlib-rs backend). Default:
    /// [`DEFAULT_LEVEL`].
    pub level: u32,
}

/// The default DEFLATE level, 5: the 1,050-frame `samba6` export with its
/// precomputed transition windows takes 4.4 s on two idle cores at level 5
/// (5.4 s at 6, 4.2 s at 4, 4.1 s at 3) for a file 1.8 % larger than at
/// level 6 (2.3 % at 4, 4.2 % at 3); past level 5 zlib's match search
/// (`longest_match`, 29 % of the export at level 6) buys under 2 %.
/// Measured 2026-11-24, see the README's web section.
pub const DEFAULT_LEVEL: u32 = 5;

impl Default for EncodeOptions {
    fn default() -> Self {
        EncodeOptions {
            max_error: 0.001,
            predictor: Predictor::SpatioTemporal,
            level: DEFAULT_LEVEL,
        }
    }
}

impl EncodeOptions {
    /// Checked options: `max_error` finite and positive (metres), `level`
    /// a DEFLATE level 0-9.
    pub fn new(
        max_error: f64,
        predictor: Predictor,
        level: u32,
    ) -> Result<EncodeOptions, CodecError> {
        if !(max_error.is_finite() && max_error > 0.0) {
            return Err(CodecError::Input(format!(
                "`EncodeOptions::max_error` must be positive, got {} m",
                Short(max_error)
            )));
        }
        if level > 9 {
            return Err(CodecError::Input(format!(
                "`EncodeOptions::level` {level}: expected a DEFLATE level 0-9"
            )));
        }
        Ok(EncodeOptions {
            max_error,
            predictor,
            level,
        })
    }
}

/// Geometry to encode: one topology, sequences of frame-major positions
/// (metres, Y-up; `frames × vertices` entries each).
#[derive(Debug, Clone)]
pub struct Geometry {
    /// Vertices per frame.
    pub vertices: usize,
    /// Triangles (indices below `vertices`).
    pub triangles: Vec<[u32; 3]>,
    /// Sequences, each frame-major positions.
    pub sequences: Vec<Vec<[f32; 3]>>,
}

/// Errors of the codec.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CodecError {
    /// The input cannot be encoded.
    #[error("cannot encode: {0}")]
    Input(String),
    /// The data is not a valid `.sm4d` file; says where.
    #[error("corrupt 4D geometry at byte {offset}: {msg}")]
    Corrupt {
        /// Byte offset (in the file) of the field or block at fault.
        offset: usize,
        /// What is wrong.
        msg: String,
    },
    /// A valid file whose geometry does not fit the memory budget.
    #[error(transparent)]
    OverBudget(#[from] crate::util::budget::OverBudget),
}

/// What [`encode`] measured.
#[derive(Debug, Clone, serde::Serialize)]
pub struct EncodeReport {
    /// Bytes of the file.
    pub bytes: usize,
    /// Frames over all sequences.
    pub frames: usize,
    /// The quantisation step finally used (metres).
    pub step: f64,
    /// The largest vertex error after decoding (metres).
    pub max_error: f64,
    /// Steps tried before the bound held.
    pub attempts: usize,
    /// The predictor used.
    pub predictor: Predictor,
}

/// Decoded geometry: quantised positions (what the page uploads) and the
/// grid that maps them to metres.
#[derive(Debug, Clone)]
pub struct Decoded {
    /// The predictor the file used.
    pub predictor: Predictor,
    /// Vertices per frame.
    pub vertices: usize,
    /// Triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Metres per unit.
    pub step: f32,
    /// Grid origin (metres).
    pub origin: [f32; 3],
    /// The error the encoder measured (metres).
    pub max_error: f32,
    /// Per sequence, frame-major quantised positions.
    pub sequences: Vec<Vec<[u16; 3]>>,
}

impl Decoded {
    /// Position in metres of a quantised vertex (f32, as the shader does).
    pub fn position(&self, q: [u16; 3]) -> [f32; 3] {
        std::array::from_fn(|c| self.origin[c] + self.step * q[c] as f32)
    }
}

/// The parent of every vertex: the smallest index sharing a triangle with
/// it when that is smaller than the vertex itself (see the module docs).
pub fn parents(vertices: usize, triangles: &[[u32; 3]]) -> Vec<u32> {
    let mut p: Vec<u32> = (0..vertices as u32).collect();
    for t in triangles {
        for &a in t {
            for &b in t {
                let (a, b) = (a as usize, b);
                if a < vertices && b < p[a] {
                    p[a] = b;
                }
            }
        }
    }
    p
}

fn zigzag(x: i32) -> u32 {
    ((x << 1) ^ (x >> 31)) as u32
}
fn unzigzag(z: u32) -> i32 {
    ((z >> 1) as i32) ^ -((z & 1) as i32)
}
fn put_varint(out: &mut Vec<u8>, mut z: u32) {
    while z >= 0x80 {
        out.push((z as u8) | 0x80);
        z >>= 7;
    }
    out.push(z as u8);
}

fn deflate(raw: &[u8], level: u32) -> Vec<u8> {
    let mut e = DeflateEncoder::new(Vec::new(), Compression::new(level.min(9)));
    // Writing into a Vec cannot fail.
    let _ = e.write_all(raw);
    e.finish().unwrap_or_default()
}

/// The residual stream of one sequence (before DEFLATE).
fn residuals(q: &[[u16; 3]], n: usize, parent: &[u32], predictor: Predictor) -> Vec<u8> {
    let frames = q.len() / n.max(1);
    let mut out = Vec::with_capacity(q.len() * 3 * 2);
    for t in 0..frames {
        let cur = &q[t * n..(t + 1) * n];
        let prev = if t > 0 {
            Some(&q[(t - 1) * n..t * n])
        } else {
            None
        };
        for c in 0..3 {
            for v in 0..n {
                let u = parent[v] as usize;
                let x = cur[v][c] as i32;
                let pred = match prev {
                    None if u != v => cur[u][c] as i32,
                    None => 0,
                    Some(p) => match predictor {
                        Predictor::SpatioTemporal if u != v => {
                            p[v][c] as i32 + cur[u][c] as i32 - p[u][c] as i32
                        }
                        _ => p[v][c] as i32,
                    },
                };
                put_varint(&mut out, zigzag(x - pred));
            }
        }
    }
    out
}

/// Encodes `g` so that no decoded vertex is further than
/// `opts.max_error` from its input: the step starts at `2·max_error/√3`
/// (rounding leaves at most half a step per axis, so at most the bound per
/// vertex in exact arithmetic) and shrinks by 3 % while the measured
/// maximum vertex error (decoded in f32, as the GPU does) exceeds the bound.
/// Cost: one pass of quantisation per attempt, then prediction and DEFLATE
/// once (sequences in parallel).
pub fn encode(g: &Geometry, opts: &EncodeOptions) -> Result<(Vec<u8>, EncodeReport), CodecError> {
    let n = g.vertices;
    check_input(g, opts)?;
    let (lo, hi) = bounds(g)?;
    let origin = lo.map(|x| x as f32);
    let parent = parents(n, &g.triangles);
    let topo = deflate(&topology_stream(&g.triangles), opts.level);
    let mut step = 2.0 * opts.max_error / 3f64.sqrt();
    for attempt in 1..=64 {
        let stepf = step as f32;
        let levels: [u32; 3] =
            std::array::from_fn(|c| (((hi[c] - origin[c] as f64) / step).round() as u32) + 1);
        if levels.iter().any(|&l| l > MAX_LEVELS) {
            return Err(CodecError::Input(format!(
                "the bounds ({} × {} × {} m) need more than {MAX_LEVELS} steps of {} mm per axis: raise the error bound",
                Short(hi[0] - lo[0]),
                Short(hi[1] - lo[1]),
                Short(hi[2] - lo[2]),
                Short(step * 1e3)
            )));
        }
        let quantised = quantise(g, origin, step);
        let worst = quantised.iter().map(|x| x.1).fold(0.0, f64::max);
        if worst <= opts.max_error {
            let blocks: Vec<(usize, Vec<u8>)> = quantised
                .par_iter()
                .map(|(q, _)| {
                    (
                        q.len() / n,
                        deflate(&residuals(q, n, &parent, opts.predictor), opts.level),
                    )
                })
                .collect();
            let header = StreamHeader {
                predictor: opts.predictor,
                vertices: n,
                triangles: g.triangles.len(),
                step: stepf,
                origin,
                levels,
                worst,
            };
            let out = assemble(&header, &topo, &blocks);
            let frames = blocks.iter().map(|b| b.0).sum();
            let bytes = out.len();
            return Ok((
                out,
                EncodeReport {
                    bytes,
                    frames,
                    step,
                    max_error: worst,
                    attempts: attempt,
                    predictor: opts.predictor,
                },
            ));
        }
        step *= 0.97;
    }
    Err(CodecError::Input(format!(
        "the error bound {} m was not met after 64 attempts",
        Short(opts.max_error)
    )))
}

/// Refuses a vertex count that is 0 or too large, an error bound that is
/// not positive and a triangle naming a vertex past the count.
fn check_input(g: &Geometry, opts: &EncodeOptions) -> Result<(), CodecError> {
    let n = g.vertices;
    if n == 0 || n > u32::MAX as usize / 2 {
        return Err(CodecError::Input(format!("{n} vertices")));
    }
    if !(opts.max_error.is_finite() && opts.max_error > 0.0) {
        return Err(CodecError::Input(format!(
            "the error bound must be positive, got {} m",
            Short(opts.max_error)
        )));
    }
    if let Some((i, t)) = g
        .triangles
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&v| v as usize >= n))
    {
        return Err(CodecError::Input(format!(
            "triangle {i} {t:?} names a vertex past {n}"
        )));
    }
    Ok(())
}

/// The bounds (minimum, maximum corner) of every position of every
/// sequence (zero without sequences); refuses a sequence that is empty or
/// not whole frames, and a non-finite position.
fn bounds(g: &Geometry) -> Result<([f64; 3], [f64; 3]), CodecError> {
    let n = g.vertices;
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for (s, seq) in g.sequences.iter().enumerate() {
        if seq.len() % n != 0 || seq.is_empty() {
            return Err(CodecError::Input(format!(
                "sequence {s} holds {} positions, not a whole number of {n}-vertex frames",
                seq.len()
            )));
        }
        for (i, p) in seq.iter().enumerate() {
            for c in 0..3 {
                let x = p[c] as f64;
                if !x.is_finite() {
                    return Err(CodecError::Input(format!(
                        "sequence {s}, frame {}, vertex {}: non-finite position",
                        i / n,
                        i % n
                    )));
                }
                lo[c] = lo[c].min(x);
                hi[c] = hi[c].max(x);
            }
        }
    }
    if g.sequences.is_empty() {
        lo = [0.0; 3];
        hi = [0.0; 3];
    }
    Ok((lo, hi))
}

/// The topology stream (before DEFLATE): the vertex indices as zigzag
/// differences from the previous one.
fn topology_stream(triangles: &[[u32; 3]]) -> Vec<u8> {
    let mut topo = Vec::with_capacity(triangles.len() * 6);
    let mut last = 0i64;
    for t in triangles {
        for &v in t {
            put_varint(&mut topo, zigzag((v as i64 - last) as i32));
            last = v as i64;
        }
    }
    topo
}

/// Every sequence quantised on the grid (`origin`, `step`), with its
/// largest vertex error decoded in f32 (sequences in parallel).
fn quantise(g: &Geometry, origin: [f32; 3], step: f64) -> Vec<(Vec<[u16; 3]>, f64)> {
    let stepf = step as f32;
    g.sequences
        .par_iter()
        .map(|seq| {
            let q: Vec<[u16; 3]> = seq
                .iter()
                .map(|p| {
                    // Round half up by truncation (`round` is a libm
                    // call without SSE4.1: a tenth of an export's time);
                    // negatives saturate to 0, as the clamp did.
                    std::array::from_fn(|c| {
                        let x = (p[c] as f64 - origin[c] as f64) / step + 0.5;
                        (x as u32).min(MAX_LEVELS - 1) as u16
                    })
                })
                .collect();
            let mut worst = 0f64;
            for (p, qq) in seq.iter().zip(&q) {
                let d: f64 = (0..3)
                    .map(|c| {
                        let r = origin[c] + stepf * qq[c] as f32;
                        ((r - p[c]) as f64).powi(2)
                    })
                    .sum::<f64>()
                    .sqrt();
                worst = worst.max(d);
            }
            (q, worst)
        })
        .collect()
}

/// The fixed header's values (see the module's layout).
struct StreamHeader {
    predictor: Predictor,
    vertices: usize,
    triangles: usize,
    step: f32,
    origin: [f32; 3],
    levels: [u32; 3],
    worst: f64,
}

/// The file: the header, the per-sequence table, the topology block, the
/// sequence blocks (`(frames, deflated residuals)`).
fn assemble(h: &StreamHeader, topo: &[u8], blocks: &[(usize, Vec<u8>)]) -> Vec<u8> {
    let mut out = Vec::with_capacity(
        HEADER_BYTES
            + 8 * blocks.len()
            + topo.len()
            + blocks.iter().map(|b| b.1.len()).sum::<usize>(),
    );
    out.extend_from_slice(MAGIC);
    for x in [
        VERSION,
        h.predictor.code(),
        h.vertices as u32,
        h.triangles as u32,
        blocks.len() as u32,
    ] {
        out.extend_from_slice(&x.to_le_bytes());
    }
    out.extend_from_slice(&h.step.to_le_bytes());
    for o in h.origin {
        out.extend_from_slice(&o.to_le_bytes());
    }
    for l in h.levels {
        out.extend_from_slice(&l.to_le_bytes());
    }
    out.extend_from_slice(&(h.worst as f32).to_le_bytes());
    out.extend_from_slice(&(topo.len() as u32).to_le_bytes());
    for (f, b) in blocks {
        out.extend_from_slice(&(*f as u32).to_le_bytes());
        out.extend_from_slice(&(b.len() as u32).to_le_bytes());
    }
    out.extend_from_slice(topo);
    for (_, b) in blocks {
        out.extend_from_slice(b);
    }
    out
}

struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}
impl Reader<'_> {
    fn u32(&mut self) -> Result<u32, CodecError> {
        let s = self
            .b
            .get(self.at..self.at + 4)
            .ok_or(CodecError::Corrupt {
                offset: self.at,
                msg: format!("the file ends in its header ({} bytes)", self.b.len()),
            })?;
        self.at += 4;
        Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }
    fn f32(&mut self) -> Result<f32, CodecError> {
        let at = self.at;
        let x = f32::from_bits(self.u32()?);
        if !x.is_finite() {
            return Err(CodecError::Corrupt {
                offset: at,
                msg: "a non-finite number in the header".into(),
            });
        }
        Ok(x)
    }
}

/// The zigzag varints of one block, inflated as they are read: a block is
/// never held inflated (a 1.9 MB file can declare 2·10⁹ values, 8 GB as
/// `i32`s; issue 46, item 5).
struct Varints<'a> {
    z: std::io::Take<DeflateDecoder<&'a [u8]>>,
    buf: Box<[u8]>,
    pos: usize,
    len: usize,
    /// Byte offset of the block in the file (for errors).
    offset: usize,
    /// Values the block must hold.
    count: usize,
    /// Values read so far.
    read: usize,
}

impl<'a> Varints<'a> {
    /// The block `data` at file offset `offset`, holding `count` values.
    fn new(data: &'a [u8], offset: usize, count: usize) -> Result<Varints<'a>, CodecError> {
        // DEFLATE expands at most 1,032:1: a count no block of this size
        // can hold is corrupt.
        if count > data.len().saturating_mul(1100) {
            return Err(CodecError::Corrupt {
                offset,
                msg: format!(
                    "{count} values cannot come from a block of {} bytes",
                    data.len()
                ),
            });
        }
        Ok(Varints {
            // At most 5 bytes per varint: a bigger stream is corrupt.
            z: DeflateDecoder::new(data).take((count as u64).saturating_mul(5) + 1),
            buf: vec![0u8; 1 << 16].into_boxed_slice(),
            pos: 0,
            len: 0,
            offset,
            count,
            read: 0,
        })
    }

    fn bad(&self, msg: String) -> CodecError {
        CodecError::Corrupt {
            offset: self.offset,
            msg,
        }
    }

    /// The next inflated byte; `None` at the end of the stream.
    fn byte(&mut self) -> Result<Option<u8>, CodecError> {
        if self.pos == self.len {
            self.len = self
                .z
                .read(&mut self.buf)
                .map_err(|e| self.bad(format!("the block does not inflate ({e})")))?;
            self.pos = 0;
            if self.len == 0 {
                return Ok(None);
            }
        }
        self.pos += 1;
        Ok(Some(self.buf[self.pos - 1]))
    }

    /// The next value; an error when the block ends before `count` values.
    fn next(&mut self) -> Result<i32, CodecError> {
        let mut z = 0u32;
        let mut shift = 0;
        loop {
            let Some(b) = self.byte()? else {
                return Err(self.bad(format!(
                    "the block holds {} values, expected {}",
                    self.read, self.count
                )));
            };
            if shift > 28 {
                return Err(self.bad("a varint longer than 5 bytes".into()));
            }
            z |= ((b & 0x7f) as u32) << shift;
            if b & 0x80 == 0 {
                self.read += 1;
                return Ok(unzigzag(z));
            }
            shift += 7;
        }
    }

    /// Checks that nothing follows the `count` values read.
    fn finish(mut self) -> Result<(), CodecError> {
        if self.byte()?.is_some() {
            return Err(self.bad(format!(
                "the block holds more than the {} values expected",
                self.count
            )));
        }
        Ok(())
    }
}

/// What [`read_header`] found before the sequence blocks.
struct Parsed {
    predictor: Predictor,
    vertices: usize,
    triangles: Vec<[u32; 3]>,
    step: f32,
    origin: [f32; 3],
    levels: [u32; 3],
    max_error: f32,
    /// Per sequence: frames, bytes of its block.
    table: Vec<(usize, usize)>,
    /// Offset of the first sequence block.
    at: usize,
}

/// The header, the table and the topology of a `.sm4d` file, checked: the
/// triangle count against the topology block's size and against the
/// memory budget before the triangles are allocated.
fn read_header(b: &[u8]) -> Result<Parsed, CodecError> {
    if b.len() < 8 || &b[..8] != MAGIC {
        return Err(CodecError::Corrupt {
            offset: 0,
            msg: "not a surfmotion 4D geometry file (bad magic)".into(),
        });
    }
    let mut r = Reader { b, at: 8 };
    let version = r.u32()?;
    if version != VERSION {
        return Err(CodecError::Corrupt {
            offset: 8,
            msg: format!("version {version}, this reader knows {VERSION}"),
        });
    }
    let pc = r.u32()?;
    let predictor = Predictor::from_code(pc).ok_or(CodecError::Corrupt {
        offset: 12,
        msg: format!("unknown predictor {pc}"),
    })?;
    let n = r.u32()? as usize;
    let nt = r.u32()? as usize;
    let ns = r.u32()? as usize;
    let step = r.f32()?;
    let origin = [r.f32()?, r.f32()?, r.f32()?];
    let levels = [r.u32()?, r.u32()?, r.u32()?];
    let max_error = r.f32()?;
    let topo_bytes = r.u32()? as usize;
    if n == 0
        || n > (1 << 26).min(b.len().saturating_mul(1100))
        || levels.iter().any(|&l| l > MAX_LEVELS)
        || step <= 0.0
    {
        return Err(CodecError::Corrupt {
            offset: 16,
            msg: format!("{n} vertices, step {step}, levels {levels:?}"),
        });
    }
    if ns > (b.len() - HEADER_BYTES.min(b.len())) / 8 {
        return Err(CodecError::Corrupt {
            offset: 24,
            msg: format!("{ns} sequences do not fit the file"),
        });
    }
    let mut table = Vec::with_capacity(ns);
    for _ in 0..ns {
        table.push((r.u32()? as usize, r.u32()? as usize));
    }
    let at = r.at;
    let topo = block(b, at, topo_bytes)?;
    let mut idx = Varints::new(topo, at, nt.saturating_mul(3))?;
    // Triangles (12 bytes), the parents (4 per vertex) and two frames of
    // quantised positions (12 per vertex).
    crate::util::budget::check(
        || {
            format!(
                "reading {} triangles and {} vertices of 4D geometry",
                crate::util::budget::thousands(nt as u128),
                crate::util::budget::thousands(n as u128)
            )
        },
        nt as u128 * 12 + n as u128 * 16,
    )?;
    let mut triangles = Vec::with_capacity(nt);
    let mut last = 0i64;
    for k in 0..nt {
        let mut t = [0u32; 3];
        for c in t.iter_mut() {
            last += idx.next()? as i64;
            if last < 0 || last as usize >= n {
                return Err(CodecError::Corrupt {
                    offset: at,
                    msg: format!("triangle {k} names vertex {last} of {n}"),
                });
            }
            *c = last as u32;
        }
        triangles.push(t);
    }
    idx.finish()?;
    Ok(Parsed {
        predictor,
        vertices: n,
        triangles,
        step,
        origin,
        levels,
        max_error,
        table,
        at: at + topo_bytes,
    })
}

/// The `len` bytes at `at`, or an error naming the truncation.
fn block(b: &[u8], at: usize, len: usize) -> Result<&[u8], CodecError> {
    b.get(at..at.saturating_add(len))
        .ok_or_else(|| CodecError::Corrupt {
            offset: at,
            msg: format!(
                "a block of {len} bytes runs past the end of the file ({} bytes): truncated?",
                b.len()
            ),
        })
}

/// Decodes every frame of `p`'s sequences from `b` in order, holding two
/// frames at a time, and hands each to `frame(sequence, t, positions)`.
fn walk(
    b: &[u8],
    p: &Parsed,
    mut frame: impl FnMut(usize, usize, &[[u16; 3]]),
) -> Result<(), CodecError> {
    let n = p.vertices;
    let parent = parents(n, &p.triangles);
    let mut prev = vec![[0u16; 3]; n];
    let mut cur = vec![[0u16; 3]; n];
    let mut at = p.at;
    for (s, &(frames, len)) in p.table.iter().enumerate() {
        let count = frames
            .checked_mul(n * 3)
            .filter(|&c| c <= len.saturating_mul(1100))
            .ok_or(CodecError::Corrupt {
                offset: HEADER_BYTES + 8 * s,
                msg: format!("sequence {s}: {frames} frames cannot come from {len} bytes"),
            })?;
        let mut res = Varints::new(block(b, at, len)?, at, count)?;
        for t in 0..frames {
            for c in 0..3 {
                for v in 0..n {
                    let u = parent[v] as usize;
                    let e = res.next()? as i64;
                    let pred = if t == 0 {
                        if u != v { cur[u][c] as i64 } else { 0 }
                    } else {
                        match p.predictor {
                            Predictor::SpatioTemporal if u != v => {
                                prev[v][c] as i64 + cur[u][c] as i64 - prev[u][c] as i64
                            }
                            _ => prev[v][c] as i64,
                        }
                    };
                    let x = pred + e;
                    if x < 0 || x >= p.levels[c] as i64 {
                        return Err(CodecError::Corrupt {
                            offset: at,
                            msg: format!(
                                "sequence {s}, frame {t}, vertex {v}: position {x} outside 0..{}",
                                p.levels[c]
                            ),
                        });
                    }
                    cur[v][c] = x as u16;
                }
            }
            frame(s, t, &cur);
            std::mem::swap(&mut prev, &mut cur);
        }
        res.finish()?;
        at += len;
    }
    if at != b.len() {
        return Err(CodecError::Corrupt {
            offset: at,
            msg: format!("{} bytes after the last block", b.len() - at),
        });
    }
    Ok(())
}

/// What [`verify`] found: the counts of a valid `.sm4d` file.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Verified {
    /// The predictor the file used.
    pub predictor: Predictor,
    /// Vertices per frame.
    pub vertices: usize,
    /// Triangles.
    pub triangles: usize,
    /// Frames of each sequence.
    pub frames: Vec<usize>,
    /// Metres per quantisation unit.
    pub step: f32,
    /// The error the encoder measured (metres).
    pub max_error: f32,
}

/// Checks a whole `.sm4d` file as [`decode`] does (every size, index and
/// position) while holding only two frames: what `inspect` uses, so a file
/// that declares millions of frames is checked, not loaded.
pub(crate) fn verify(b: &[u8]) -> Result<Verified, CodecError> {
    let p = read_header(b)?;
    walk(b, &p, |_, _, _| {})?;
    Ok(Verified {
        predictor: p.predictor,
        vertices: p.vertices,
        triangles: p.triangles.len(),
        frames: p.table.iter().map(|t| t.0).collect(),
        step: p.step,
        max_error: p.max_error,
    })
}

/// Reads a `.sm4d` file; every size, index and value is checked, and the
/// error names the byte offset of the field or block at fault. The
/// positions the file declares (6 bytes per vertex and frame) are checked
/// against the block sizes and the memory budget ([`crate::util::budget`])
/// before they are allocated.
pub fn decode(b: &[u8]) -> Result<Decoded, CodecError> {
    let p = read_header(b)?;
    let n = p.vertices;
    let mut total = 0u128;
    for (s, &(frames, len)) in p.table.iter().enumerate() {
        // A block cannot be longer than the file: checked before the
        // budget, so that a corrupt length is named as such.
        if len as u128 > b.len() as u128 {
            return Err(CodecError::Corrupt {
                offset: HEADER_BYTES + 8 * s,
                msg: format!(
                    "sequence {s}: a block of {len} bytes in a file of {} bytes",
                    b.len()
                ),
            });
        }
        if (frames as u128) * (n as u128) * 3 > (len as u128) * 1100 {
            return Err(CodecError::Corrupt {
                offset: HEADER_BYTES + 8 * s,
                msg: format!("sequence {s}: {frames} frames cannot come from {len} bytes"),
            });
        }
        total += frames as u128 * n as u128;
    }
    crate::util::budget::check(
        || {
            format!(
                "decoding {} frames of {} vertices",
                crate::util::budget::thousands(p.table.iter().map(|t| t.0 as u128).sum()),
                crate::util::budget::thousands(n as u128)
            )
        },
        total * 6,
    )?;
    let mut sequences: Vec<Vec<[u16; 3]>> = p
        .table
        .iter()
        .map(|&(frames, _)| Vec::with_capacity(frames * n))
        .collect();
    walk(b, &p, |s, _, q| sequences[s].extend_from_slice(q))?;
    Ok(Decoded {
        predictor: p.predictor,
        vertices: n,
        triangles: p.triangles,
        step: p.step,
        origin: p.origin,
        max_error: p.max_error,
        sequences,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small moving grid: two sequences, the second moving faster.
    fn grid() -> Geometry {
        let w = 6;
        let n = w * w;
        let mut triangles = Vec::new();
        for i in 0..w - 1 {
            for j in 0..w - 1 {
                let a = (i * w + j) as u32;
                triangles.push([a, a + 1, a + w as u32]);
                triangles.push([a + 1, a + w as u32 + 1, a + w as u32]);
            }
        }
        let seq = |speed: f32, frames: usize| {
            let mut p = Vec::new();
            for t in 0..frames {
                for v in 0..n {
                    let (x, y) = ((v % w) as f32 * 0.1, (v / w) as f32 * 0.1);
                    let s = (t as f32 * speed + x).sin() * 0.05;
                    p.push([x + t as f32 * 0.01, y + s, s * x]);
                }
            }
            p
        };
        Geometry {
            vertices: n,
            triangles,
            sequences: vec![seq(0.2, 7), seq(0.5, 4)],
        }
    }

    fn max_err(g: &Geometry, d: &Decoded) -> f64 {
        let mut worst = 0f64;
        for (a, b) in g.sequences.iter().zip(&d.sequences) {
            for (p, q) in a.iter().zip(b) {
                let r = d.position(*q);
                let e: f64 = (0..3).map(|c| ((r[c] - p[c]) as f64).powi(2)).sum();
                worst = worst.max(e.sqrt());
            }
        }
        worst
    }

    #[test]
    fn round_trip_meets_the_bound_for_both_predictors() {
        let g = grid();
        for predictor in [Predictor::Temporal, Predictor::SpatioTemporal] {
            for bound in [1e-3, 1e-4] {
                let opts = EncodeOptions {
                    max_error: bound,
                    predictor,
                    level: 6,
                };
                let (bytes, rep) = encode(&g, &opts).unwrap();
                let d = decode(&bytes).unwrap();
                assert_eq!(d.triangles, g.triangles);
                assert_eq!(d.predictor, predictor);
                let e = max_err(&g, &d);
                assert!(e <= bound, "{predictor:?} {bound}: {e}");
                assert!((e - rep.max_error).abs() < 1e-7);
                assert_eq!(rep.frames, 11);
            }
        }
    }

    #[test]
    fn every_truncation_is_an_error_not_a_panic() {
        let (bytes, _) = encode(&grid(), &EncodeOptions::default()).unwrap();
        for len in 0..bytes.len() {
            assert!(decode(&bytes[..len]).is_err(), "truncated to {len}");
        }
        let mut flipped = bytes.clone();
        for i in 0..flipped.len() {
            flipped[i] ^= 0x5a;
            let _ = decode(&flipped);
            flipped[i] ^= 0x5a;
        }
        let mut bad = bytes.clone();
        bad[8] = 9;
        assert!(matches!(
            decode(&bad),
            Err(CodecError::Corrupt { offset: 8, .. })
        ));
    }

    #[test]
    fn a_header_claiming_huge_counts_is_an_error_not_an_allocation() {
        let (mut bytes, _) = encode(&grid(), &EncodeOptions::default()).unwrap();
        let mut b = bytes.clone();
        b[20..24].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(decode(&b), Err(CodecError::Corrupt { .. })));
        bytes[16..20].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(
            decode(&bytes),
            Err(CodecError::Corrupt { offset: 16, .. })
        ));
    }

    /// `web export`'s time is mostly DEFLATE: flate2 must run on its zlib
    /// backend (zlib-rs, 2.2x less CPU than miniz_oxide at level 6 on the
    /// 1,050-frame export). `Compress::new_with_window_bits` exists only
    /// with a zlib backend, so this fails to build on miniz_oxide alone.
    #[test]
    fn deflate_runs_on_a_zlib_backend() {
        let c = flate2::Compress::new_with_window_bits(Compression::new(6), false, 15);
        assert_eq!(c.total_in(), 0);
        let raw: Vec<u8> = (0..10_000u32).map(|i| (i % 7) as u8).collect();
        let mut back = Vec::new();
        DeflateDecoder::new(&deflate(&raw, 6)[..])
            .read_to_end(&mut back)
            .unwrap();
        assert_eq!(back, raw);
    }

    #[test]
    fn zigzag_round_trips() {
        for x in [0, 1, -1, 63, -64, 1 << 20, -(1 << 20), i32::MAX, i32::MIN] {
            assert_eq!(unzigzag(zigzag(x)), x);
        }
    }

    #[test]
    fn parents_are_smaller_neighbours() {
        let g = grid();
        let p = parents(g.vertices, &g.triangles);
        assert_eq!(p[0], 0);
        for (v, &u) in p.iter().enumerate().skip(1) {
            assert!((u as usize) < v);
            assert!(
                g.triangles
                    .iter()
                    .any(|t| t.contains(&u) && t.contains(&(v as u32)))
            );
        }
    }
}
