//! `inspect graph.dot`: the Graphviz file `graph --dot` writes
//! ([`crate::graph::SurfaceMotionGraph::to_dot`]): one node a sequence
//! (`sN [label="NAME\nK frames"]`), one edge a sequence pair labelled with
//! its transitions (`m→n (L=w, cost)`, one a line). Another DOT file is
//! described by its node and edge statements.

use super::error::InspectError;
use super::json::JsonReport;
use crate::batch::summary::count;
use std::path::Path;

/// A node or edge statement of one line: `(ids, label)`; `ids` holds one
/// id for a node, two for an edge.
fn statement(line: &str) -> Option<(Vec<&str>, String)> {
    let line = line.trim().trim_end_matches(';');
    let (head, attrs) = match line.find('[') {
        Some(i) => (line[..i].trim(), &line[i..]),
        None => (line, ""),
    };
    if head.is_empty()
        || head.contains(['{', '}', '='])
        || ["graph", "node", "edge", "digraph", "subgraph"].contains(&head)
    {
        return None;
    }
    let ids: Vec<&str> = head
        .split("->")
        .flat_map(|p| p.split("--"))
        .map(|p| p.trim().trim_matches('"'))
        .collect();
    if ids.iter().any(|i| i.is_empty()) || ids.len() > 2 {
        return None;
    }
    let label = attrs
        .find("label=\"")
        .map(|i| {
            let rest = &attrs[i + 7..];
            let mut out = String::new();
            let mut chars = rest.chars();
            while let Some(c) = chars.next() {
                match c {
                    '"' => break,
                    '\\' => match chars.next() {
                        Some('n') => out.push('\n'),
                        Some(o) => out.push(o),
                        None => break,
                    },
                    c => out.push(c),
                }
            }
            out
        })
        .unwrap_or_default();
    Some((ids, label))
}

/// Describes the DOT file `path`.
pub(crate) fn inspect_dot(path: &Path) -> Result<JsonReport, InspectError> {
    let text = crate::util::fsutil::read_small_text(path)
        .map_err(|e| InspectError::Json(e.to_string()))?;
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .unwrap_or("");
    if !(first.starts_with("digraph") || first.starts_with("graph") || first.starts_with("strict"))
    {
        return Err(InspectError::Json(format!(
            "{}:1: not a Graphviz file (it starts with neither `digraph` nor `graph`)",
            path.display()
        )));
    }
    let ours = first.starts_with("digraph surface_motion_graph");
    let (mut nodes, mut edges) = (Vec::new(), Vec::new());
    for line in text.lines().skip(1) {
        match statement(line) {
            Some((ids, label)) if ids.len() == 1 => nodes.push((ids[0].to_string(), label)),
            Some((ids, label)) => edges.push((ids[0].to_string(), ids[1].to_string(), label)),
            None => {}
        }
    }
    let mut lines = Vec::new();
    if !ours {
        lines.push(format!(
            "a Graphviz graph (not one `surfmotion graph --dot` wrote): {}, {}",
            count(nodes.len(), "node"),
            count(edges.len(), "edge")
        ));
        return Ok(report(path, lines));
    }
    // Node labels are `NAME\nK frames`; edge labels one transition a line.
    let name = |id: &str| {
        nodes
            .iter()
            .find(|(n, _)| n == id)
            .map(|(_, l)| l.lines().next().unwrap_or(id).to_string())
            .unwrap_or_else(|| id.to_string())
    };
    let frames: usize = nodes
        .iter()
        .filter_map(|(_, l)| l.lines().nth(1)?.split(' ').next()?.parse::<usize>().ok())
        .sum();
    let transitions: usize = edges
        .iter()
        .map(|(_, _, l)| l.lines().filter(|t| t.contains('→')).count())
        .sum();
    lines.push(format!(
        "the Surface Motion Graph `surfmotion graph DB --dot` writes (draw it: dot -Tsvg {} -o graph.svg)",
        path.display()
    ));
    lines.push(format!(
        "{} ({} in all): {}",
        count(nodes.len(), "sequence"),
        count(frames, "frame"),
        nodes
            .iter()
            .map(|(_, l)| l.replace('\n', " (") + ")")
            .collect::<Vec<_>>()
            .join(", ")
    ));
    lines.push(format!(
        "{}, {} (transitions within a sequence: {})",
        count(transitions, "transition"),
        count(edges.len(), "sequence edge"),
        edges
            .iter()
            .filter(|(a, b, _)| a == b)
            .map(|(_, _, l)| l.lines().filter(|t| t.contains('→')).count())
            .sum::<usize>()
    ));
    for (a, b, l) in &edges {
        let best = l
            .lines()
            .filter_map(|t| {
                t.rsplit(", ")
                    .next()?
                    .trim_end_matches(')')
                    .parse::<f64>()
                    .ok()
            })
            .min_by(f64::total_cmp);
        lines.push(format!(
            "{} → {}: {}{}",
            name(a),
            name(b),
            count(l.lines().filter(|t| t.contains('→')).count(), "transition"),
            best.map(|c| format!(", best cost {c}")).unwrap_or_default()
        ));
    }
    Ok(report(path, lines))
}

fn report(path: &Path, lines: Vec<String>) -> JsonReport {
    JsonReport {
        path: path.to_path_buf(),
        format: "Graphviz graph".into(),
        lines,
    }
}
