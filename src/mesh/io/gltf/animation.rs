//! Animations: the morph-weights animation (sparse per-key weights) and
//! node transform channels (translation, rotation, scale), and their sampling.

use super::asset::{KeyWeights, NodeAnimation, NodeChannel, TrsPath};
use super::buffers::Ctx;
use crate::mesh::MeshError;
use gltf::accessor::Dimensions;

/// The animations of an asset (see [`GltfAsset`]).
pub(super) struct Animations {
    pub(super) names: Vec<(String, f32)>,
    pub(super) nodes: Vec<NodeAnimation>,
    pub(super) weights: Option<(Vec<f32>, Vec<KeyWeights>)>,
}

/// Step 6 of [`parse_gltf`](super::parse_gltf): every animation's name and duration, its node
/// (TRS) channels, and the first morph-weights channel that drives
/// `morph_node` (with `nt` targets).
pub(super) fn read_animations(
    ctx: &Ctx,
    doc: &gltf::Document,
    morph_node: Option<usize>,
    nt: usize,
) -> Result<Animations, MeshError> {
    let mut names = Vec::new();
    let mut nodes = Vec::new();
    let mut weights = None;
    for a in doc.animations() {
        let mut dur = 0.0f32;
        for ch in a.channels() {
            let input = ch.sampler().input();
            let (t, _) = ctx.read_f32(&input, "animation input")?;
            dur = t.iter().copied().fold(dur, f32::max);
            if weights.is_none()
                && ch.target().property() == gltf::animation::Property::MorphTargetWeights
                && Some(ch.target().node().index()) == morph_node
                && nt > 0
            {
                weights = Some(read_weights_channel(ctx, &ch, t, nt)?);
            }
        }
        names.push((a.name().unwrap_or("").to_string(), dur));
        let mut channels = Vec::new();
        for ch in a.channels() {
            if let Some(c) = read_trs_channel(ctx, &a, &ch)? {
                channels.push(c);
            }
        }
        nodes.push(NodeAnimation {
            name: a.name().unwrap_or("").to_string(),
            duration: dur,
            channels,
        });
    }
    Ok(Animations {
        names,
        nodes,
        weights,
    })
}

/// A morph-weights channel with key times `t` as sparse keys: the non-zero
/// weights of each key (the value part of a cubic-spline key).
fn read_weights_channel(
    ctx: &Ctx,
    ch: &gltf::animation::Channel,
    t: Vec<f32>,
    nt: usize,
) -> Result<(Vec<f32>, Vec<KeyWeights>), MeshError> {
    let out = ch.sampler().output();
    let per_key = match ch.sampler().interpolation() {
        gltf::animation::Interpolation::CubicSpline => 3 * nt,
        _ => nt,
    };
    if out.dimensions() != Dimensions::Scalar || Some(out.count()) != t.len().checked_mul(per_key) {
        return Err(ctx.err("morph weights animation output has the wrong size"));
    }
    // Element i is weight i % per_key (of which the value part
    // of a cubic key, off..off + nt) at key i / per_key.
    let off = if per_key == 3 * nt { nt } else { 0 };
    let mut keys = vec![Vec::new(); t.len()];
    let mut put = |i: usize, w: f32| {
        let j = i % per_key;
        if w != 0.0 && (off..off + nt).contains(&j) {
            keys[i / per_key].push(((j - off) as u32, w));
        }
    };
    match ctx.read_sparse_zeros(&out, "animation output")? {
        Some((idx, vals)) => idx.into_iter().zip(vals).for_each(|(i, w)| put(i, w)),
        None => {
            let (w, _) = ctx.read_f32(&out, "animation output")?;
            w.into_iter().enumerate().for_each(|(i, w)| put(i, w));
        }
    }
    Ok((t, keys))
}

/// A translation, rotation or scale channel of animation `a` (`None` for a
/// morph-weights channel); cubic-spline keys keep their tangents (glTF 2.0
/// Appendix C: each key's output is in-tangent, value, out-tangent).
fn read_trs_channel(
    ctx: &Ctx,
    a: &gltf::Animation,
    ch: &gltf::animation::Channel,
) -> Result<Option<NodeChannel>, MeshError> {
    use gltf::animation::Property as P;
    let path = match ch.target().property() {
        P::Translation => TrsPath::Translation,
        P::Rotation => TrsPath::Rotation,
        P::Scale => TrsPath::Scale,
        P::MorphTargetWeights => return Ok(None),
    };
    let (times, _) = ctx.read_f32(&ch.sampler().input(), "animation input")?;
    let (vals, comps) = ctx.read_f32(&ch.sampler().output(), "animation output")?;
    let want = if path == TrsPath::Rotation { 4 } else { 3 };
    let cubic = ch.sampler().interpolation() == gltf::animation::Interpolation::CubicSpline;
    let per_key = if cubic { 3 } else { 1 };
    if comps != want || vals.len() != times.len() * per_key * comps {
        return Err(ctx.err(format!(
            "animation '{}': a channel's output has the wrong size",
            a.name().unwrap_or("")
        )));
    }
    if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| w[1] < w[0]) {
        return Err(ctx.err(format!(
            "animation '{}': key times are not ascending",
            a.name().unwrap_or("")
        )));
    }
    let at = |k: usize, part: usize| {
        let o = (k * per_key + part) * comps;
        let mut v = [0.0f32; 4];
        v[..comps].copy_from_slice(&vals[o..o + comps]);
        v
    };
    let values = (0..times.len())
        .map(|k| at(k, if cubic { 1 } else { 0 }))
        .collect();
    let tangents: Vec<[[f32; 4]; 2]> = if cubic {
        (0..times.len()).map(|k| [at(k, 0), at(k, 2)]).collect()
    } else {
        Vec::new()
    };
    if tangents.iter().flatten().flatten().any(|x| !x.is_finite()) {
        return Err(ctx.err(format!(
            "animation '{}': a cubic-spline tangent is not a finite number",
            a.name().unwrap_or("")
        )));
    }
    let step = ch.sampler().interpolation() == gltf::animation::Interpolation::Step;
    Ok(Some(NodeChannel {
        node: ch.target().node().index(),
        path,
        times,
        values,
        step,
        tangents,
    }))
}

/// Cubic-spline channel `ch` between keys `k - 1` and `k`, at `s` (0..1)
/// of the interval `td` seconds long: glTF 2.0 Appendix C's cubic Hermite
/// spline, `p(s) = (2s³ − 3s² + 1)·v₀ + td·(s³ − 2s² + s)·b₀ + (−2s³ +
/// 3s²)·v₁ + td·(s³ − s²)·a₁` (`b₀` the first key's out-tangent, `a₁` the
/// second's in-tangent); a rotation is normalised (the first key's where
/// the sum has no length).
fn hermite(ch: &NodeChannel, k: usize, s: f32, td: f32) -> [f32; 4] {
    let (s2, s3) = (s * s, s * s * s);
    let (h00, h10, h01, h11) = (
        2.0 * s3 - 3.0 * s2 + 1.0,
        s3 - 2.0 * s2 + s,
        -2.0 * s3 + 3.0 * s2,
        s3 - s2,
    );
    let (v0, v1) = (ch.values[k - 1], ch.values[k]);
    let (b0, a1) = (ch.tangents[k - 1][1], ch.tangents[k][0]);
    let v: [f32; 4] =
        std::array::from_fn(|i| h00 * v0[i] + td * h10 * b0[i] + h01 * v1[i] + td * h11 * a1[i]);
    if ch.path != TrsPath::Rotation {
        return v;
    }
    let q = glam::Quat::from_array(v);
    if q.length() > 1e-12 {
        q.normalize().to_array()
    } else {
        glam::Quat::from_array(v0).normalize().to_array()
    }
}

/// Samples one channel at time `t`.
pub(super) fn sample(ch: &NodeChannel, t: f32) -> [f32; 4] {
    let n = ch.times.len();
    if n == 0 {
        return [0.0, 0.0, 0.0, 1.0];
    }
    let k = ch.times.partition_point(|&x| x <= t);
    if k == 0 {
        return ch.values[0];
    }
    if k >= n || ch.step {
        return ch.values[(k - 1).min(n - 1)];
    }
    let (t0, t1) = (ch.times[k - 1], ch.times[k]);
    let a = if t1 > t0 {
        ((t - t0) / (t1 - t0)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (v0, v1) = (ch.values[k - 1], ch.values[k]);
    if !ch.tangents.is_empty() {
        return hermite(ch, k, a, t1 - t0);
    }
    if ch.path == TrsPath::Rotation {
        let q0 = glam::Quat::from_array(v0).normalize();
        let q1 = glam::Quat::from_array(v1).normalize();
        q0.slerp(q1, a).to_array()
    } else {
        std::array::from_fn(|i| v0[i] + (v1[i] - v0[i]) * a)
    }
}
