//! `inspect` of the files that are neither clips, meshes nor JSON: a
//! database manifest, the web viewer's geometry (`.sm4d`) and site folder,
//! the caches `db build` writes, and the pictures and pages the verbs write
//! (`inspect` said "unknown file type" for each, though the tool writes
//! or reads every one of them).

use super::error::InspectError;
use super::json::JsonReport;
use crate::batch::summary::count;
use crate::util::fsutil::{MAX_INPUT_BYTES, open_input, read_bytes, read_small_text};
use std::io::Read;
use std::path::Path;

/// Reads every file a site lists and says what it found, or names the
/// first file that is missing or does not decode (issue 46, item 9: a site
/// whose `character.sm4d` was cut in half was reported with exit 0): the
/// geometry its `manifest.json` names (its size against the manifest's,
/// decoded, its blocks and frames against the manifest's), and each local
/// file `index.html` loads (`src=` and `href=`).
fn check_site(site: &Path) -> Result<Vec<String>, String> {
    let manifest_path = site.join("manifest.json");
    let text = read_small_text(&manifest_path).map_err(|e| e.to_string())?;
    let m: crate::web::SiteManifest = serde_json::from_str(&text)
        .map_err(|e| format!("{}: not a site manifest: {e}", manifest_path.display()))?;
    let url = format!("/{}", m.geometry);
    let geo = crate::web::resolve_path(site, &url).ok_or_else(|| {
        format!(
            "{}: the geometry file it names is missing or outside the site",
            site.join(&m.geometry).display()
        )
    })?;
    let bytes = read_bytes(&geo).map_err(|e| e.to_string())?;
    let shown = site.join(&m.geometry);
    if bytes.len() != m.geometry_bytes {
        return Err(format!(
            "{}: {} bytes, the site's manifest.json says {} (cut short or replaced; export the site again)",
            shown.display(),
            bytes.len(),
            m.geometry_bytes
        ));
    }
    let d = crate::web::codec::decode(&bytes).map_err(|e| format!("{}: {e}", shown.display()))?;
    if d.sequences.len() != m.geometry_sequences {
        return Err(format!(
            "{}: {} blocks of frames, the site's manifest.json says {}",
            shown.display(),
            d.sequences.len(),
            m.geometry_sequences
        ));
    }
    for (i, (q, s)) in d.sequences.iter().zip(&m.sequences).enumerate() {
        let frames = q.len() / d.vertices.max(1);
        if frames != s.frames {
            return Err(format!(
                "{}: block {i} ('{}') has {frames} frames, the site's manifest.json says {}",
                shown.display(),
                s.name,
                s.frames
            ));
        }
    }
    let index = site.join("index.html");
    let html = read_small_text(&index).map_err(|e| e.to_string())?;
    let mut assets = Vec::new();
    for key in ["src=\"", "href=\""] {
        for part in html.split(key).skip(1) {
            let Some(target) = part.split('"').next() else {
                continue;
            };
            let local = !target.is_empty()
                && !target.starts_with('#')
                && !target.contains(':')
                && !target.starts_with("//");
            if local && !assets.contains(&target) {
                assets.push(target);
            }
        }
    }
    for a in &assets {
        let url = format!("/{}", a.trim_start_matches("./"));
        let Some(p) = crate::web::resolve_path(site, &url) else {
            return Err(format!(
                "{}: index.html loads {a}, which is missing",
                site.display()
            ));
        };
        open_input(&p, MAX_INPUT_BYTES).map_err(|e| e.to_string())?;
    }
    Ok(vec![format!(
        "checked: {} ({} bytes, {} decoded) and the {} index.html loads",
        m.geometry,
        bytes.len(),
        count(d.sequences.len(), "block"),
        count(assets.len(), "file")
    )])
}

/// The report of `path` when it is one of these kinds; `None` otherwise.
pub(crate) fn inspect_other(path: &Path) -> Option<Result<JsonReport, InspectError>> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if path.is_dir() {
        return inspect_site(path);
    }
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
    Some(match ext.as_deref()? {
        "toml" if name.as_deref() == Some(crate::db::MANIFEST) => inspect_manifest(path),
        "sm4d" => inspect_sm4d(path),
        "bin" => inspect_bin(path),
        "png" => inspect_png(path),
        "svg" | "html" | "htm" => inspect_page(path, ext.as_deref() == Some("svg")),
        _ => return None,
    })
}

/// A report of `path` of kind `format`.
fn report(path: &Path, format: &str, lines: Vec<String>) -> JsonReport {
    JsonReport {
        path: path.to_path_buf(),
        format: format.into(),
        lines,
    }
}

fn err(e: String) -> InspectError {
    InspectError::Json(e)
}

/// A folder written by `web export` (its manifest, then the site checked);
/// `None` for any other folder.
fn inspect_site(path: &Path) -> Option<Result<JsonReport, InspectError>> {
    let manifest = path.join("manifest.json");
    if !(path.join("index.html").is_file() && manifest.is_file()) {
        return None;
    }
    Some(super::json::inspect_json(&manifest).and_then(|m| {
        let mut lines = m.lines;
        lines.extend(check_site(path).map_err(err)?);
        lines.push(format!(
            "open it with `surfmotion web serve --site {}` (or any static web server)",
            path.display()
        ));
        Ok(report(path, "web site", lines))
    }))
}

/// A database's `surfmotion.toml`.
fn inspect_manifest(path: &Path) -> Result<JsonReport, InspectError> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    crate::db::Manifest::load(dir)
        .map(|m| {
            let mut lines = vec![
                format!(
                    "the manifest of the character database '{}': {} fps, units {}, up {}",
                    m.name, m.fps, m.units, m.up
                ),
                format!("topology {}", m.topology.display()),
            ];
            lines.extend(
                m.sequences
                    .iter()
                    .map(|s| format!("sequence {} {}", s.name, s.path.display())),
            );
            lines.extend(
                m.spaces
                    .iter()
                    .map(|s| format!("motion space {}: {}", s.name, s.sequences.join(", "))),
            );
            lines.push(format!(
                "`surfmotion db info {}` reads every file it names",
                dir.display()
            ));
            report(path, "database manifest", lines)
        })
        .map_err(|e| err(e.to_string()))
}

/// A `.sm4d` file, checked frame by frame.
fn inspect_sm4d(path: &Path) -> Result<JsonReport, InspectError> {
    read_bytes(path)
        .map_err(|e| err(e.to_string()))
        .and_then(|b| {
            // Checked frame by frame, not loaded (a 1.9 MB file that
            // declared 66.7 million frames aborted on 8 GB).
            crate::web::codec::verify(&b)
                .map_err(|e| err(format!("{}: {e}", path.display())))
                .map(|d| {
                    let frames = d.frames.clone();
                    let shown: Vec<String> = frames.iter().take(8).map(|f| f.to_string()).collect();
                    report(
                        path,
                        "web geometry",
                        vec![
                            format!(
                                "the compressed 4D geometry of a `web export` site: {}, {}",
                                count(d.vertices, "vertex"),
                                count(d.triangles, "triangle")
                            ),
                            format!(
                                "{} of frames, {} in all: {}{} (the site's manifest.json names them; transition windows follow the sequences)",
                                count(frames.len(), "block"),
                                frames.iter().sum::<usize>(),
                                shown.join(", "),
                                if frames.len() > 8 { ", …" } else { "" }
                            ),
                            format!(
                                "{:?} prediction, step {:.3} mm, max vertex error {:.3} mm, {} bytes",
                                d.predictor,
                                1e3 * d.step,
                                1e3 * d.max_error,
                                b.len()
                            ),
                        ],
                    )
                })
        })
}

/// A `.bin` cache, by its magic bytes.
fn inspect_bin(path: &Path) -> Result<JsonReport, InspectError> {
    head(path, 8).map(|b| match &b[..] {
        b"SMSIM001" => report(
            path,
            "similarity cache",
            vec!["the frame-similarity matrix `db build` caches (rebuilt whenever the database changes; `surfmotion graph DB --matrix M.png` draws it)".into()],
        ),
        b"SMPAR001" => report(
            path,
            "parametric model cache",
            vec!["the parametric motion model `db build` caches for `play` (rebuilt whenever the database or its [[space]] entries change)".into()],
        ),
        _ => report(path, "unknown binary", vec!["not a cache the tool writes".into()]),
    })
}

/// A PNG picture's size.
fn inspect_png(path: &Path) -> Result<JsonReport, InspectError> {
    head(path, 24).map(|b| {
        let size = (b.len() == 24 && b.starts_with(b"\x89PNG\r\n\x1a\n")).then(|| {
            let be = |i: usize| u32::from_be_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
            (be(16), be(20))
        });
        report(
            path,
            "PNG picture",
            vec![match size {
                Some((w, h)) => format!("a picture of {w} × {h} pixels"),
                None => "not a PNG file (no PNG signature)".into(),
            }],
        )
    })
}

/// An SVG picture's size (`svg`) or an HTML page's title.
fn inspect_page(path: &Path, svg: bool) -> Result<JsonReport, InspectError> {
    read_small_text(path)
        .map_err(|e| err(e.to_string()))
        .map(|t| {
            let between = |a: &str, b: &str| {
                let i = t.find(a)? + a.len();
                Some(t[i..].split(b).next()?.trim().to_string())
            };
            if svg {
                report(
                    path,
                    "SVG picture",
                    vec![
                        match (between("width=\"", "\""), between("height=\"", "\"")) {
                            (Some(w), Some(h)) => format!("a picture of {w} × {h}"),
                            _ => "a picture".into(),
                        },
                    ],
                )
            } else {
                report(
                    path,
                    "HTML page",
                    vec![format!(
                        "a page{} ({} bytes); open it in a web browser",
                        between("<title>", "</title>")
                            .map(|x| format!(" titled '{x}'"))
                            .unwrap_or_default(),
                        t.len()
                    )],
                )
            }
        })
}

/// The first `n` bytes of a regular file (fewer if it is shorter).
pub(super) fn head(path: &Path, n: usize) -> Result<Vec<u8>, InspectError> {
    let f = open_input(path, MAX_INPUT_BYTES).map_err(|e| InspectError::Json(e.to_string()))?;
    let mut b = Vec::with_capacity(n);
    f.take(n as u64)
        .read_to_end(&mut b)
        .map_err(|e| InspectError::Json(format!("{}: {e}", path.display())))?;
    Ok(b)
}
