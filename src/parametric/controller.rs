//! The frame-by-frame controller (Casas et al. 2013, Sec. 3): the character
//! in a motion space at a phase and blend weight, steered by control input
//! (speed, turn, requested space), one mesh per call.
//!
//! Per frame: the hybrid blend at the current weight and phase
//! ([`super::hybrid`], Eq. 3), placed at the integrated root (the blended
//! root step of the phase, [`super::params`]); the phase advances by one
//! frame of the blended cycle; the weight moves towards `h⁻¹(p)` of the
//! asked parameter at most [`WEIGHT_RATE`] per second (no pops). A
//! requested space is reached by the transition that [`super::transition`]
//! finds at request time (Eqs. 4-5), played as a short cross-fade. A later
//! `turn` parameter of a space steers the heading (added to the blend's own
//! turning so that the total is the asked rate). [`Controller::advance`]
//! does not allocate.

use super::Parameter;
use super::space::{Motion, place};
use super::transition::{TargetState, TransitionPlanner};
use glam::DVec2;
use serde::Serialize;

/// Largest change of the weight coordinate per second.
pub(crate) const WEIGHT_RATE: f64 = 1.5;

/// Control input; `None` keeps the previous value.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Control {
    /// The space to be in (an index into [`Motion::spaces`]).
    pub space: Option<usize>,
    /// Speed, m/s.
    pub speed: Option<f64>,
    /// Turn rate, degrees per second (left positive).
    pub turn: Option<f64>,
}

/// Something a control request could not do as asked.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Notice {
    /// The asked value is outside the space's valid range: clamped.
    Clamped {
        /// Space.
        space: String,
        /// Parameter.
        parameter: Parameter,
        /// Asked.
        asked: f64,
        /// Used.
        used: f64,
        /// Valid range.
        range: [f64; 2],
    },
    /// The space has no such parameter: the value waits for a space that has.
    NotInSpace {
        /// Space.
        space: String,
        /// Parameter.
        parameter: Parameter,
    },
}

impl std::fmt::Display for Notice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Notice::Clamped {
                space,
                parameter,
                asked,
                used,
                range,
            } => write!(
                f,
                "space '{space}': {} {} {u} is outside the valid range [{:.3}, {:.3}] {u}: clamped to {used:.3}",
                parameter.name(),
                crate::util::numfmt::Short(*asked),
                range[0],
                range[1],
                u = parameter.unit()
            ),
            Notice::NotInSpace { space, parameter } => {
                write!(
                    f,
                    "space '{space}' has no parameter '{}': ignored there",
                    parameter.name()
                )
            }
        }
    }
}

/// One transition taken.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TransitionRecord {
    /// Source space.
    pub from: String,
    /// Target space.
    pub to: String,
    /// Frame of the request.
    pub request_frame: usize,
    /// First frame of the cross-fade (the jump).
    pub start_frame: usize,
    /// First frame fully in the target space.
    pub end_frame: usize,
    /// `(start − request) / fps`, seconds.
    pub latency: f64,
    /// Similarity at the jump (Eq. 5).
    pub similarity: f64,
    /// `E_S + λ E_L` (Eq. 4).
    pub cost: f64,
    /// Source phase samples played from the request to the jump (the
    /// forward trellis path).
    pub source_path: Vec<usize>,
    /// Target phase sample entered.
    pub entry: usize,
    /// Seconds the decision took.
    pub decision_seconds: f64,
}

#[derive(Debug, Clone, Copy)]
struct Head {
    space: usize,
    phase: f64,
    u: f64,
}

#[derive(Debug, Clone, Copy)]
struct Pending {
    target: usize,
    wait: usize,
    entry: usize,
    u: f64,
    record: usize,
}

/// Plays a [`Motion`] frame by frame.
pub struct Controller<'m> {
    motion: &'m Motion,
    head: Head,
    u_target: f64,
    wanted: [Option<f64>; 2],
    steer: f64,
    root: DVec2,
    heading: f64,
    pending: Option<Pending>,
    fade: Option<(Head, usize, usize)>,
    frame: usize,
    local: Vec<[f64; 3]>,
    other: Vec<[f64; 3]>,
    out: Vec<[f64; 3]>,
    predicted: Vec<usize>,
    planner: TransitionPlanner,
    /// Transitions taken so far.
    pub transitions: Vec<TransitionRecord>,
}

impl<'m> Controller<'m> {
    /// A controller in space `space` at phase 0, the first sequence's
    /// weight, at the origin facing +Z.
    pub fn new(motion: &'m Motion, space: usize) -> Controller<'m> {
        let n = motion.topology.vertex_count();
        let depth = motion.options.transition.depth;
        let kmax = motion.spaces.iter().map(|s| s.grid()).max().unwrap_or(1);
        Controller {
            motion,
            head: Head {
                space,
                phase: 0.0,
                u: 0.0,
            },
            u_target: 0.0,
            wanted: [None; 2],
            steer: 0.0,
            root: DVec2::ZERO,
            heading: 0.0,
            pending: None,
            fade: None,
            frame: 0,
            local: vec![[0.0; 3]; n],
            other: vec![[0.0; 3]; n],
            out: vec![[0.0; 3]; n],
            predicted: Vec::with_capacity(depth + 1),
            planner: TransitionPlanner::with_capacity(depth, kmax),
            transitions: Vec::with_capacity(16),
        }
    }

    /// The space the character is in (the source until a transition's
    /// cross-fade ends).
    pub fn space(&self) -> usize {
        self.head.space
    }
    /// Root position `(x, z)` (metres).
    pub fn root(&self) -> DVec2 {
        self.root
    }
    /// Heading (radians, unwrapped, left positive).
    pub fn heading(&self) -> f64 {
        self.heading
    }
    /// Frames played.
    pub fn frame(&self) -> usize {
        self.frame
    }
    /// The current phase (grid units of the current space).
    pub fn phase(&self) -> f64 {
        self.head.phase
    }
    /// The current weight coordinate.
    pub fn weight(&self) -> f64 {
        self.head.u
    }
    /// A transition is waiting or fading.
    pub(crate) fn in_transition(&self) -> bool {
        self.pending.is_some() || self.fade.is_some()
    }

    /// The weight and notices for the wanted parameters in `space`; also
    /// sets the steering when `space` is the current one.
    fn resolve(&self, space: usize, notices: &mut Vec<Notice>) -> (f64, f64) {
        let s = &self.motion.spaces[space];
        let mut u = self.head.u.min(s.u_max());
        if space != self.head.space {
            u = 0.0;
        }
        let mut steer_turn = None;
        for (i, p) in Parameter::ALL.iter().enumerate() {
            let Some(v) = self.wanted[i] else { continue };
            match s.parameters().iter().position(|q| q == p) {
                None => notices.push(Notice::NotInSpace {
                    space: s.name().to_owned(),
                    parameter: *p,
                }),
                Some(0) => {
                    if let Some(map) = &s.axis() {
                        let (w, clamped) = map.inverse(v);
                        if clamped {
                            notices.push(Notice::Clamped {
                                space: s.name().to_owned(),
                                parameter: *p,
                                asked: v,
                                used: v.clamp(map.range[0], map.range[1]),
                                range: map.range,
                            });
                        }
                        u = w;
                    }
                }
                Some(_) => steer_turn = Some(v),
            }
        }
        (u, steer_turn.unwrap_or(f64::NAN))
    }

    /// Applies control input. A new space starts a transition search now
    /// (Eqs. 4-5); parameters set the weight target. Returns what could not
    /// be done as asked. Allocates only for the notices and the record.
    pub fn control(&mut self, c: &Control) -> Vec<Notice> {
        let mut notices = Vec::new();
        if let Some(v) = c.speed {
            self.wanted[0] = Some(v);
        }
        if let Some(v) = c.turn {
            self.wanted[1] = Some(v);
        }
        let current_target = self
            .pending
            .map(|p| p.target)
            .or(self.fade.map(|f| f.0.space))
            .unwrap_or(self.head.space);
        match c.space {
            Some(t)
                if t != current_target && t < self.motion.spaces.len() && !self.in_transition() =>
            {
                let (ut, _) = self.resolve(t, &mut notices);
                self.plan(t, ut);
            }
            _ => {}
        }
        let target = self.pending.map(|p| p.target).unwrap_or(self.head.space);
        notices.clear();
        let (u, _) = self.resolve(target, &mut notices);
        if target == self.head.space {
            self.u_target = u;
        } else if let Some(p) = self.pending.as_mut() {
            p.u = u;
        }
        notices
    }

    fn plan(&mut self, target: usize, ut: f64) {
        let t0 = std::time::Instant::now();
        let m = self.motion;
        let src = &m.spaces[self.head.space];
        let opts = m.options.transition;
        // The forward trellis: the source's phase samples for the next frames.
        self.predicted.clear();
        let mut ph = self.head.phase;
        let k = src.grid();
        for _ in 0..=opts.depth {
            self.predicted.push((ph.round() as usize) % k);
            ph = src.play_phase(self.head.u, ph, 1.0).0;
        }
        let table = m.table(self.head.space, target);
        let plan = self.planner.plan(
            table,
            &self.predicted,
            self.head.u,
            ut,
            TargetState::AnyPhase,
            &[],
            m.fps,
            &opts,
        );
        let secs = t0.elapsed().as_secs_f64();
        let Some(plan) = plan else { return };
        self.transitions.push(TransitionRecord {
            from: src.name().to_owned(),
            to: m.spaces[target].name().to_owned(),
            request_frame: self.frame,
            start_frame: self.frame + plan.wait,
            end_frame: self.frame + plan.wait + opts.blend_frames,
            latency: plan.wait as f64 / m.fps,
            similarity: plan.similarity,
            cost: plan.cost,
            source_path: self.predicted[..=plan.wait].to_vec(),
            entry: plan.entry,
            decision_seconds: secs,
        });
        self.pending = Some(Pending {
            target,
            wait: plan.wait,
            entry: plan.entry,
            u: ut,
            record: self.transitions.len() - 1,
        });
    }

    /// Moves a playhead one frame: returns the root step `(x, z, dθ)` in its
    /// body frame.
    fn step_head(motion: &Motion, h: &mut Head) -> [f64; 3] {
        let (p, d) = motion.spaces[h.space].play_phase(h.u, h.phase, 1.0);
        h.phase = p;
        d
    }

    /// Plays one frame: the mesh (metres, Y-up, world placement). No
    /// allocation.
    pub fn advance(&mut self) -> &[[f64; 3]] {
        let m = self.motion;
        let fps = m.fps;
        if let Some(p) = self.pending
            && p.wait == 0
        {
            let n = m.options.transition.blend_frames;
            let target = Head {
                space: p.target,
                phase: p.entry as f64,
                u: p.u,
            };
            self.transitions[p.record].start_frame = self.frame;
            if n == 0 {
                self.head = target;
                self.u_target = p.u;
                self.transitions[p.record].end_frame = self.frame;
            } else {
                self.fade = Some((target, 0, n));
            }
            self.pending = None;
        } else if let Some(p) = self.pending.as_mut() {
            p.wait -= 1;
        }
        let space = &m.spaces[self.head.space];
        space
            .blend()
            .eval(self.head.u, self.head.phase, &mut self.local);
        let mut d = Self::step_head(m, &mut self.head);
        if let Some((mut t, done, total)) = self.fade {
            let a = (done + 1) as f64 / (total + 1) as f64;
            m.spaces[t.space]
                .blend()
                .eval(t.u, t.phase, &mut self.other);
            for (l, o) in self.local.iter_mut().zip(&self.other) {
                for c in 0..3 {
                    l[c] += (o[c] - l[c]) * a;
                }
            }
            let e = Self::step_head(m, &mut t);
            for c in 0..3 {
                d[c] += (e[c] - d[c]) * a;
            }
            if done + 1 >= total {
                self.head = t;
                self.u_target = t.u;
                self.fade = None;
                if let Some(r) = self.transitions.last_mut() {
                    r.end_frame = self.frame + 1;
                }
            } else {
                self.fade = Some((t, done + 1, total));
            }
        }
        place(&self.local, self.root, self.heading, &mut self.out);
        // Steering: a later `turn` parameter adds to the blend's own turning.
        let space = &m.spaces[self.head.space];
        let steer = match (
            space
                .parameters()
                .iter()
                .position(|p| *p == Parameter::Turn),
            self.wanted[1],
        ) {
            (Some(i), Some(v)) if i > 0 => {
                (v - space.measured_at(self.head.u)[1]).to_radians() / fps
            }
            _ => 0.0,
        };
        self.steer = steer;
        self.root += super::local::rotate(DVec2::new(d[0], d[1]), self.heading);
        self.heading += d[2] + steer;
        let du = WEIGHT_RATE / fps;
        self.head.u += (self.u_target - self.head.u).clamp(-du, du);
        self.frame += 1;
        &self.out
    }
}
