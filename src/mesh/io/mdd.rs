//! MDD point caches (LightWave, Blender, Houdini): big-endian i32 frame
//! count, i32 point count, f32 time per frame, then f32 xyz per point per frame.

use super::pc2::PointCache;
use crate::mesh::MeshError;
use std::path::Path;

/// Parses MDD bytes, checking counts against the data before allocating.
pub fn parse_mdd(bytes: &[u8], path: &Path) -> Result<PointCache, MeshError> {
    if bytes.len() < 8 {
        return Err(MeshError::invalid(
            path,
            "too short for an MDD header (8 bytes)",
        ));
    }
    let be = |o: usize| [bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]];
    let frames = i32::from_be_bytes(be(0));
    let points = i32::from_be_bytes(be(4));
    if frames <= 0 || points <= 0 {
        return Err(MeshError::invalid(
            path,
            format!("header: {frames} frames, {points} points"),
        ));
    }
    let need = 8u128 + frames as u128 * 4 + frames as u128 * points as u128 * 12;
    if need > bytes.len() as u128 {
        return Err(MeshError::invalid(
            path,
            format!(
                "truncated: header claims {frames} frames × {points} points ({need} bytes), file has {}",
                bytes.len()
            ),
        ));
    }
    let mut warnings = Vec::new();
    if (bytes.len() as u128) > need {
        crate::util::fsutil::raise_warning(
            &mut warnings,
            path,
            format!(
                "{} bytes after the last frame ignored",
                bytes.len() as u128 - need
            ),
        );
    }
    let (frames, points) = (frames as usize, points as usize);
    let times: Vec<f32> = bytes[8..8 + 4 * frames]
        .chunks_exact(4)
        .map(|c| f32::from_be_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let data = &bytes[8 + 4 * frames..8 + 4 * frames + 12 * frames * points];
    let positions = super::pc2::decode_points(data, points, true, path)?;
    Ok(PointCache {
        points,
        positions,
        start: 0.0,
        sample_rate: 1.0,
        times: Some(times),
        warnings,
    })
}

/// Reads an MDD file.
pub(crate) fn read_mdd(path: &Path) -> Result<PointCache, MeshError> {
    parse_mdd(&crate::util::fsutil::read_bytes(path)?, path)
}

/// Encodes positions as MDD with frame times `k / fps`.
pub fn encode_mdd(points: usize, positions: &[[f64; 3]], fps: f64) -> Vec<u8> {
    let frames = positions.len() / points.max(1);
    let mut out = Vec::with_capacity(8 + frames * 4 + positions.len() * 12);
    out.extend_from_slice(&(frames as i32).to_be_bytes());
    out.extend_from_slice(&(points as i32).to_be_bytes());
    for k in 0..frames {
        out.extend_from_slice(&((k as f64 / fps) as f32).to_be_bytes());
    }
    for p in positions {
        for v in p {
            out.extend_from_slice(&(*v as f32).to_be_bytes());
        }
    }
    out
}

/// Writes an MDD file atomically.
pub(crate) fn write_mdd(
    points: usize,
    positions: &[[f64; 3]],
    fps: f64,
    path: &Path,
) -> Result<(), MeshError> {
    crate::util::fsutil::write_bytes_atomic(path, &encode_mdd(points, positions, fps))?;
    Ok(())
}
