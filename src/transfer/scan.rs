//! A raw scan made ready for Confluent Motion: repaired (welded, degenerate
//! and duplicate triangles and unreferenced vertices dropped), its markers
//! placed or mapped onto the repaired mesh, and connected components that
//! no marker reaches dropped (nothing would drive them). A scan that still
//! cannot be factored gives a typed error from [`super::Confluent::new`].

use super::markers::{Marker, MarkerError, MarkerFile, MarkerOptions, generate};
use crate::embed::landmarks::{Landmarks, Mark};
use crate::embed::{EmbedError, Embedding};
use crate::mesh::Mesh;
use crate::mesh::components::components;
use crate::mesh::repair::{RepairOptions, RepairReport, repair};
use serde::Serialize;
use std::collections::HashMap;

/// Where the scan's markers come from.
pub enum MarkerSpec<'a> {
    /// Generated from the rig embedded from landmarks.
    Landmarks(&'a Landmarks, MarkerOptions),
    /// Read from a file (triangle ids of the input mesh); the landmarks,
    /// if given, still embed the rig (a mocap source needs the skeleton).
    File(&'a MarkerFile, Option<&'a Landmarks>),
}

/// A scan ready to factor.
pub struct PreparedScan {
    /// The repaired mesh with only marked components.
    pub mesh: Mesh,
    /// Its markers (triangle ids of `mesh`).
    pub markers: Vec<Marker>,
    /// The rig embedded in the repaired mesh, if landmarks were given.
    pub rig: Option<Embedding>,
    /// What was changed.
    pub report: ScanReport,
}

/// What preparing a scan changed.
#[derive(Debug, Clone, Serialize, Default)]
pub struct ScanReport {
    /// The repair.
    pub repair: RepairReport,
    /// Markers whose triangle the repair removed.
    pub lost_markers: usize,
    /// Components dropped for having no marker: (vertices, triangles).
    pub dropped_components: Vec<(usize, usize)>,
}

/// Why a scan cannot be prepared.
#[derive(Debug, thiserror::Error)]
pub enum ScanError {
    /// The rig could not be embedded.
    #[error(transparent)]
    Embed(#[from] EmbedError),
    /// The markers are unusable.
    #[error(transparent)]
    Markers(#[from] MarkerError),
}

/// Repairs `mesh`, places markers and drops unmarked components.
pub fn prepare(mesh: &Mesh, spec: MarkerSpec<'_>) -> Result<PreparedScan, ScanError> {
    let (fixed, rep, vmap) = repair(mesh, &RepairOptions::default());
    let mut report = ScanReport {
        repair: rep,
        ..Default::default()
    };
    let spec_points = match &spec {
        MarkerSpec::Landmarks(lm, _) => Some(resolved_points(mesh, lm)),
        MarkerSpec::File(_, lm) => lm.map(|l| resolved_points(mesh, l)),
    };
    let (markers, rig) = match spec {
        MarkerSpec::Landmarks(lm, opts) => {
            opts.validate(fixed.triangle_count())?;
            let rig = embed_resolved(mesh, &fixed, lm)?;
            (generate(&fixed, &rig, &opts), Some(rig))
        }
        MarkerSpec::File(f, lm) => {
            // Triangle ids are only meaningful on the mesh they were made
            // for: the file records its triangle count (`--save-markers`
            // writes that of the repaired scan).
            let on_fixed = match f.triangle_count {
                Some(c) if c == mesh.triangle_count() => false,
                Some(c) if c == fixed.triangle_count() => true,
                Some(c) => {
                    return Err(MarkerError::OtherMesh {
                        recorded: c,
                        triangles: mesh.triangle_count(),
                    }
                    .into());
                }
                None => false,
            };
            let rig = lm.map(|l| embed_resolved(mesh, &fixed, l)).transpose()?;
            let index: HashMap<[u32; 3], u32> = fixed
                .triangles()
                .iter()
                .enumerate()
                .map(|(i, t)| (sorted(*t), i as u32))
                .collect();
            let mut kept = Vec::with_capacity(f.markers.len());
            for m in &f.markers {
                if on_fixed {
                    match fixed.triangles().get(m.triangle as usize) {
                        Some(_) => kept.push(m.clone()),
                        None => report.lost_markers += 1,
                    }
                    continue;
                }
                let Some(tv) = mesh.triangles().get(m.triangle as usize) else {
                    report.lost_markers += 1;
                    continue;
                };
                let key = sorted(tv.map(|v| vmap[v as usize]));
                match index.get(&key) {
                    Some(&t) if !key.contains(&u32::MAX) => kept.push(Marker {
                        triangle: t,
                        ..m.clone()
                    }),
                    _ => report.lost_markers += 1,
                }
            }
            (kept, rig)
        }
    };
    if markers.is_empty() {
        return Err(MarkerError::TooFew(
            "no marker lies on the scan (check the landmarks or the marker file)".into(),
        )
        .into());
    }
    let before = fixed.vertex_count();
    let (mesh, markers) = keep_marked(fixed, markers, &mut report);
    // The rig's per-vertex data (labels, skin, regressors) must index the
    // mesh that is kept: re-embed it when stray pieces were dropped.
    // Regression (issue 18, item 1): `batch --scan` on the raw MakeHuman
    // base mesh indexed a regressor past the kept vertices and panicked.
    let rig = match (rig, spec_points) {
        (Some(_), Some(points)) if mesh.vertex_count() != before => {
            Some(Embedding::new(&mesh, &points, None)?)
        }
        (rig, _) => rig,
    };
    Ok(PreparedScan {
        mesh,
        markers,
        rig,
        report,
    })
}

/// The rig of the repaired mesh `fixed` from landmarks on the input `mesh`:
/// marks given as vertex ids name input vertices, so they become points
/// before the repair's renumbering matters.
fn embed_resolved(mesh: &Mesh, fixed: &Mesh, lm: &Landmarks) -> Result<Embedding, EmbedError> {
    Embedding::new(fixed, &resolved_points(mesh, lm), None)
}

/// The landmarks as points on the input `mesh` (vertex ids resolved).
fn resolved_points(mesh: &Mesh, lm: &Landmarks) -> Landmarks {
    Landmarks {
        marks: lm
            .marks
            .keys()
            .filter_map(|&l| lm.point(l, mesh.positions()).map(|p| (l, Mark::Point(p))))
            .collect(),
    }
}

fn sorted(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

/// Drops the connected components without a marker; renumbers the rest.
fn keep_marked(mesh: Mesh, markers: Vec<Marker>, report: &mut ScanReport) -> (Mesh, Vec<Marker>) {
    let c = components(&mesh);
    if c.count <= 1 {
        return (mesh, markers);
    }
    let t = mesh.triangles();
    let mut marked = vec![false; c.count];
    for m in &markers {
        marked[c.label[t[m.triangle as usize][0] as usize] as usize] = true;
    }
    if marked.iter().all(|&m| m) {
        return (mesh, markers);
    }
    let keep_v: Vec<bool> = c
        .label
        .iter()
        .map(|&l| l != u32::MAX && marked[l as usize])
        .collect();
    let mut dropped = vec![(0usize, 0usize); c.count];
    for (v, &l) in c.label.iter().enumerate() {
        if !keep_v[v] && l != u32::MAX {
            dropped[l as usize].0 += 1;
        }
    }
    let mut new_v = vec![u32::MAX; mesh.vertex_count()];
    let mut pos = Vec::new();
    for (v, &k) in keep_v.iter().enumerate() {
        if k {
            new_v[v] = pos.len() as u32;
            pos.push(mesh.positions()[v]);
        }
    }
    let mut new_t = vec![u32::MAX; t.len()];
    let mut tris = Vec::new();
    for (i, tv) in t.iter().enumerate() {
        if keep_v[tv[0] as usize] {
            new_t[i] = tris.len() as u32;
            tris.push(tv.map(|v| new_v[v as usize]));
        } else {
            dropped[c.label[tv[0] as usize] as usize].1 += 1;
        }
    }
    report.dropped_components = dropped
        .into_iter()
        .zip(&marked)
        .filter(|(_, m)| !**m)
        .map(|(d, _)| d)
        .collect();
    let markers = markers
        .into_iter()
        .map(|m| Marker {
            triangle: new_t[m.triangle as usize],
            ..m
        })
        .collect();
    let out = Mesh::new(pos, tris).expect("indices are renumbered in range");
    (out, markers)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::shapes::capsule_mesh;

    #[test]
    fn unmarked_pieces_are_dropped_and_markers_follow() {
        let a = capsule_mesh(0.1, 1.0, 8, 4);
        let n = a.vertex_count() as u32;
        let nt = a.triangle_count() as u32;
        let mut p: Vec<[f64; 3]> = a
            .positions()
            .iter()
            .map(|q| [q[0] + 3.0, q[1], q[2]])
            .collect();
        p.extend_from_slice(a.positions());
        let mut t: Vec<[u32; 3]> = a.triangles().to_vec();
        t.extend(a.triangles().iter().map(|tv| tv.map(|v| v + n)));
        let two = Mesh::new(p, t).unwrap();
        let file = MarkerFile {
            triangle_count: Some(two.triangle_count()),
            markers: vec![Marker {
                name: "m".into(),
                triangle: nt + 3,
                bone: None,
            }],
        };
        let s = prepare(&two, MarkerSpec::File(&file, None)).unwrap();
        assert_eq!(s.mesh.vertex_count(), n as usize);
        assert_eq!(s.report.dropped_components, vec![(n as usize, nt as usize)]);
        assert_eq!(s.markers[0].triangle, 3);
        assert_eq!(s.mesh.triangles()[3], a.triangles()[3]);
    }

    /// Regression (issue 18, item 16): markers recording another mesh's
    /// triangle count are refused, not applied to unrelated triangles.
    #[test]
    fn markers_of_another_mesh_are_refused() {
        let a = capsule_mesh(0.1, 1.0, 8, 4);
        let file = MarkerFile {
            triangle_count: Some(a.triangle_count() + 7),
            markers: vec![Marker {
                name: "m".into(),
                triangle: 3,
                bone: None,
            }],
        };
        let e = prepare(&a, MarkerSpec::File(&file, None)).err().unwrap();
        assert!(e.to_string().contains("another mesh"), "{e}");
    }
}
