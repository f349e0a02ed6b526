//! Checks made before the `gltf` crate's document is trusted: the GLB
//! layout, enum values and attribute indices of the JSON.

use crate::mesh::MeshError;
use std::path::Path;

/// Rejects enum-valued fields the `gltf` crate would unwrap (and panic on)
/// when they hold an unknown value: its validation lets some through (an
/// animation target `path` of `"weigh9s"` panics in `Target::property`).
pub(super) fn check_enums(root: &gltf::json::Root, path: &Path) -> Result<(), MeshError> {
    use gltf::json::validation::Checked;
    let bad = |what: String| Err(MeshError::invalid(path, format!("glTF: invalid {what}")));
    for (i, a) in root.accessors.iter().enumerate() {
        if matches!(a.component_type, Checked::Invalid) || matches!(a.type_, Checked::Invalid) {
            return bad(format!("componentType or type of accessor {i}"));
        }
        if let Some(sp) = &a.sparse
            && matches!(sp.indices.component_type, Checked::Invalid)
        {
            return bad(format!("sparse index type of accessor {i}"));
        }
    }
    for (i, a) in root.animations.iter().enumerate() {
        if a.channels
            .iter()
            .any(|c| matches!(c.target.path, Checked::Invalid))
        {
            return bad(format!("channel target path in animation {i}"));
        }
        if a.samplers
            .iter()
            .any(|s| matches!(s.interpolation, Checked::Invalid))
        {
            return bad(format!("sampler interpolation in animation {i}"));
        }
    }
    for (i, m) in root.meshes.iter().enumerate() {
        for p in &m.primitives {
            if matches!(p.mode, Checked::Invalid)
                || p.attributes.keys().any(|k| matches!(k, Checked::Invalid))
            {
                return bad(format!("primitive mode or attribute name in mesh {i}"));
            }
        }
    }
    Ok(())
}

/// Rejects mesh attributes naming an accessor that does not exist: the
/// `gltf` crate's validation indexes the POSITION accessor unchecked (a
/// panic; found by `tests/it/hostile/malformed.rs` on a bit-flipped GLB).
pub(super) fn check_attribute_indices(
    root: &gltf::json::Root,
    path: &Path,
) -> Result<(), MeshError> {
    let n = root.accessors.len();
    for (i, m) in root.meshes.iter().enumerate() {
        for p in &m.primitives {
            let targets = p.targets.iter().flatten();
            let named = p.attributes.values().copied().chain(
                targets.flat_map(|t| [t.positions, t.normals, t.tangents].into_iter().flatten()),
            );
            for a in named.chain(p.indices) {
                if a.value() >= n {
                    return Err(MeshError::invalid(
                        path,
                        format!(
                            "glTF: mesh {i} names accessor {}, the file has {n}",
                            a.value()
                        ),
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Checks a GLB container's header and chunk lengths before the `gltf` crate
/// sees them: its parser subtracts the header size from the declared length
/// unchecked (a declared length under 12 overflows; found by cargo-fuzz).
/// Returns the bytes the header declares. Non-GLB input passes through.
pub(super) fn check_glb_layout<'a>(bytes: &'a [u8], path: &Path) -> Result<&'a [u8], MeshError> {
    if !bytes.starts_with(b"glTF") {
        return Ok(bytes);
    }
    let bad = |msg: String| Err(MeshError::invalid(path, format!("GLB: {msg}")));
    if bytes.len() < 20 {
        return bad(format!(
            "{} bytes: too short for a header and a chunk",
            bytes.len()
        ));
    }
    let u32_at = |o: usize| {
        u32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]) as usize
    };
    let (version, total) = (u32_at(4), u32_at(8));
    if version != 2 {
        return bad(format!("version {version}, expected 2"));
    }
    if total < 20 || total > bytes.len() {
        return bad(format!(
            "header declares {total} bytes, the file has {}",
            bytes.len()
        ));
    }
    let mut off = 12;
    let mut first = true;
    while off + 8 <= total {
        let (len, kind) = (u32_at(off), &bytes[off + 4..off + 8]);
        if first && kind != b"JSON" {
            return bad("the first chunk is not JSON".into());
        }
        first = false;
        match (off + 8).checked_add(len) {
            Some(end) if end <= total => off = end,
            _ => {
                return bad(format!(
                    "chunk at byte {off} declares {len} bytes, past the end ({total})"
                ));
            }
        }
    }
    Ok(&bytes[..total])
}
