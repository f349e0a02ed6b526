//! Point Cache 2 (`.pc2`), as read by Blender's Mesh Cache modifier, Maya and
//! Houdini: a 32-byte little-endian header (`POINTCACHE2\0`, version 1,
//! point count, start frame, sample rate, sample count) then f32 xyz per
//! point per sample.

use crate::mesh::MeshError;
use std::path::Path;

/// Vertex positions per frame without topology (a PC2 or MDD cache).
#[derive(Debug, Clone, PartialEq)]
pub struct PointCache {
    /// Points per frame.
    pub points: usize,
    /// Positions, frame-major (`frames × points`).
    pub positions: Vec<[f64; 3]>,
    /// First frame number (PC2) or 0.
    pub start: f32,
    /// Frames between samples (PC2 sample rate) or 1.
    pub sample_rate: f32,
    /// Per-frame times in seconds, where the format stores them (MDD).
    pub times: Option<Vec<f32>>,
    /// Non-fatal problems (trailing bytes).
    pub warnings: Vec<String>,
}

impl PointCache {
    /// Number of frames.
    pub fn frame_count(&self) -> usize {
        self.positions.len() / self.points.max(1)
    }
}

const MAGIC: &[u8; 12] = b"POINTCACHE2\0";

/// Decodes packed f32 xyz triples (little or big endian) into f64 points,
/// rejecting non-finite values with their frame and point. Shared by PC2 and MDD.
pub(crate) fn decode_points(
    data: &[u8],
    points: usize,
    big_endian: bool,
    path: &Path,
) -> Result<Vec<[f64; 3]>, MeshError> {
    let f = |c: &[u8]| {
        let b = [c[0], c[1], c[2], c[3]];
        (if big_endian {
            f32::from_be_bytes(b)
        } else {
            f32::from_le_bytes(b)
        }) as f64
    };
    let positions: Vec<[f64; 3]> = data
        .chunks_exact(12)
        .map(|c| [f(&c[0..4]), f(&c[4..8]), f(&c[8..12])])
        .collect();
    if let Some(k) = positions
        .iter()
        .position(|p| !p.iter().all(|v| v.is_finite()))
    {
        return Err(MeshError::invalid(
            path,
            format!(
                "non-finite position at frame {}, point {}",
                k / points.max(1),
                k % points.max(1)
            ),
        ));
    }
    Ok(positions)
}

/// Parses PC2 bytes. Header counts are checked against the data length
/// before anything is allocated.
pub fn parse_pc2(bytes: &[u8], path: &Path) -> Result<PointCache, MeshError> {
    if bytes.len() < 32 {
        return Err(MeshError::invalid(
            path,
            format!("{} bytes: too short for a PC2 header (32)", bytes.len()),
        ));
    }
    if &bytes[..12] != MAGIC {
        return Err(MeshError::invalid(
            path,
            "not a PC2 file (no POINTCACHE2 signature)",
        ));
    }
    let i32_at =
        |o: usize| i32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let f32_at =
        |o: usize| f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let version = i32_at(12);
    let points = i32_at(16);
    let start = f32_at(20);
    let rate = f32_at(24);
    let samples = i32_at(28);
    if version != 1 {
        return Err(MeshError::invalid(
            path,
            format!("PC2 version {version}, expected 1"),
        ));
    }
    if points <= 0 || samples <= 0 {
        // No samples is no sequence: it was read, and written to a GLB
        // of 0 frames (exit 0).
        return Err(MeshError::invalid(
            path,
            format!("header: {points} points, {samples} samples (a point cache needs both)"),
        ));
    }
    let need = (points as u128) * (samples as u128) * 12;
    let have = (bytes.len() - 32) as u128;
    if need > have {
        return Err(MeshError::invalid(
            path,
            format!(
                "truncated: header claims {samples} frames × {points} points ({need} bytes), file has {have}"
            ),
        ));
    }
    let mut warnings = Vec::new();
    if have > need {
        crate::util::fsutil::raise_warning(
            &mut warnings,
            path,
            format!("{} bytes after the last frame ignored", have - need),
        );
    }
    let positions = decode_points(&bytes[32..32 + need as usize], points as usize, false, path)?;
    Ok(PointCache {
        points: points as usize,
        positions,
        start: if start.is_finite() { start } else { 0.0 },
        sample_rate: if rate.is_finite() && rate > 0.0 {
            rate
        } else {
            1.0
        },
        times: None,
        warnings,
    })
}

/// Reads a PC2 file.
pub fn read_pc2(path: &Path) -> Result<PointCache, MeshError> {
    parse_pc2(&crate::util::fsutil::read_bytes(path)?, path)
}

/// The 32-byte PC2 header of `frames` frames of `points` points (start
/// frame 0, sample rate 1); the frames follow it.
pub fn header(points: i32, frames: i32) -> [u8; 32] {
    let mut h = [0u8; 32];
    h[..12].copy_from_slice(MAGIC);
    h[12..16].copy_from_slice(&1i32.to_le_bytes());
    h[16..20].copy_from_slice(&points.to_le_bytes());
    h[20..24].copy_from_slice(&0f32.to_le_bytes());
    h[24..28].copy_from_slice(&1f32.to_le_bytes());
    h[28..32].copy_from_slice(&frames.to_le_bytes());
    h
}

/// Appends points as packed f32 xyz triples (little or big endian): a
/// PC2 or MDD frame. The one encoder of frames, for the whole-file writers
/// and the streamed one ([`super::stream::SequenceWriter`]).
pub(crate) fn encode_points(out: &mut Vec<u8>, points: &[[f64; 3]], big_endian: bool) {
    out.reserve(points.len() * 12);
    for p in points {
        for &v in p {
            let v = v as f32;
            out.extend_from_slice(&if big_endian {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            });
        }
    }
}

/// Encodes positions (`frames × points`, frame-major) as PC2, in memory
/// (for small caches; [`write_pc2`] writes a file frame by frame).
pub fn encode_pc2(points: usize, positions: &[[f64; 3]]) -> Vec<u8> {
    let frames = positions.len() / points.max(1);
    let mut out = Vec::with_capacity(32 + positions.len() * 12);
    out.extend_from_slice(&header(points as i32, frames as i32));
    encode_points(&mut out, positions, false);
    out
}

/// Writes a PC2 file atomically, a frame at a time (the file's bytes are
/// never held whole: they were, a second copy of every position, 12 bytes
/// per vertex and frame). The bytes are those of [`encode_pc2`].
pub fn write_pc2(points: usize, positions: &[[f64; 3]], path: &Path) -> Result<(), MeshError> {
    let frames = positions.len() / points.max(1);
    let mut file = crate::util::fsutil::AtomicFile::create(path)?;
    file.write_all(&header(points as i32, frames as i32))?;
    let mut bytes = Vec::with_capacity(points.max(1) * 12);
    for frame in positions.chunks(points.max(1)) {
        bytes.clear();
        encode_points(&mut bytes, frame, false);
        file.write_all(&bytes)?;
    }
    file.commit()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The file written frame by frame is the in-memory encoding, byte
    /// for byte, and reads back as the positions (to f32).
    #[test]
    fn the_streamed_file_is_the_encoding() {
        let dir = tempfile::tempdir().unwrap();
        let positions: Vec<[f64; 3]> = (0..7 * 5)
            .map(|i| [i as f64 * 0.25, -(i as f64) / 3.0, 1e3 + i as f64])
            .collect();
        let p = dir.path().join("a.pc2");
        write_pc2(5, &positions, &p).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        assert_eq!(bytes, encode_pc2(5, &positions));
        let back = parse_pc2(&bytes, &p).unwrap();
        assert_eq!(back.frame_count(), 7);
        for (a, b) in back.positions.iter().zip(&positions) {
            for k in 0..3 {
                assert_eq!(a[k], b[k] as f32 as f64);
            }
        }
    }
}
