//! Steps 3, 4 and 6 of the automatic landmarks: the extremities (geodesic
//! local maxima from the body's centre) told apart as feet, hands and head
//! top; the wrist and elbow from the rings of each hand; the knee from the
//! rings of each foot.

use super::frame::Frame;
use super::geometry::{Graph, along, arc_length, bend, clamp01, rings};
use glam::DVec3;

/// The extremities found and the vertex of each one named (`None`: not
/// found).
pub(super) struct Ends {
    /// Every extremity (vertices).
    pub all: Vec<usize>,
    pub lfoot: Option<usize>,
    pub rfoot: Option<usize>,
    pub lhand: Option<usize>,
    pub rhand: Option<usize>,
    pub head: Option<usize>,
}

/// Step 3: the geodesic local maxima (over a ball of 12 % of the height)
/// of the distance from the body's centre; a doubt when much of the mesh
/// is not connected to it.
pub(super) fn extremities(
    g: &Graph,
    p: &[DVec3],
    f: &Frame,
    doubts: &mut Vec<String>,
) -> Vec<usize> {
    let h = f.h;
    let mid = {
        let target = f.centre + f.up * (f.floor + 0.55 * h - f.centre.dot(f.up));
        let target = target - f.left * f.side(target);
        (0..p.len())
            .min_by(|&a, &b| p[a].distance(target).total_cmp(&p[b].distance(target)))
            .unwrap_or(0)
    };
    let gd = g.dijkstra(&[mid], f64::INFINITY);
    let reach = gd
        .iter()
        .copied()
        .filter(|d| d.is_finite())
        .fold(0.0, f64::max);
    let unreached = gd.iter().filter(|d| !d.is_finite()).count();
    if unreached > p.len() / 20 {
        doubts.push(format!(
            "{unreached} vertices are not connected to the body's centre (pieces apart)"
        ));
    }
    let mut cands: Vec<usize> = (0..p.len())
        .filter(|&v| {
            gd[v].is_finite()
                && gd[v] > 0.25 * reach
                && g.nb(v).iter().all(|&(w, _)| gd[w as usize] <= gd[v])
        })
        .collect();
    cands.sort_by(|&a, &b| gd[b].total_cmp(&gd[a]));
    let radius = 0.12 * h;
    let mut ext: Vec<usize> = Vec::new();
    let mut taken = vec![false; p.len()];
    for v in cands {
        if taken[v] {
            continue;
        }
        let ball = g.dijkstra(&[v], radius);
        let is_max = ball
            .iter()
            .enumerate()
            .all(|(w, d)| !d.is_finite() || gd[w] <= gd[v]);
        for (w, d) in ball.iter().enumerate() {
            if d.is_finite() {
                taken[w] = true;
            }
        }
        if is_max {
            ext.push(v);
        }
    }
    ext
}

/// Feet lowest on each side; hands farthest to each side above 30 % of
/// the height; head the highest near the plane.
pub(super) fn classify(ext: Vec<usize>, p: &[DVec3], f: &Frame) -> Ends {
    let h = f.h;
    let (side, hgt) = (|q: DVec3| f.side(q), |q: DVec3| f.hgt(q));
    let pick = |pred: &dyn Fn(usize) -> bool, key: &dyn Fn(usize) -> f64| {
        ext.iter()
            .copied()
            .filter(|&v| pred(v))
            .max_by(|&a, &b| key(a).total_cmp(&key(b)))
    };
    let lfoot = pick(&|v| side(p[v]) > 0.02 * h && hgt(p[v]) < 0.2 * h, &|v| {
        -hgt(p[v])
    });
    let rfoot = pick(&|v| side(p[v]) < -0.02 * h && hgt(p[v]) < 0.2 * h, &|v| {
        -hgt(p[v])
    });
    let lhand = pick(&|v| side(p[v]) > 0.08 * h && hgt(p[v]) > 0.3 * h, &|v| {
        side(p[v])
    });
    let rhand = pick(&|v| side(p[v]) < -0.08 * h && hgt(p[v]) > 0.3 * h, &|v| {
        -side(p[v])
    });
    let head = pick(
        &|v| side(p[v]).abs() < 0.08 * h && hgt(p[v]) > 0.75 * h,
        &|v| hgt(p[v]),
    );
    Ends {
        all: ext,
        lfoot,
        rfoot,
        lhand,
        rhand,
        head,
    }
}

/// One arm's wrist and elbow, their confidence and how they were found.
pub(super) struct Arm {
    pub wrist: DVec3,
    pub elbow: DVec3,
    pub conf: f64,
    pub how: String,
    pub elbow_how: String,
}

/// Step 4 for the hand whose tip is `tip`: rings from the tip, the wrist
/// the first narrowing after the palm, the elbow where the arm's centre
/// line bends most (else one forearm up it).
pub(super) fn arm(g: &Graph, p: &[DVec3], f: &Frame, tip: usize, step: f64) -> Arm {
    let h = f.h;
    let mut out = Arm {
        wrist: DVec3::ZERO,
        elbow: DVec3::ZERO,
        conf: 1.0,
        how: String::new(),
        elbow_how: String::new(),
    };
    let d = g.dijkstra(&[tip], 0.4 * h);
    let r = rings(g, p, &d, step, 0.4 * h);
    // The wrist: the ring of least perimeter between 5 and 16 % of the
    // height from the tip (the fingers and the flat palm are longer
    // around).
    // The hand's widest ring (the palm, 4-12 % of the height from the
    // tip), then the first narrowing after it.
    let palm = r
        .iter()
        .enumerate()
        .filter(|(_, x)| x.0 >= 0.04 * h && x.0 <= 0.12 * h)
        .max_by(|a, b| a.1.3.total_cmp(&b.1.3))
        .map(|(i, _)| i);
    let wide = palm.map_or(0.0, |i| r[i].3);
    let wrist = palm.and_then(|i| {
        let mut j = i;
        while j + 1 < r.len() && r[j + 1].3 <= r[j].3 && r[j + 1].0 <= 0.2 * h {
            j += 1;
        }
        if j > i {
            return Some(r[j]);
        }
        // No descent right after the palm: the least ring within 8 %
        // of the height beyond it.
        r[i + 1..]
            .iter()
            .filter(|x| x.0 <= r[i].0 + 0.08 * h)
            .min_by(|a, b| a.3.total_cmp(&b.3))
            .copied()
    });
    let Some(wrist) = wrist else {
        out.conf = 0.0;
        out.how = "no ring at the hand's base".into();
        return out;
    };
    let narrowing = if wide > 0.0 { wrist.3 / wide } else { 1.0 };
    let line: Vec<DVec3> = r.iter().filter(|x| x.0 >= wrist.0).map(|x| x.1).collect();
    let (elbow, bent) = match bend(&line, 0.08 * h, 0.25 * h, 0.05 * h) {
        Some((q, deg)) if deg > 40.0 => (q, Some(deg)),
        _ => (along(&line, 0.145 * h), None),
    };
    out.elbow_how = match bent {
        Some(deg) => {
            format!("where the arm's centre line bends most ({deg:.0}°) above the wrist")
        }
        None => "one forearm (14.5% of the height) up the arm's centre line from the wrist".into(),
    };
    if arc_length(&line) < 0.145 * h {
        out.conf = 0.0;
        out.how = "the arm is shorter than a forearm".into();
    }
    // A wrist shorter around than the hand: a hand; a wrist as thick
    // as a torso: something else (a prop).
    let c_thin = clamp01((0.95 - narrowing) / 0.2);
    let around = wrist.3 / h;
    let c_rad = clamp01((0.35 - around) / 0.1);
    if c_thin < 1.0 {
        out.how = format!(
            "the ring at the hand's base is {:.0}% of the hand's longest around (a wrist: shorter)",
            100.0 * narrowing
        );
    }
    if c_rad < 1.0 {
        out.how = format!(
            "the ring at the hand's base is {:.0}% of the height around (a wrist: under 25%)",
            100.0 * around
        );
    }
    out.conf = out.conf.min(c_thin).min(c_rad);
    out.wrist = wrist.1;
    out.elbow = elbow;
    out
}

/// Step 6 for the foot whose tip is `tip`: rings from the tip, the knee
/// where the leg's centre line bends most (else halfway from the ankle to
/// the hip); `(knee, confidence, how)` (`how` empty: the default words).
pub(super) fn leg(
    g: &Graph,
    p: &[DVec3],
    f: &Frame,
    tip: usize,
    step: f64,
    groin_h: f64,
) -> (DVec3, f64, String) {
    let h = f.h;
    let hgt = |q: DVec3| f.hgt(q);
    let d = g.dijkstra(&[tip], 1.2 * groin_h + 0.2 * h);
    let r = rings(g, p, &d, step, 1.2 * groin_h + 0.2 * h);
    let Some(a0) = r.iter().position(|x| hgt(x.1) > 0.039 * h) else {
        return (DVec3::ZERO, 0.0, "no leg above the foot".into());
    };
    let top = r
        .iter()
        .position(|x| hgt(x.1) > groin_h - 0.03 * h)
        .unwrap_or(r.len());
    if top <= a0 + 2 {
        return (DVec3::ZERO, 0.0, "the leg does not reach the groin".into());
    }
    let line: Vec<DVec3> = r[a0..top].iter().map(|x| x.1).collect();
    let len = arc_length(&line);
    match bend(&line, 0.25 * len, 0.8 * len, 0.05 * h) {
        Some((q, deg)) if deg > 40.0 => (
            q,
            1.0,
            format!("where the leg's centre line bends most ({deg:.0}°)"),
        ),
        // Shank and thigh of one length (Drillis & Contini): halfway
        // from the ankle to the hip, 9 % of the height above the
        // line's end below the crotch.
        _ => (along(&line, 0.5 * (len + 0.09 * h)), 1.0, String::new()),
    }
}
