//! The static site: the page's assets, the compact geometry
//! ([`super::codec`]) and `manifest.json` with the sequences and the Surface
//! Motion Graph's transition table (Huang et al. 2015, Sec. 4.3; the
//! paper's fixed transitions as Volino et al. 2015 play them in the
//! browser), each transition with the rigid ground-plane alignment that
//! carries the target's frames onto the source's.
//!
//! The folder is written into a temporary sibling and renamed into place:
//! an interrupted export never leaves a half-written site. The export
//! records what it wrote (name, size and hash of every file) in
//! [`RECORD_FILE`]; a later export replaces a folder only when it holds
//! nothing else (it refuses, naming the first file it did not write), and
//! never when an input lies inside it.

use super::codec::{self, EncodeOptions, EncodeReport, Geometry};
use super::site::{SiteManifest, SitePair, SiteSequence, SiteSpace, SiteTransition, WebError};
use super::windows::frame;
use crate::db::{BuildOptions, DbError, Manifest, Quiet};
use crate::graph::SurfaceMotionGraph;
use crate::mesh::io::{LoadOptions, load_sequence};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Name of the geometry file in a site.
pub const GEOMETRY_FILE: &str = "character.sm4d";
/// Name of the manifest in a site.
pub(crate) const MANIFEST_FILE: &str = "manifest.json";
/// The `format` field of a site manifest.
pub(crate) const FORMAT: &str = "surfmotion-web";
/// The record of the files an export wrote (the marker that lets a later
/// export replace the folder).
pub(crate) const RECORD_FILE: &str = ".surfmotion-export.json";
/// The geometry and manifest as a classic script (`window.surfmotionData`),
/// for the page opened from disk (`file://`), where browsers refuse `fetch`.
pub(crate) const SCRIPT_DATA_FILE: &str = "character.sm4d.js";
/// The `format` field of [`RECORD_FILE`].
const RECORD_FORMAT: &str = "surfmotion-web-export-files";

fn io(path: &Path) -> impl Fn(std::io::Error) -> WebError + '_ {
    move |e| WebError::Io {
        path: path.to_path_buf(),
        msg: e.to_string(),
    }
}

/// Options of the export.
#[derive(Debug, Clone, Copy, Default)]
pub struct ExportOptions {
    /// The geometry codec's options (default: 1 mm max vertex error).
    pub codec: EncodeOptions,
    /// Leave the transitions to the page's linear blend on the GPU instead
    /// of precomputing each window's non-linear blend (Huang et al. 2015,
    /// Sec. 4.4; default false: precomputed).
    pub linear_transitions: bool,
}

/// What an export wrote.
#[derive(Debug, Clone, Serialize)]
pub struct ExportReport {
    /// The site folder.
    pub site: PathBuf,
    /// The codec's report.
    pub geometry: EncodeReport,
    /// Vertices per frame.
    pub vertices: usize,
    /// Bytes the positions take as raw float32.
    pub raw_bytes: usize,
    /// Transitions in the table.
    pub transitions: usize,
    /// Frames of the precomputed non-linear transition windows.
    pub transition_frames: usize,
    /// Their bytes in the geometry file.
    pub transition_bytes: usize,
    /// Seconds spent blending them.
    pub transition_seconds: f64,
    /// Parametric spaces exported.
    pub spaces: usize,
    /// Frames of the spaces' reference blocks.
    pub space_frames: usize,
    /// Their bytes in the geometry file.
    pub space_bytes: usize,
    /// Seconds spent (load, encode and write).
    pub seconds: f64,
}

/// A database's geometry in metres, Y-up, with its manifest and graph.
pub fn load_db_geometry(dir: &Path) -> Result<(Manifest, Geometry, SurfaceMotionGraph), WebError> {
    let (_, graph, _) = crate::db::build(dir, &BuildOptions::default(), &Quiet)?;
    let m = Manifest::load(dir)?;
    let topo = m.load_topology(dir)?;
    let n = topo.vertex_count();
    let scale = crate::mocap::units::parse_unit(&m.units)
        .map(|u| u.metres_per_unit)
        .unwrap_or(1.0);
    let z_up = m.up.eq_ignore_ascii_case("z");
    let mut sequences = Vec::with_capacity(m.sequences.len());
    for s in &m.sequences {
        let seq = m.load_sequence(dir, s)?;
        if seq.mesh().vertex_count() != n {
            return Err(DbError::Manifest {
                path: dir.join(crate::db::MANIFEST),
                msg: format!(
                    "sequence '{}': {} vertices, the topology has {n}",
                    s.name,
                    seq.mesh().vertex_count()
                ),
            }
            .into());
        }
        sequences.push(metres(seq.all_positions(), z_up, scale));
    }
    Ok((
        m,
        Geometry {
            vertices: n,
            triangles: topo.triangles().to_vec(),
            sequences,
        },
        graph,
    ))
}

fn metres(p: &[[f64; 3]], z_up: bool, scale: f64) -> Vec<[f32; 3]> {
    p.iter()
        .map(|&q| {
            let v = crate::similarity::sets::y_up(q, z_up) * scale;
            [v.x as f32, v.y as f32, v.z as f32]
        })
        .collect()
}

/// The ground-plane rigid motion `[cos θ, sin θ, tx, tz]` that best carries
/// the points `b` onto `a` (2D Procrustes on x, z; Umeyama 1991 without
/// scale): `x' = R(θ) x + t` with `R` a rotation about +Y.
pub(crate) fn align_ground(a: &[[f32; 3]], b: &[[f32; 3]]) -> [f64; 4] {
    let k = a.len().min(b.len()).max(1) as f64;
    let mean = |p: &[[f32; 3]]| {
        let (mut x, mut z) = (0.0, 0.0);
        for q in p {
            x += q[0] as f64;
            z += q[2] as f64;
        }
        (x / k, z / k)
    };
    let (ax, az) = mean(a);
    let (bx, bz) = mean(b);
    let (mut dot, mut cross) = (0.0, 0.0);
    for (p, q) in a.iter().zip(b) {
        let (px, pz) = (p[0] as f64 - ax, p[2] as f64 - az);
        let (qx, qz) = (q[0] as f64 - bx, q[2] as f64 - bz);
        dot += px * qx + pz * qz;
        // Rotation about +Y maps (x, z) to (x cos + z sin, −x sin + z cos).
        cross += qz * px - qx * pz;
    }
    let th = cross.atan2(dot);
    let (c, s) = (th.cos(), th.sin());
    let tx = ax - (c * bx + s * bz);
    let tz = az - (-s * bx + c * bz);
    [c, s, tx, tz]
}

/// Writes the site for database `dir` into `out` (replacing an earlier
/// site there; refusing to replace any other non-empty folder).
pub fn export_db(dir: &Path, out: &Path, opts: &ExportOptions) -> Result<ExportReport, WebError> {
    let t0 = std::time::Instant::now();
    let inputs = db_inputs(dir);
    check_output(out, &inputs)?;
    let (m, mut g, graph) = load_db_geometry(dir)?;
    let sequences = m
        .sequences
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let frames = g.sequences[i].len() / g.vertices;
            SiteSequence {
                name: s.name.clone(),
                frames,
                fps: s.fps.unwrap_or(m.fps),
                restart: align_ground(frame(&g, i, frames - 1), frame(&g, i, 0)),
            }
        })
        .collect();
    let mut transitions = transition_table(&graph, &g);
    let base = g.sequences.len();
    let mut extra = Extra::default();
    if !opts.linear_transitions && !transitions.is_empty() {
        let t1 = std::time::Instant::now();
        let windows = super::windows::blend_windows(&g, &transitions, &Default::default())?;
        for (t, w) in transitions.iter_mut().zip(windows) {
            t.blended = Some(g.sequences.len());
            extra.transition_frames += w.len() / g.vertices;
            extra.transition_seqs.push(g.sequences.len());
            g.sequences.push(w);
        }
        extra.transition_seconds = t1.elapsed().as_secs_f64();
    }
    let spaces = if m.spaces.is_empty() {
        Vec::new()
    } else {
        let s0 = g.sequences.len();
        let sp = space_table(dir, &mut g)?;
        extra.space_seqs = (s0..g.sequences.len()).collect();
        extra.space_frames = g.sequences[s0..].iter().map(|s| s.len()).sum::<usize>() / g.vertices;
        sp
    };
    debug_assert!(g.sequences.len() >= base);
    write_site(
        out,
        &g,
        m.name.clone(),
        "character",
        sequences,
        transitions,
        spaces,
        extra,
        opts,
        &inputs,
        t0,
    )
}

/// The files a database export reads: the folder, and the topology and
/// sequences its manifest names (they may lie outside it).
fn db_inputs(dir: &Path) -> Vec<PathBuf> {
    let mut v = vec![dir.to_path_buf()];
    if let Ok(m) = Manifest::load(dir) {
        v.push(Manifest::resolve(dir, &m.topology));
        v.extend(m.sequences.iter().map(|s| Manifest::resolve(dir, &s.path)));
    }
    v
}

/// What the export adds to the database's own sequences.
#[derive(Debug, Default)]
struct Extra {
    transition_seqs: Vec<usize>,
    transition_frames: usize,
    transition_seconds: f64,
    space_seqs: Vec<usize>,
    space_frames: usize,
}

/// The database's parametric model ([`crate::parametric`], built or read
/// from its cache) as the page's spaces; each reference block is appended
/// to `g` as a geometry sequence of `K` frames.
fn space_table(dir: &Path, g: &mut Geometry) -> Result<Vec<SiteSpace>, WebError> {
    use crate::parametric::{MotionOptions, store::load_or_build};
    let (motion, _) = load_or_build(dir, &MotionOptions::default(), false)?;
    let summary = motion.summary();
    let mut out = Vec::with_capacity(motion.spaces.len());
    for (s, sum) in motion.spaces.iter().zip(summary) {
        if s.blend().n != g.vertices {
            return Err(WebError::Io {
                path: dir.to_path_buf(),
                msg: format!(
                    "space '{}': {} vertices, the topology has {}",
                    s.name(),
                    s.blend().n,
                    g.vertices
                ),
            });
        }
        let first = g.sequences.len();
        for b in &s.blend().blocks {
            g.sequences
                .push(b.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect());
        }
        out.push(SiteSpace {
            name: s.name().to_owned(),
            sequences: s.sequences().to_owned(),
            parameters: s
                .parameters()
                .iter()
                .map(|p| p.name().to_string())
                .collect(),
            grid: s.grid(),
            fps: motion.fps,
            pairs: s
                .blend()
                .pairs
                .iter()
                .map(|p| SitePair {
                    weights: p.weights.clone(),
                    blocks: p.blocks.iter().map(|b| first + b).collect(),
                })
                .collect(),
            first_block: first,
            steps: s
                .steps()
                .iter()
                .map(|r| {
                    r.step
                        .iter()
                        .zip(&r.duration)
                        .map(|(x, &d)| [x[0], x[1], x[2], d])
                        .collect()
                })
                .collect(),
            measured: s.measured().to_owned(),
            axis: s.axis().cloned(),
            ranges: sum.ranges.iter().map(|r| [r.min, r.max]).collect(),
        });
    }
    Ok(out)
}

/// The graph's transitions as the page's table, in the graph's order.
pub fn transition_table(graph: &SurfaceMotionGraph, g: &Geometry) -> Vec<SiteTransition> {
    graph
        .transitions()
        .iter()
        .map(|t| SiteTransition {
            from: t.from,
            to: t.to,
            m: t.m,
            n: t.n,
            window: t.window,
            cost: t.cost,
            align: align_ground(frame(g, t.from, t.m), frame(g, t.to, t.n)),
            blended: None,
        })
        .collect()
}

/// Writes a site that plays one result (a `.glb`, or a `.pc2`/`.mdd` with
/// its topology: `topology`, else the `.obj` of the same name) with a
/// timeline. Results are in metres, Y-up, as every writer of this tool
/// makes them.
pub fn export_result(
    result: &Path,
    topology: Option<&Path>,
    out: &Path,
    opts: &ExportOptions,
) -> Result<ExportReport, WebError> {
    let t0 = std::time::Instant::now();
    // The result, its topology, and the `.obj` of the same name the loader
    // takes when no topology is given.
    let mut inputs = vec![result.to_path_buf(), result.with_extension("obj")];
    inputs.extend(topology.map(Path::to_path_buf));
    check_output(out, &inputs)?;
    let seq = load_sequence(
        &result.to_string_lossy(),
        &LoadOptions {
            topology: topology.map(Path::to_path_buf),
            fps: None,
        },
    )?;
    let n = seq.mesh().vertex_count();
    let g = Geometry {
        vertices: n,
        triangles: seq.mesh().triangles().to_vec(),
        sequences: vec![metres(seq.all_positions(), false, 1.0)],
    };
    let frames = seq.frame_count();
    let name = result
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "result".into());
    let sequences = vec![SiteSequence {
        name: name.clone(),
        frames,
        fps: seq.fps.unwrap_or(30.0),
        restart: [1.0, 0.0, 0.0, 0.0],
    }];
    write_site(
        out,
        &g,
        name,
        "result",
        sequences,
        Vec::new(),
        Vec::new(),
        Extra::default(),
        opts,
        &inputs,
        t0,
    )
}

#[allow(clippy::too_many_arguments)]
fn write_site(
    out: &Path,
    g: &Geometry,
    name: String,
    mode: &str,
    sequences: Vec<SiteSequence>,
    transitions: Vec<SiteTransition>,
    spaces: Vec<SiteSpace>,
    extra: Extra,
    opts: &ExportOptions,
    inputs: &[PathBuf],
    t0: std::time::Instant,
) -> Result<ExportReport, WebError> {
    let (bytes, rep) = codec::encode(g, &opts.codec)?;
    // Bytes of geometry sequence `s`: its entry in the file's table.
    let seq_bytes = |s: usize| -> usize {
        let at = codec::HEADER_BYTES + 8 * s + 4;
        bytes
            .get(at..at + 4)
            .map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    let transition_bytes = extra.transition_seqs.iter().map(|&s| seq_bytes(s)).sum();
    let space_bytes = extra.space_seqs.iter().map(|&s| seq_bytes(s)).sum();
    let manifest = SiteManifest {
        format: FORMAT.into(),
        version: 1,
        mode: mode.into(),
        name,
        geometry: GEOMETRY_FILE.into(),
        geometry_bytes: bytes.len(),
        max_error: rep.max_error,
        sequences,
        transitions,
        spaces,
        geometry_sequences: g.sequences.len(),
    };
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&parent).map_err(io(&parent))?;
    // Checked again: the folder may have changed while the geometry encoded.
    check_output(out, inputs)?;
    let json = serde_json::to_string_pretty(&manifest).map_err(|e| WebError::Io {
        path: out.join(MANIFEST_FILE),
        msg: e.to_string(),
    })?;
    let script = script_data(&json, &bytes);
    let mut files: Vec<(&str, &[u8])> = super::assets::FILES.to_vec();
    files.push((GEOMETRY_FILE, &bytes));
    files.push((MANIFEST_FILE, json.as_bytes()));
    files.push((SCRIPT_DATA_FILE, script.as_bytes()));
    let record = Record {
        format: RECORD_FORMAT.into(),
        version: 1,
        files: files
            .iter()
            .map(|(name, body)| RecordedFile {
                name: (*name).into(),
                bytes: body.len() as u64,
                xxh3: format!("{:016x}", xxhash_rust::xxh3::xxh3_64(body)),
            })
            .collect(),
    };
    let record = serde_json::to_string_pretty(&record).map_err(|e| WebError::Io {
        path: out.join(RECORD_FILE),
        msg: e.to_string(),
    })?;
    files.push((RECORD_FILE, record.as_bytes()));
    let tmp = tempfile::Builder::new()
        .prefix(".surfmotion-site-")
        .tempdir_in(&parent)
        .map_err(io(&parent))?;
    for (file, body) in &files {
        let p = tmp.path().join(file);
        std::fs::write(&p, body).map_err(io(&p))?;
    }
    // Folders are created private; a site is for serving.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(tmp.path(), std::fs::Permissions::from_mode(0o755))
            .map_err(io(tmp.path()))?;
    }
    if out.symlink_metadata().is_ok() {
        // Only an earlier export of this tool's own, holding nothing else,
        // gets here (check_output): it is moved aside, the new site moved
        // in, then the old one removed; a failed move puts it back.
        let old = tempfile::Builder::new()
            .prefix(".surfmotion-old-site-")
            .tempdir_in(&parent)
            .map_err(io(&parent))?;
        let old_site = old.path().join("site");
        std::fs::rename(out, &old_site).map_err(io(out))?;
        if let Err(e) = std::fs::rename(tmp.path(), out) {
            let _ = std::fs::rename(&old_site, out);
            return Err(io(out)(e));
        }
        let _ = tmp.keep();
        old.close().map_err(|e| WebError::Io {
            path: old_site,
            msg: format!("the earlier site was replaced but not removed: {e}"),
        })?;
    } else {
        std::fs::rename(tmp.path(), out).map_err(io(out))?;
        let _ = tmp.keep();
    }
    Ok(ExportReport {
        site: out.to_path_buf(),
        vertices: g.vertices,
        raw_bytes: g.sequences.iter().map(|s| s.len() * 12).sum(),
        transitions: manifest.transitions.len(),
        transition_frames: extra.transition_frames,
        transition_bytes,
        transition_seconds: extra.transition_seconds,
        spaces: manifest.spaces.len(),
        space_frames: extra.space_frames,
        space_bytes,
        geometry: rep,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// The record of an export's files ([`RECORD_FILE`]).
#[derive(Debug, Serialize, Deserialize)]
struct Record {
    format: String,
    version: u32,
    files: Vec<RecordedFile>,
}

/// One file an export wrote.
#[derive(Debug, Serialize, Deserialize)]
struct RecordedFile {
    name: String,
    bytes: u64,
    /// XXH3-64 of the contents, hex.
    xxh3: String,
}

/// The geometry and manifest as a classic script: a page opened from disk
/// (`file://`) loads it with a `<script>` tag where `fetch` is refused.
fn script_data(manifest_json: &str, geometry: &[u8]) -> String {
    use base64::Engine as _;
    format!(
        "// The manifest and geometry of this site for a page opened from disk (file://),\n\
         // where browsers refuse fetch(); written by `surfmotion web export`.\n\
         window.surfmotionData = {{ manifest: {}, geometry: \"{}\" }};\n",
        manifest_json,
        base64::engine::general_purpose::STANDARD.encode(geometry)
    )
}

/// Refuses an output folder that an input lies in (an export replaces the
/// folder), or that holds anything an earlier export did not write: a
/// folder may be replaced only when it is empty, or holds exactly files
/// recorded in its [`RECORD_FILE`] with their recorded size and hash (or,
/// for a site of an earlier version without the record, only the files such
/// a site holds, with its manifest). Names the first file it refuses for.
pub(crate) fn check_output(out: &Path, inputs: &[PathBuf]) -> Result<(), WebError> {
    let Ok(meta) = out.symlink_metadata() else {
        return Ok(());
    };
    let refuse = |path: PathBuf, msg: String| Err(WebError::Refused { path, msg });
    if !meta.is_dir() {
        return refuse(
            out.to_path_buf(),
            "exists and is not a folder; not replacing it with a site".into(),
        );
    }
    if let Ok(o) = out.canonicalize() {
        for i in inputs {
            // A pattern or a file not there yet: its folder.
            let c = i.canonicalize().or_else(|_| {
                i.parent()
                    .map_or(Err(()), |p| p.canonicalize().map_err(|_| ()))
            });
            if c.is_ok_and(|c| c.starts_with(&o)) {
                return refuse(
                    i.clone(),
                    format!(
                        "an input of the export lies in the output folder {}, which the export replaces; write the site to another folder",
                        out.display()
                    ),
                );
            }
        }
    }
    let mut names: Vec<std::ffi::OsString> = std::fs::read_dir(out)
        .map_err(io(out))?
        .map(|e| e.map(|e| e.file_name()))
        .collect::<Result<_, _>>()
        .map_err(io(out))?;
    names.sort();
    if names.is_empty() {
        return Ok(());
    }
    let record: Option<Record> = crate::util::fsutil::read_small_text(&out.join(RECORD_FILE))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .filter(|r: &Record| r.format == RECORD_FORMAT);
    // A site of an earlier version: its manifest, no record.
    let legacy = record.is_none()
        && crate::util::fsutil::read_small_text(&out.join(MANIFEST_FILE))
            .ok()
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
            .is_some_and(|v| v["format"] == FORMAT);
    for name in &names {
        let name_s = name.to_string_lossy();
        let path = out.join(name);
        let is_file = path.symlink_metadata().is_ok_and(|m| m.is_file());
        let foreign = |why: &str| {
            refuse(
                path.clone(),
                format!(
                    "{why}; not replacing {} (move the file away or choose another output folder)",
                    out.display()
                ),
            )
        };
        if let Some(r) = &record {
            if name_s == RECORD_FILE && is_file {
                continue;
            }
            let Some(f) = r.files.iter().find(|f| f.name == name_s) else {
                return foreign("not written by the earlier `web export` in this folder");
            };
            let body = if is_file {
                crate::util::fsutil::read_bytes(&path).ok()
            } else {
                None
            };
            let same = body.is_some_and(|b| {
                b.len() as u64 == f.bytes
                    && format!("{:016x}", xxhash_rust::xxh3::xxh3_64(&b)) == f.xxh3
            });
            if !same {
                return foreign("changed since the earlier `web export` wrote it");
            }
        } else if legacy {
            let known = super::assets::FILES.iter().any(|(f, _)| *f == name_s)
                || name_s == GEOMETRY_FILE
                || name_s == MANIFEST_FILE;
            if !(known && is_file) {
                return foreign("not a file of a `web export` site");
            }
        } else {
            return foreign(
                "the folder is not empty and holds no earlier `web export` (no record of its files)",
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ground_alignment_recovers_a_turn_and_shift() {
        let a: Vec<[f32; 3]> = (0..20)
            .map(|i| {
                let t = i as f32 * 0.7;
                [t.cos() + 0.1 * t, t * 0.05, t.sin()]
            })
            .collect();
        let (c, s) = (0.6f64.cos(), 0.6f64.sin());
        // b = R(−0.6)(a − (1, 2)): aligning b onto a must give R(0.6), t = (1, 2)
        // up to the rotation's convention; check by applying it.
        let b: Vec<[f32; 3]> = a
            .iter()
            .map(|p| {
                let (x, z) = (p[0] as f64 - 1.0, p[2] as f64 - 2.0);
                [(c * x - s * z) as f32, p[1], (s * x + c * z) as f32]
            })
            .collect();
        let [c2, s2, tx, tz] = align_ground(&a, &b);
        for (p, q) in a.iter().zip(&b) {
            let (x, z) = (q[0] as f64, q[2] as f64);
            let (x2, z2) = (c2 * x + s2 * z + tx, -s2 * x + c2 * z + tz);
            assert!((x2 - p[0] as f64).abs() < 1e-5 && (z2 - p[2] as f64).abs() < 1e-5);
        }
    }
}
