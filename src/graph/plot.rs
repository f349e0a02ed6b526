//! A picture of the similarity matrix with the transitions marked, like
//! Huang et al. 2015, Fig. 4: dark is similar, bright dissimilar
//! (a viridis-like ramp up to the 98th percentile), white lines between
//! sequences, each transition a red cross at `(m, n)` with its window drawn
//! along the diagonal.

use super::SurfaceMotionGraph;
use crate::similarity::Dissimilarity;
use crate::tools::render::Image;

/// Five stops of the viridis colour map.
const RAMP: [[f64; 3]; 5] = [
    [68.0, 1.0, 84.0],
    [59.0, 82.0, 139.0],
    [33.0, 145.0, 140.0],
    [94.0, 201.0, 98.0],
    [253.0, 231.0, 37.0],
];

fn ramp(t: f64) -> [u8; 3] {
    let t = t.clamp(0.0, 1.0) * (RAMP.len() - 1) as f64;
    let i = (t as usize).min(RAMP.len() - 2);
    let f = t - i as f64;
    std::array::from_fn(|c| (RAMP[i][c] * (1.0 - f) + RAMP[i + 1][c] * f).round() as u8)
}

/// Draws the matrix at about `max_px` pixels a side (each pixel the
/// minimum of the frames it covers, so narrow valleys stay visible; small
/// matrices are enlarged to whole pixels per frame).
pub fn matrix_image(
    m: &(impl Dissimilarity + ?Sized),
    g: &SurfaceMotionGraph,
    max_px: usize,
) -> Image {
    let n = m.frame_count().max(1);
    let max_px = max_px.max(16);
    let (px, per) = if n <= max_px {
        let s = (max_px / n).max(1);
        (n * s, 1.0 / s as f64)
    } else {
        (max_px, n as f64 / max_px as f64)
    };
    // Pairs a sparse similarity does not store are infinite: drawn at the
    // top of the ramp, left out of the percentile.
    let frames = m.frame_count();
    let mut vals: Vec<f32> = (0..frames)
        .flat_map(|a| (0..frames).map(move |b| (a, b)))
        .map(|(a, b)| m.value(a, b))
        .filter(|v| v.is_finite())
        .collect();
    let hi = if vals.is_empty() {
        1.0
    } else {
        let k = ((vals.len() as f64) * 0.98) as usize;
        let k = k.min(vals.len() - 1);
        *vals.select_nth_unstable_by(k, f32::total_cmp).1 as f64
    }
    .max(f64::MIN_POSITIVE);
    let mut img = Image::new(px, px, [255; 3]);
    let span = |p: usize| -> (usize, usize) {
        let a = (p as f64 * per) as usize;
        let b = (((p + 1) as f64 * per).ceil() as usize).clamp(a + 1, n);
        (a.min(n - 1), b)
    };
    for y in 0..px {
        let (ra, rb) = span(y);
        for x in 0..px {
            let (ca, cb) = span(x);
            let mut v = f32::INFINITY;
            for r in ra..rb {
                for c in ca..cb {
                    v = v.min(m.value(r, c));
                }
            }
            let rgb = ramp(v as f64 / hi);
            img.rgb[(y * px + x) * 3..(y * px + x) * 3 + 3].copy_from_slice(&rgb);
        }
    }
    let to_px = |f: usize| ((f as f64 + 0.5) / per) as usize;
    for s in m.spans().iter().skip(1) {
        let p = ((s.start as f64) / per) as usize;
        for k in 0..px {
            for (x, y) in [(p, k), (k, p)] {
                if x < px && y < px {
                    img.rgb[(y * px + x) * 3..(y * px + x) * 3 + 3].copy_from_slice(&[255; 3]);
                }
            }
        }
    }
    let mut dot = |x: i64, y: i64, c: [u8; 3]| {
        if x >= 0 && y >= 0 && (x as usize) < px && (y as usize) < px {
            let i = (y as usize * px + x as usize) * 3;
            img.rgb[i..i + 3].copy_from_slice(&c);
        }
    };
    let arm = (px as i64 / 120).max(2);
    for t in g.transitions() {
        let r = m.spans()[t.from].start + t.m;
        let c = m.spans()[t.to].start + t.n;
        let (x, y) = (to_px(c) as i64, to_px(r) as i64);
        // The blend window along the diagonal.
        for k in -(t.window as i64)..=(t.window as i64) {
            let (rr, cc) = (r as i64 + k, c as i64 + k);
            if rr >= 0 && cc >= 0 {
                dot(
                    to_px(cc as usize) as i64,
                    to_px(rr as usize) as i64,
                    [255, 120, 120],
                );
            }
        }
        for d in -arm..=arm {
            dot(x + d, y + d, [230, 20, 20]);
            dot(x + d, y - d, [230, 20, 20]);
        }
    }
    img
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{GraphEdits, TransitionOptions};
    use crate::similarity::{Measure, SimilarityMatrix, Span};

    #[test]
    fn draws_values_boundaries_and_crosses() {
        let n = 60;
        let data: Vec<f32> = (0..n * n)
            .map(|k| (((k / n) % 20) as f32 - ((k % n) % 20) as f32).abs())
            .collect();
        let spans = vec![
            Span {
                name: "a".into(),
                start: 0,
                len: 40,
            },
            Span {
                name: "b".into(),
                start: 40,
                len: 20,
            },
        ];
        let m = SimilarityMatrix::new(spans, data).unwrap();
        let g = SurfaceMotionGraph::build(
            &m,
            Measure::Shape,
            &TransitionOptions::default(),
            &GraphEdits::default(),
        )
        .unwrap();
        assert!(!g.transitions().is_empty());
        let img = matrix_image(&m, &g, 240);
        assert_eq!((img.width, img.height), (240, 240));
        // Diagonal dark, boundary white, some red.
        assert_eq!(&img.rgb[0..3], &ramp(0.0));
        let b = 40 * 4;
        assert_eq!(
            &img.rgb[(5 * 240 + b) * 3..(5 * 240 + b) * 3 + 3],
            &[255; 3]
        );
        assert!(img.rgb.chunks(3).any(|p| p == [230, 20, 20]));
        // Large matrices are reduced.
        assert_eq!(matrix_image(&m, &g, 30).width, 30);
    }
}
