//! A picture of the Table III grid ([`super::grid`]): one cell per target
//! (distance rows, time columns), coloured by the larger of its distance
//! and time errors in percent of the target: green up to 1 % (the issue's
//! goal), yellow to red up to 10 %, dark red beyond. Targets the database
//! cannot reach are drawn faded. SVG carries axis labels and a legend;
//! PNG is the cells alone (8 px each).

use super::grid::{GridQuery, GridReport};
use crate::tools::render::Image;
use crate::util::fsutil::{FsError, write_bytes_atomic};
use std::path::Path;

/// The larger of the two errors, percent of the target.
pub(crate) fn error_pct(q: &GridQuery) -> f64 {
    let pct = |e: f64, t: f64| if t > 0.0 { 100.0 * e.abs() / t } else { 0.0 };
    pct(q.achieved_distance - q.distance, q.distance).max(pct(q.achieved_time - q.time, q.time))
}

/// The colour of an error (percent); faded when unreachable.
pub fn colour(pct: f64, reachable: bool) -> [u8; 3] {
    let c: [f64; 3] = if pct <= 1.0 {
        // Dark to light green across 0-1 %.
        let t = pct.clamp(0.0, 1.0);
        [30.0 + 90.0 * t, 140.0 + 60.0 * t, 60.0 + 20.0 * t]
    } else if pct <= 10.0 {
        // Yellow to red across 1-10 %.
        let t = (pct - 1.0) / 9.0;
        [240.0, 220.0 * (1.0 - t) + 40.0 * t, 40.0]
    } else {
        [130.0, 20.0, 20.0]
    };
    let f = if reachable { 1.0 } else { 0.3 };
    std::array::from_fn(|i| (c[i] * f + 255.0 * (1.0 - f)).round() as u8)
}

fn cell(g: &GridReport, i: usize, j: usize) -> Option<&GridQuery> {
    g.queries.get(i * g.times.len() + j)
}

/// The grid as cells of `px` pixels (rows: distances, bottom to top the
/// smallest first; columns: times).
pub fn image(g: &GridReport, px: usize) -> Image {
    let (rows, cols) = (g.distances.len(), g.times.len());
    let px = px.max(1);
    let mut img = Image::new(cols * px, rows * px, [255; 3]);
    for i in 0..rows {
        for j in 0..cols {
            let Some(q) = cell(g, i, j) else { continue };
            let c = colour(error_pct(q), q.reachable);
            for y in 0..px {
                for x in 0..px {
                    let (yy, xx) = ((rows - 1 - i) * px + y, j * px + x);
                    let o = (yy * img.width + xx) * 3;
                    img.rgb[o..o + 3].copy_from_slice(&c);
                }
            }
        }
    }
    img
}

/// The grid as an SVG document with axes and a legend.
pub fn svg(g: &GridReport) -> String {
    let (rows, cols) = (g.distances.len(), g.times.len());
    let (cw, ch) = (16.0, 16.0);
    let (left, top) = (60.0, 40.0);
    let (w, h) = (
        left + cols as f64 * cw + 170.0,
        top + rows as f64 * ch + 50.0,
    );
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"10\">\n\
         <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n\
         <text x=\"{left}\" y=\"20\" font-size=\"13\">Key-frame grid {}: max(distance, time) error, % of target</text>\n",
        xml(&g.keys.join(" → "))
    );
    for i in 0..rows {
        let y = top + (rows - 1 - i) as f64 * ch;
        s += &format!(
            "<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{} m</text>\n",
            left - 4.0,
            y + ch * 0.75,
            g.distances[i]
        );
        for j in 0..cols {
            let Some(q) = cell(g, i, j) else { continue };
            let p = error_pct(q);
            let c = colour(p, q.reachable);
            s += &format!(
                "<rect x=\"{}\" y=\"{y}\" width=\"{cw}\" height=\"{ch}\" fill=\"rgb({},{},{})\" stroke=\"white\" stroke-width=\"0.5\"><title>{} m in {} s: {:.3} m in {:.2} s ({:.2} %){}</title></rect>\n",
                left + j as f64 * cw,
                c[0],
                c[1],
                c[2],
                q.distance,
                q.time,
                q.achieved_distance,
                q.achieved_time,
                p,
                if q.reachable { "" } else { ", unreachable" }
            );
        }
    }
    let yb = top + rows as f64 * ch;
    for (j, t) in g.times.iter().enumerate() {
        if j % 5 == 0 || j + 1 == cols {
            s += &format!(
                "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{t} s</text>\n",
                left + (j as f64 + 0.5) * cw,
                yb + 14.0
            );
        }
    }
    let lx = left + cols as f64 * cw + 20.0;
    for (k, (label, p, r)) in [
        ("0 %", 0.0, true),
        ("1 %", 1.0, true),
        ("5 %", 5.0, true),
        ("10 %", 10.0, true),
        ("> 10 %", 50.0, true),
        ("unreachable, 1 %", 1.0, false),
        ("unreachable, > 10 %", 50.0, false),
    ]
    .iter()
    .enumerate()
    {
        let c = colour(*p, *r);
        let y = top + k as f64 * 20.0;
        s += &format!(
            "<rect x=\"{lx}\" y=\"{y}\" width=\"14\" height=\"14\" fill=\"rgb({},{},{})\"/><text x=\"{}\" y=\"{}\">{label}</text>\n",
            c[0],
            c[1],
            c[2],
            lx + 20.0,
            y + 11.0
        );
    }
    s += "</svg>\n";
    s
}

fn xml(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Writes the picture: `.svg` with labels, anything else as PNG.
pub fn save(g: &GridReport, path: &Path) -> Result<(), FsError> {
    let svg_ext = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    if svg_ext {
        write_bytes_atomic(path, svg(g).as_bytes())
    } else {
        image(g, 8).save_png(path)
    }
}
