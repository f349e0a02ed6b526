//! From a retrieved frame path to what each output frame blends
//! (Huang et al. 2015, Secs. 4.4 and 5.2.2).
//!
//! Every output frame starts as a time `τ` in one sequence. A frame that
//! the path repeats `n` times before moving on to its natural successor is
//! interpolated: the `j`th repeat sits at `τ = t + j/n`, i.e. the non-linear
//! blend `G(M(t), M(t+1), j/n)` (Sec. 5.2.2). A jump (a transition, or a
//! cut) from frame `m` of `A` to frame `n+1` of `B` is blended over the
//! `2L` output frames around it (Sec. 4.4): before the jump the output's
//! `A` time `τ` is paired with `B` at `τ + (n − m)`, after it the `B` time
//! with `A` at `τ − (n − m)`, and the weight of `B` rises as
//! `α = (k − (k_jump − L) + ½) / 2L`. Within a run that plays on, time is
//! smoothed with a (¼, ½, ¼) filter, so a skipped frame becomes a brief
//! speed-up. `L` is the transition's optimal
//! window, shortened so that neighbouring windows do not overlap. An output
//! frame is thus a weighted set of at most four database frames, blended
//! non-linearly.

use crate::graph::FlatFrame;
use serde::Serialize;

/// What one output frame blends: database frames and weights (summing to 1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct OutFrame {
    /// `(frame, weight)`; the first `count` are used.
    pub sources: [(FlatFrame, f64); 4],
    /// Sources used.
    pub count: usize,
}

impl OutFrame {
    /// The used sources.
    pub fn used(&self) -> &[(FlatFrame, f64)] {
        &self.sources[..self.count]
    }
    /// The source with the largest weight (frame 0 when none is used).
    pub(crate) fn primary(&self) -> FlatFrame {
        self.used()
            .iter()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(FlatFrame::default(), |s| s.0)
    }
    fn push(&mut self, id: FlatFrame, w: f64) {
        if w <= 1e-9 {
            return;
        }
        if let Some(s) = self.sources[..self.count].iter_mut().find(|s| s.0 == id) {
            s.1 += w;
        } else if self.count < 4 {
            self.sources[self.count] = (id, w);
            self.count += 1;
        }
    }
}

/// A jump in the path.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Jump {
    /// First output frame after the jump.
    pub at: usize,
    /// Frame left.
    pub from: FlatFrame,
    /// Frame entered.
    pub to: FlatFrame,
    /// Half-window of the blend.
    pub window: usize,
    /// True for a transition of the graph, false for a cut.
    pub transition: bool,
}

/// Frame layout of the database: sequence of a frame id, the id of
/// `(sequence, t)`, and sequence lengths.
pub trait Frames {
    /// `(sequence, frame)` of an id.
    fn frame_of(&self, id: FlatFrame) -> (usize, usize);
    /// Id of `(sequence, frame)`.
    fn flat_id(&self, s: usize, t: usize) -> FlatFrame;
    /// Frames in sequence `s`.
    fn len(&self, s: usize) -> usize;
    /// The graph's window for a transition `(m → n)` given as
    /// `(frame left, frame entered − 1)`, if it is one.
    fn transition_window(&self, from: FlatFrame, to_prev: FlatFrame) -> Option<usize>;
}

/// True when `b` plays on from `a`: the same frame, the next, or the one
/// after (a skip).
pub fn plays_on(db: &dyn Frames, a: FlatFrame, b: FlatFrame) -> bool {
    let (sa, ta) = db.frame_of(a);
    let (sb, tb) = db.frame_of(b);
    sa == sb && tb >= ta && tb <= ta + 2
}

/// Options of the timeline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimelineOptions {
    /// Interpolate repeated frames (Sec. 5.2.2). Default: true.
    pub interpolate: bool,
    /// Blend across jumps (Sec. 4.4). Default: true.
    pub blend: bool,
    /// Half-window for a cut. Default: 4.
    pub cut_window: usize,
}

impl Default for TimelineOptions {
    fn default() -> Self {
        TimelineOptions {
            interpolate: true,
            blend: true,
            cut_window: 4,
        }
    }
}

/// The output frames for a path, and the jumps it makes.
pub fn timeline(
    path: &[FlatFrame],
    db: &dyn Frames,
    opts: &TimelineOptions,
) -> (Vec<OutFrame>, Vec<Jump>) {
    let mut t = Timeline::default();
    timeline_into(path, db, opts, &mut t);
    (t.out, t.jumps)
}

/// [`timeline`]'s result and buffers, reused from one path to the next
/// (a live session's window; cleared before use).
#[derive(Debug, Clone, Default)]
pub struct Timeline {
    /// The output frames.
    pub out: Vec<OutFrame>,
    /// The jumps.
    pub jumps: Vec<Jump>,
    /// Each output frame's sequence and time, and a run's times.
    tau: Vec<(usize, f64)>,
    run: Vec<f64>,
}

/// [`timeline`] into `t` (its output frames and jumps): no allocation
/// once its buffers hold the path's frames and jumps.
pub fn timeline_into(
    path: &[FlatFrame],
    db: &dyn Frames,
    opts: &TimelineOptions,
    t: &mut Timeline,
) {
    let Timeline {
        out,
        jumps,
        tau,
        run,
    } = t;
    let nq = path.len();
    let succ = |id: FlatFrame| {
        let (s, t) = db.frame_of(id);
        (t + 1 < db.len(s)).then(|| db.flat_id(s, t + 1))
    };
    // Sequence and time of each output frame.
    tau.clear();
    tau.extend(path.iter().map(|&id| {
        let (s, t) = db.frame_of(id);
        (s, t as f64)
    }));
    if opts.interpolate {
        let mut k0 = 0;
        while k0 < nq {
            let mut k1 = k0 + 1;
            while k1 < nq && path[k1] == path[k0] {
                k1 += 1;
            }
            if k1 < nq && k1 - k0 > 1 && succ(path[k0]) == Some(path[k1]) {
                let n = (k1 - k0) as f64;
                for (j, t) in tau[k0..k1].iter_mut().enumerate() {
                    t.1 += j as f64 / n;
                }
            }
            k0 = k1;
        }
    }
    // Smooth time within each run that plays on, so a skipped frame
    // becomes a brief speed-up rather than a doubled step.
    if opts.interpolate {
        smooth_runs(path, db, tau, run);
    }
    // Jumps (a repeat, the next frame or a skip of one frame plays on);
    // at most one a frame, reserved so (no allocation as a window of the
    // same length meets more jumps: issue 45).
    jumps.clear();
    jumps.reserve(nq);
    for k in 1..nq {
        let (a, b) = (path[k - 1], path[k]);
        if plays_on(db, a, b) {
            continue;
        }
        let (sb, tb) = db.frame_of(b);
        let prev_b = (tb > 0).then(|| db.flat_id(sb, tb - 1));
        let win = prev_b.and_then(|p| db.transition_window(a, p));
        jumps.push(Jump {
            at: k,
            from: a,
            to: b,
            window: win.unwrap_or(opts.cut_window).max(1),
            transition: win.is_some(),
        });
    }
    // Windows must not overlap their neighbours' or leave the output.
    for i in 0..jumps.len() {
        let k = jumps[i].at;
        let mut l = jumps[i].window.min(k).min(nq - k);
        if i > 0 {
            l = l.min((k - jumps[i - 1].at) / 2);
        }
        if i + 1 < jumps.len() {
            l = l.min((jumps[i + 1].at - k) / 2);
        }
        jumps[i].window = l.max(1);
    }
    let split = |out: &mut OutFrame, s: usize, t: f64, w: f64| {
        let len = db.len(s);
        let t = t.clamp(0.0, (len - 1) as f64);
        let f = t.floor() as usize;
        let frac = t - f as f64;
        out.push(db.flat_id(s, f), w * (1.0 - frac));
        if f + 1 < len {
            out.push(db.flat_id(s, f + 1), w * frac);
        }
    };
    out.clear();
    out.extend(tau.iter().map(|&(s, t)| {
        let mut o = OutFrame {
            sources: [(FlatFrame::default(), 0.0); 4],
            count: 0,
        };
        split(&mut o, s, t, 1.0);
        o
    }));
    if opts.blend {
        for j in jumps.iter() {
            let (sa, ta) = db.frame_of(j.from);
            let (sb, tb) = db.frame_of(j.to);
            // B's time = A's time + offset (frame `to − 1` pairs with `from`).
            let offset = tb as f64 - 1.0 - ta as f64;
            let l = j.window;
            for kk in j.at.saturating_sub(l)..(j.at + l).min(nq) {
                let alpha = (kk as f64 - (j.at as f64 - l as f64) + 0.5) / (2 * l) as f64;
                let (s, t) = tau[kk];
                let (t_a, t_b) = if kk < j.at {
                    (t, t + offset)
                } else {
                    (t - offset, t)
                };
                let _ = s;
                let mut o = OutFrame {
                    sources: [(FlatFrame::default(), 0.0); 4],
                    count: 0,
                };
                split(&mut o, sa, t_a, 1.0 - alpha);
                split(&mut o, sb, t_b, alpha);
                out[kk] = o;
            }
        }
    }
}

/// Smooths the times `tau` of `path` within each run that plays on with
/// a (¼, ½, ¼) filter (`run`, a buffer for a run's times).
fn smooth_runs(path: &[FlatFrame], db: &dyn Frames, tau: &mut [(usize, f64)], run: &mut Vec<f64>) {
    let nq = path.len();
    run.clear();
    run.reserve(nq);
    let mut k0 = 0;
    while k0 < nq {
        let mut k1 = k0 + 1;
        while k1 < nq && plays_on(db, path[k1 - 1], path[k1]) {
            k1 += 1;
        }
        run.clear();
        run.extend(tau[k0..k1].iter().map(|t| t.1));
        for k in k0 + 1..k1.saturating_sub(1) {
            let a = (k - 1).max(k0);
            let b = (k + 2).min(k1);
            let w = if b - a == 3 {
                [0.25, 0.5, 0.25]
            } else {
                [0.0, 1.0, 0.0]
            };
            tau[k].1 = if b - a == 3 {
                w[0] * run[a - k0] + w[1] * run[a + 1 - k0] + w[2] * run[a + 2 - k0]
            } else {
                run[k - k0]
            };
        }
        k0 = k1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two sequences of 20 and 30 frames; one transition a:10 -> b:5 (L=3).
    struct Two;
    impl Frames for Two {
        fn frame_of(&self, id: FlatFrame) -> (usize, usize) {
            if id.get() < 20 {
                (0, id.index())
            } else {
                (1, id.index() - 20)
            }
        }
        fn flat_id(&self, s: usize, t: usize) -> FlatFrame {
            FlatFrame::from_index(if s == 0 { t } else { 20 + t })
        }
        fn len(&self, s: usize) -> usize {
            if s == 0 { 20 } else { 30 }
        }
        fn transition_window(&self, from: FlatFrame, to_prev: FlatFrame) -> Option<usize> {
            (from == f(10) && to_prev == f(25)).then_some(3)
        }
    }

    fn f(id: u32) -> FlatFrame {
        FlatFrame::new(id)
    }

    #[test]
    fn repeats_are_interpolated_and_jumps_blended() {
        // a:2 a:2 a:2 a:3 ... a:10 then b:6 b:7 ...
        let mut path: Vec<FlatFrame> = vec![f(2), f(2), f(2)];
        path.extend((3..=10).map(f));
        path.extend((26..=32).map(f));
        let (out, jumps) = timeline(&path, &Two, &TimelineOptions::default());
        assert_eq!(out.len(), path.len());
        // Interpolated repeats: 2, 2⅓, 2⅔.
        assert_eq!(out[0].used(), &[(f(2), 1.0)]);
        assert!((out[1].sources[0].1 - 2.0 / 3.0).abs() < 1e-12 && out[1].sources[1].0 == f(3));
        assert!((out[2].sources[1].1 - 2.0 / 3.0).abs() < 1e-12);
        // One transition with the graph's window.
        assert_eq!(jumps.len(), 1);
        let j = jumps[0];
        assert!(j.transition && j.window == 3 && j.at == 11);
        // Weights sum to 1; B's weight rises across the window.
        let mut last = 0.0;
        for (k, o) in out.iter().enumerate() {
            let total: f64 = o.used().iter().map(|s| s.1).sum();
            assert!((total - 1.0).abs() < 1e-12, "{k}");
            let wb: f64 = o.used().iter().filter(|s| s.0 >= f(20)).map(|s| s.1).sum();
            if (8..14).contains(&k) {
                assert!(wb > last && wb > 0.0 && wb < 1.0, "{k}: {wb}");
                last = wb;
            } else if k < 8 {
                assert_eq!(wb, 0.0);
            } else {
                assert_eq!(wb, 1.0);
            }
        }
        // Before the jump, A's frame pairs with B at the transition offset
        // (a:10 ↔ b:5, i.e. ids 10 ↔ 25).
        assert!(out[10].used().iter().any(|s| s.0 == f(10)));
        assert!(out[10].used().iter().any(|s| s.0 == f(25)));
        // Without blending or interpolation, frames are plain.
        let plain = TimelineOptions {
            interpolate: false,
            blend: false,
            ..Default::default()
        };
        let (out, _) = timeline(&path, &Two, &plain);
        assert!(out.iter().zip(&path).all(|(o, &p)| o.used() == [(p, 1.0)]));
    }
}
