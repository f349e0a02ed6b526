//! The text summaries of the jobs whose report prints in a few lines
//! (their `--json` is the report itself): `blend`, `render`, `graph`,
//! `mocap convert` and `procedural`, `live send`, the landmark page
//! ([`super::pick`]). The longer summaries are in [`super::text`].

use super::blend::BlendReport;
use super::mocap::{Converted, ProceduralClip};
use super::pick::PickReport;
use super::render::RenderReport;
use crate::batch::summary::count;
use crate::graph::SurfaceMotionGraph;
use crate::live::send::SendReport;
use std::fmt::Write as _;

/// `blend`'s report: the mesh written and its distortions against the
/// linear blend's (Huang et al. 2015, Sec. 4.2's non-linear blend).
pub fn blend(r: &BlendReport) -> String {
    format!(
        "wrote {} ({} blend, α = {}, {:.1} ms)\n  edge-length distortion {:.4} (linear: {:.4})\n  volume distortion      {:.4} (linear: {:.4})\n  (relative to the mean of the inputs' edge lengths and volumes)\n",
        r.output.display(),
        r.method,
        r.alpha,
        r.seconds * 1e3,
        r.edge_length_distortion,
        r.linear_edge_length_distortion,
        r.volume_distortion,
        r.linear_volume_distortion
    )
}

/// `render`'s report: the picture written.
pub fn render(r: &RenderReport) -> String {
    format!(
        "wrote {} ({}x{}: front and left side of each, one scale)\n",
        r.output.display(),
        r.width,
        r.height
    )
}

/// The landmark page's report once stopped: requests, embeddings and the
/// files saved.
pub fn pick(r: &PickReport) -> String {
    let mut s = format!(
        "pick: stopped after {} and {}\n",
        count(r.requests, "request"),
        count(r.embeds, "embedding")
    );
    if r.saved.is_empty() {
        s += "  nothing saved\n";
    }
    for p in &r.saved {
        let _ = writeln!(s, "  saved {}", p.display());
    }
    if let Some(m) = &r.manifest {
        let _ = writeln!(s, "  {} now names the last one", m.display());
    }
    s
}

/// A Surface Motion Graph's sequences and sequence edges (Huang et al.
/// 2015, Sec. 4.3), one line each.
pub fn graph(g: &SurfaceMotionGraph) -> String {
    let mut out = String::new();
    for s in g.sequences() {
        let _ = writeln!(out, "{} ({})", s.name, count(s.len, "frame"));
    }
    for e in g.edges() {
        let _ = writeln!(
            out,
            "{} -> {}: {}, best cost {:.4}",
            g.sequences()[e.from].name,
            g.sequences()[e.to].name,
            count(e.transitions.len(), "transition"),
            e.cost
        );
    }
    out
}

/// A Surface Motion Graph and its frame adjacency (compressed rows) as
/// one JSON value: `{"graph", "adjacency": {"offsets", "targets", "costs"}}`.
pub fn graph_json(g: &SurfaceMotionGraph) -> Result<serde_json::Value, serde_json::Error> {
    let adj = g.adjacency();
    let mut a = serde_json::Map::new();
    a.insert("offsets".into(), serde_json::to_value(adj.offsets)?);
    a.insert("targets".into(), serde_json::to_value(adj.targets)?);
    a.insert("costs".into(), serde_json::to_value(adj.costs)?);
    let mut v = serde_json::Map::new();
    v.insert("graph".into(), serde_json::to_value(g)?);
    v.insert("adjacency".into(), a.into());
    Ok(v.into())
}

/// A clip converted to BVH.
pub fn mocap_converted(r: &Converted) -> String {
    format!(
        "wrote {} ({}, {} at {:.3} fps)",
        r.output.display(),
        count(r.joints, "joint"),
        count(r.frames, "frame"),
        r.fps
    )
}

/// One procedural clip written.
pub fn procedural_clip(c: &ProceduralClip) -> String {
    format!(
        "wrote {} ({} at {} fps)",
        c.path.display(),
        count(c.frames, "frame"),
        c.fps
    )
}

/// A clip sent to a live session, to `to` over `protocol`.
pub fn sent(r: &SendReport, to: &dyn std::fmt::Display, protocol: &str) -> String {
    format!(
        "sent {} frames at {:.1} fps to {to} ({protocol}) in {:.2} s",
        r.frames, r.fps, r.seconds
    )
}
