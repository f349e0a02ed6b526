//! A live session: query frames in, one character mesh per frame out, as
//! offline synthesis makes it (Huang et al. 2015, Sec. 5.2) but frame by
//! frame, on a character prepared once ([`Prepared`]).
//!
//! Per arriving frame (the stream's canonical pose, metres, Y-up, at the
//! database's rate):
//! 1. analysis: the pose kernel ([`Prepared::analyse`]) on the last
//!    `analysis_window` frames before the undecided ones and these
//!    (at most `lag`), the newest frame's result kept (the
//!    kernel levels the ground and finds the floor and the feet's support
//!    over a clip; online it sees the recent past and the undecided
//!    frames). The undecided frames take this analysis (their query and
//!    their retrieval's candidates, [`OnlineTrellis::revise`]): only the
//!    frames that left the lag keep what they were decided with;
//! 2. retrieval: [`OnlineTrellis`], which decides the frame `lag` back;
//! 3. for each decided frame: its interpolation and blend weights by the
//!    offline [`timeline`] and its placement by the offline placement, both
//!    over a window of the last `history` decided frames followed by the
//!    decoder's current continuation (at most `lag` frames; all of it at the
//!    end of the stream), then blending ([`blend_placed`]) and the
//!    part-based deformation towards the query pose.
//!
//! With `lag` and `history` at least the query's length every output frame
//! is the offline one, the stream pushed raw ([`Session::push`]: nothing is
//! decided before the end, and the last analysis is of the whole clip) or
//! analysed as a whole ([`Session::push_analysed`]); the integration test
//! `live::online` checks both. The
//! memory is bounded by `history + lag + analysis_window` frames: a stream
//! of any length runs in constant memory (the retrieval's sorted sample of
//! best-match costs, 8 bytes per frame, aside).

use super::floor::RunningFloor;
use super::ground::{OfflineGround, WindowGround};
use super::kept::KeptGround;
use super::online::{Advance, OnlineOptions, OnlineStats, OnlineTrellis};
use super::overlap::{Overlap, PairGain, cpu_since, process_cpu_seconds};
use super::stages::{FrameStages, Stage, StageClock, thread_cpu_seconds};
use crate::db::Character;
use crate::deform::resident::page_in;
use crate::deform::{DeformWorkspace, Deformer};
use crate::drive::placement::{
    BlendScratch, Floor, PlacementScratch, blend_placed, placements_into,
};
use crate::drive::timeline::{Timeline, timeline_into};
use crate::drive::trellis::TrellisInput;
use crate::drive::{Analysed, DriveOptions, Prepared};
use crate::graph::FlatFrame;
use crate::mesh::blend::{BlendWorkspace, FrameGradients};
use crate::pose::Pose;
use crate::pose::retarget::{
    ClipNeutral, ClipNeutralSource, Given, JointRotations, KernelWorkspace, Support, contact_band,
    leg_length,
};
use crate::rig::Canonical as C;
use glam::{DQuat, DVec2, DVec3};
use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Instant;

/// Options of a live session.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SessionOptions {
    /// Synthesis as offline (retrieval, timeline, placement smoothing,
    /// deformation).
    pub retarget: DriveOptions,
    /// The online retrieval's lag and hysteresis.
    pub online: OnlineOptions,
    /// Decided frames kept for the timeline and placement. Default: 64.
    pub history: usize,
    /// Frames of context, besides the undecided ones (up to `lag`), the
    /// pose kernel analyses each frame with. Default: 128 (its floor and
    /// contacts are decided over them; measured on samba 131_02 at lag 3
    /// the query's velocity error against offline's was 0.297 cm/frame
    /// over 32 frames, 0.203 over 128, 0.172 over 256).
    pub analysis_window: usize,
    /// Fraction of the difference between the last output query and the
    /// newest analysis of that frame that is given up per frame (see
    /// [`Session::push`]); 1 takes each analysis as it is. Default: 0.05.
    pub settle: f64,
    /// The most the floor the kernel stands the stream on moves per frame
    /// once frames are output (metres; [`RunningFloor`]: the window's own
    /// floor followed by at most this much a frame).
    /// `None` (the default) lets the kernel find its floor over each
    /// window. Measured (`scripts/live-fidelity.sh`, samba, lag 3, live
    /// over offline velocity error) with `Some(0.0005)`: 131_02 2.57 →
    /// 2.24, but 02_02 (a walk up a floor sloping 8 cm over 4 m) 1.70 →
    /// 2.46: not yet the default.
    pub floor_step: Option<f64>,
    /// The fraction of the vertical part of the settle's difference (its
    /// mean over the joints: the body's height, which the kernel decides
    /// over the window from the floor, the supports and the feet, and
    /// re-decides as the window slides) given up per frame; `None` (the
    /// default) gives it up at `settle` like the rest. Each frame given up
    /// is a velocity the offline motion does not have, but what is not
    /// given up leaves the body off the ground the newest analysis stands
    /// it on: measured on samba (`scripts/live-fidelity.sh`, lag 3) with
    /// 0.01, CMU 03_01's velocity error 0.517 → 0.448 cm/frame but the
    /// median penetration against the offline grounds 4.1 → 7.8 cm (the
    /// clip starts on a block the stream took for its floor, and the
    /// correction is put off past the clip's end rather than avoided):
    /// not the default.
    pub lift_settle: Option<f64>,
    /// Frames of the stream after which the levelling and the floor are
    /// decided over the window and kept ([`KeptGround`]: decided again
    /// only when the window's own floor is more than the contact band
    /// from the kept one); `None` (the default) decides both over each
    /// window. Measured (`live::decompose`, samba, the output queries'
    /// joint-velocity error against offline's, cm/frame) after 64 frames:
    /// CMU 03_01 lag 0 / 3 / 10 0.522 → 0.536, 0.442 → 0.457, 0.431 →
    /// 0.460; 131_02 lag 3 0.208 → 0.232 (`live::stream_rules`, with
    /// the open end): kept within a band (3 cm) of the window's own
    /// floor, the contacts are decided on a floor up to 3 cm off. Not the
    /// default.
    pub keep_ground: Option<usize>,
    /// Once frames are output, the window's end is the stream's newest
    /// frame ([`Given::open_end`]): a foot that has left its support and
    /// not landed counts with the floor under it, not the support it
    /// left (stepping down off a block, the support left held the body
    /// up until the landing was seen). Measured as `keep_ground`: CMU
    /// 03_01 lag 0 0.522 → 0.358, but lag 3 0.442 → 0.547 (the body
    /// dropped 8 cm in one frame where the leading foot left the block,
    /// frame 40, no longer held and not yet ramped down to its landing),
    /// lag 10 0.431 → 0.421. s26: a foot that left a step above the floor
    /// and has not landed carries the body down no faster than the
    /// window's pelvis falls fastest (the kernel's causal step-down):
    /// lag 3 0.547 → 0.443 (s24's 0.442), lag 0 0.358 as before
    /// (`live::stream_rules`). Not measured on all eight clips of the
    /// fidelity table: false (the default) as s24.
    pub open_end: bool,
    /// The two-frame overlap: when a frame ready for its deformation is
    /// held until the next one is, the two deformed at once on two threads
    /// (`rayon::join`, each with its own workspace, prepared once), then
    /// output in order ([`Overlap`]); [`Session::finish`] deforms a lone
    /// held frame. Every output frame is the one-frame path's bit for bit
    /// (the deformation carries no state from frame to frame); a held frame
    /// comes out one decided frame later ([`LiveFrame::held`]), and up to
    /// two frames are deformed in the time of one on two free cores.
    /// Default: [`Overlap::Queued`] (session 40). Its resident memory
    /// had grown after the analysis window filled (`live::long`'s looped
    /// replay: 2.7-9.1 % over the full-window sample in 19 runs of main's
    /// binary, 10 over the test's 5 %). Every slot's buffers are now grown
    /// to the other's and made resident after each deformation, on the
    /// session's thread (`Slot::even_out`,
    /// [`DeformWorkspace::keep_resident`]): 2.6-5.4 % in five runs; and the
    /// `live` verb allocates from one malloc arena (the pool threads'
    /// arenas grew at later loops' starts): 1.3-3.5 % in 20 runs, as the
    /// one-frame path's 2.3 %. README, *Live*, session 40.
    pub overlap: Overlap,
}

impl Default for SessionOptions {
    fn default() -> Self {
        SessionOptions {
            retarget: DriveOptions::default(),
            online: OnlineOptions::default(),
            history: 64,
            analysis_window: 128,
            settle: 0.05,
            floor_step: None,
            lift_settle: None,
            keep_ground: None,
            open_end: false,
            overlap: Overlap::Queued,
        }
    }
}

/// One output frame.
#[derive(Debug)]
pub struct LiveFrame<'s> {
    /// Query frame it stands for (from 0).
    pub index: usize,
    /// Database frame retrieved for it.
    pub id: FlatFrame,
    /// The character's vertices (metres, Y-up).
    pub positions: &'s [[f64; 3]],
    /// The query pose on the character's skeleton it follows.
    pub query: &'s Pose,
    /// Where the time making it went (the arriving frame's analysis and
    /// retrieval count with the first frame it outputs).
    pub stages: FrameStages,
    /// Frames pushed since the one whose push decided this frame: 1 for a
    /// frame the two-frame overlap held ([`SessionOptions::overlap`])
    /// until the next push, 0 otherwise (and for every frame
    /// [`Session::finish`] outputs).
    pub held: usize,
}

/// A frame between its blending and its output: the blend, the pose it
/// is deformed to, the result, and its own deformation workspace.
struct Slot {
    blended: Vec<[f64; 3]>,
    deformed: Vec<[f64; 3]>,
    ws: Option<DeformWorkspace>,
    target: Pose,
    index: usize,
    id: FlatFrame,
    stages: FrameStages,
    /// The session's pushes when it was decided.
    pushed: usize,
    /// Triangles its deformation left turned over.
    after: usize,
}

impl Slot {
    fn new(n: usize, ws: Option<DeformWorkspace>) -> Slot {
        let (mut blended, mut deformed) = (vec![[0.0; 3]; n], vec![[0.0; 3]; n]);
        page_in(&mut blended, true);
        page_in(&mut deformed, true);
        Slot {
            blended,
            deformed,
            ws,
            target: [DVec3::ZERO; C::COUNT],
            index: 0,
            id: FlatFrame::new(0),
            stages: FrameStages::default(),
            pushed: 0,
            after: 0,
        }
    }

    /// [`Slot::deform`] on a thread of the pool (rayon's global one, or
    /// the one the caller runs in): the deformation's parallel steps (the
    /// regions of a level, the repair's tests over the triangles) then
    /// split their work inside the pool instead of each being sent to it
    /// from outside and waited for (a wake-up and a sleep per step).
    /// Measured on the deformation bench (`part_in_pool_75_frames`, the
    /// real samba capture, CMU 02_02, 2 cores): 0.85-0.88 s against
    /// 1.02-1.13 s per 75 frames from outside the pool (issue 45).
    fn deform_in_pool(&mut self, ch: &Character, d: Option<&Deformer>) -> f64 {
        rayon::scope(|_| self.deform(ch, d))
    }

    /// Deforms the blend towards the target (with `d`, when the character
    /// deforms); returns this thread's CPU seconds spent.
    fn deform(&mut self, ch: &Character, d: Option<&Deformer>) -> f64 {
        let began = thread_cpu_seconds();
        if let (Some(d), Some(ws)) = (d, self.ws.as_mut()) {
            let sp = ch.rig().frame_joints(&self.blended);
            let c = d.deform(ch, &self.blended, &sp, &self.target, &mut self.deformed, ws);
            self.after = c.after;
            self.stages.repaired = c.before > 0;
            self.stages.repair_work = ws.repair_work();
        }
        match (began, thread_cpu_seconds()) {
            (Some(a), Some(b)) => (b - a).max(0.0),
            _ => 0.0,
        }
    }

    /// After a deformation, on the session's thread: each slot's
    /// fold-repair buffers grown to the other's capacities
    /// ([`DeformWorkspace::reserve_as`]) and every workspace's buffers
    /// made resident where they grew ([`DeformWorkspace::keep_resident`]).
    /// So both slots hold the largest patch either has met, in resident
    /// memory, from the frame that met it on — not grown or paged in by a
    /// later pair on a pool thread (session 39, heaptrack: the second
    /// slot's 8.9 MiB grew after the analysis window filled; a reserved
    /// buffer's pages are resident only once written). O(buffers) when
    /// nothing grew.
    fn even_out(slots: &mut [Slot]) {
        match slots {
            [a, b] => {
                if let (Some(wa), Some(wb)) = (a.ws.as_mut(), b.ws.as_mut()) {
                    wa.reserve_as(wb);
                    wb.reserve_as(wa);
                }
            }
            [a] => {
                if let Some(w) = a.ws.as_mut() {
                    w.keep_resident();
                }
            }
            _ => {}
        }
    }

    /// The frame's vertices: deformed when it has a workspace.
    fn positions(&self) -> &[[f64; 3]] {
        match self.ws {
            Some(_) => &self.deformed,
            None => &self.blended,
        }
    }
}

/// The state of a live session.
pub struct Session<'a> {
    ch: &'a Character,
    prepared: &'a Prepared,
    opts: SessionOptions,
    reference: ClipNeutral,
    trellis: OnlineTrellis<'a>,
    /// The last `analysis_window + lag` raw frames, and their file joints'
    /// rotations when the stream gives them (one per raw frame).
    raw: VecDeque<Pose>,
    raw_rotations: VecDeque<Option<JointRotations>>,
    /// Raw frames received ([`Session::push`]).
    received: usize,
    /// The analysed pelvis (x, z) of each raw frame but the newest, on the
    /// stream's own root trajectory (see [`Session::push`]).
    roots: VecDeque<DVec2>,
    /// Query poses (on the character) from frame `query_start` on.
    query: VecDeque<Pose>,
    query_start: usize,
    /// The newest analysis of the raw window's frames (on the stream's
    /// trajectory), from frame `latest_start` on; empty when the frames
    /// come analysed ([`Session::push_analysed`]).
    latest: Vec<Pose>,
    latest_start: usize,
    /// The query of the last output frame (its index, the pose).
    last_out: Option<(usize, Pose)>,
    /// Decided frames from `path_start` on (at most `history + 1`).
    path: VecDeque<FlatFrame>,
    path_start: usize,
    blend_ws: BlendWorkspace,
    buf: Vec<[f64; 3]>,
    grads: Vec<FrameGradients>,
    /// One frame's blend, deformation and workspace; two with the
    /// two-frame overlap ([`SessionOptions::overlap`]).
    slots: Vec<Slot>,
    /// The slot of a frame held for the overlap's next frame.
    held: Option<usize>,
    /// The stream's next arrival is already waiting ([`Overlap::Queued`]).
    waiting: bool,
    /// The pairs' measured gain ([`Overlap::Queued`]).
    gain: PairGain,
    /// Frames pushed ([`Session::push`], [`Session::push_analysed`]).
    pushes: usize,
    turned_over: usize,
    /// The running floor estimate (when `floor_step` is given).
    floor: Option<RunningFloor>,
    /// The kept levelling and floor (when `keep_ground` is given), and
    /// the stream's contact band (the clip's metres).
    kept: Option<KeptGround>,
    band: f64,
    /// Ground decisions taken from the offline analysis of the clip being
    /// replayed ([`Session::swap_in`]).
    offline: Option<OfflineGround>,
    /// The stage clock of the frame being made and its times so far.
    clock: StageClock,
    stages: FrameStages,
    /// The pose kernel's buffers, reused by every frame's analysis
    /// (issue 45: no allocation in its clip-level steps per frame).
    kernel_ws: KernelWorkspace,
    /// The placement's window (decided frames and the continuation), its
    /// queries, buffers and result, reused by every frame.
    place: PlaceBuffers,
    /// The newest analysis (the pose kernel's run over the window),
    /// refilled by every push (issue 45).
    analysed: Analysed,
    /// The analysis window's rotations (one per raw frame when every
    /// frame has them, else none), updated in place while the window's
    /// length stays (issue 45); the kernel reads them as the window's
    /// [`ClipNeutral::rotations`].
    rotations: Arc<[JointRotations]>,
    /// The retrieval's last step and the frames it decided followed by
    /// its continuation, refilled by every push (issue 45).
    advance: Advance,
    ids: Vec<FlatFrame>,
}

/// The buffers of an output frame's placement over its window
/// ([`Session::blend_into`]), reused from frame to frame (issue 45).
#[derive(Default)]
struct PlaceBuffers {
    window: Vec<FlatFrame>,
    queries: Vec<Pose>,
    timeline: Timeline,
    scratch: PlacementScratch,
    placed: Vec<Floor>,
}

impl<'a> Session<'a> {
    /// A session on `ch` prepared as `prepared`, retrieving from `input`
    /// (the character's trellis input), the stream's neutral pose being
    /// `reference`.
    pub fn new(
        ch: &'a Character,
        prepared: &'a Prepared,
        input: &'a TrellisInput<'a>,
        reference: ClipNeutral,
        opts: SessionOptions,
    ) -> Self {
        let n = ch.n();
        let mut slots: Vec<Slot> = (0..if opts.overlap == Overlap::Off { 1 } else { 2 })
            .map(|_| Slot::new(n, prepared.deformer().map(|d| d.workspace())))
            .collect();
        Slot::even_out(&mut slots);
        let band = contact_band(leg_length(&reference.pose));
        // The window's and the history's lengths, reserved once so that
        // filling them does not grow them push by push.
        let window = opts.analysis_window.max(1) + opts.online.lag;
        let history = opts.history.max(1) + opts.online.lag + 2;
        let mut s = Session {
            ch,
            prepared,
            opts,
            reference,
            trellis: OnlineTrellis::new(input, opts.retarget.trellis, opts.online),
            raw: VecDeque::with_capacity(window),
            raw_rotations: VecDeque::with_capacity(window),
            received: 0,
            roots: VecDeque::with_capacity(window),
            query: VecDeque::with_capacity(history),
            query_start: 0,
            latest: Vec::with_capacity(window),
            latest_start: 0,
            last_out: None,
            path: VecDeque::with_capacity(history),
            path_start: 0,
            blend_ws: prepared.blender().workspace(),
            buf: vec![[0.0; 3]; n],
            grads: vec![FrameGradients::default(); 4],
            slots,
            held: None,
            waiting: false,
            gain: PairGain::default(),
            pushes: 0,
            turned_over: 0,
            floor: opts.floor_step.map(RunningFloor::new),
            kept: opts.keep_ground.map(KeptGround::new),
            band,
            offline: None,
            clock: StageClock::start(),
            stages: FrameStages::default(),
            kernel_ws: KernelWorkspace::new(),
            place: PlaceBuffers::default(),
            analysed: Analysed::default(),
            rotations: Arc::from(Vec::new()),
            advance: Advance::default(),
            ids: Vec::new(),
        };
        s.size_analysis(window);
        s
    }

    /// Grows the pose kernel's buffers and the analysis to a full window
    /// once, by analysing `window` frames of the stream's neutral pose
    /// (a body standing still), so the window filling frame by frame does
    /// not grow them push by push (issue 45). Its result is left in
    /// `analysed`, which every push refills before reading.
    fn size_analysis(&mut self, window: usize) {
        let still = vec![self.reference.pose; window];
        let reference = ClipNeutral {
            pose: self.reference.pose,
            source: ClipNeutralSource::Frame(usize::MAX),
            rotations: Arc::clone(&self.rotations),
        };
        let stream = Stream {
            floor: None,
            kept: None,
            open_end: false,
        };
        let ws = (&mut self.kernel_ws, &mut self.analysed);
        analyse(
            self.prepared,
            self.ch,
            &reference,
            &still,
            (&stream, &WindowGround::default()),
            ws,
        );
    }

    /// Makes the analysis of every window take the ground decisions
    /// `offline` swaps in (the offline analysis's of the clip this session
    /// is pushed, frame for frame from its first): where live loses to
    /// offline, one decision at a time (issue 45's decomposition).
    pub fn swap_in(&mut self, offline: OfflineGround) {
        self.offline = Some(offline);
    }

    /// The retrieval's counts.
    pub fn stats(&self) -> OnlineStats {
        self.trellis.stats()
    }

    /// The bytes the deformation workspaces hold (their buffers'
    /// capacities): the whole-step allocation test tells a buffer grown
    /// to a larger repair than met before from a per-frame allocation.
    #[cfg(test)]
    pub(crate) fn deform_capacity(&mut self) -> usize {
        use crate::deform::resident::Resident;
        let ws = self.slots.iter_mut().filter_map(|s| s.ws.as_mut());
        ws.map(|w| w.resident(false)).sum()
    }

    /// Triangle-frames the deformation left turned over (after repair).
    pub fn turned_over(&self) -> usize {
        self.turned_over
    }

    /// Tells the session whether the stream's next arrival is already
    /// waiting (before a push): with [`Overlap::Queued`] a frame is held
    /// for its partner only then.
    pub fn set_waiting(&mut self, waiting: bool) {
        self.waiting = waiting;
    }

    /// Analyses the stream's next pose (`raw`: its canonical joints, metres,
    /// Y-up; `rotations`: its file joints' world rotations, when known, which
    /// turn the chest as offline) and hands every frame it lets the session
    /// decide to `out`.
    pub fn push(
        &mut self,
        raw: &Pose,
        rotations: Option<&JointRotations>,
        out: &mut dyn FnMut(LiveFrame<'_>),
    ) {
        self.clock = StageClock::start();
        self.stages = FrameStages::default();
        self.pushes += 1;
        // The window holds every undecided frame besides its context.
        let w = self
            .opts
            .analysis_window
            .max(1)
            .saturating_add(self.opts.online.lag);
        if self.raw.len() >= w {
            self.raw.pop_front();
            self.raw_rotations.pop_front();
            self.roots.pop_front();
        }
        self.raw.push_back(*raw);
        self.raw_rotations.push_back(rotations.copied());
        self.received += 1;
        let from_start = self.received == self.raw.len();
        window_rotations(&self.raw_rotations, &mut self.rotations);
        let reference = ClipNeutral {
            pose: self.reference.pose,
            // A reference frame of the stream is the window's frame of the
            // same index only while the window starts at the stream's first
            // frame (the kernel reads `Frame(i)` as the window's frame i);
            // then the reference's pose stands for it.
            source: match self.reference.source {
                ClipNeutralSource::Frame(_) if !from_start => ClipNeutralSource::Frame(usize::MAX),
                s => s,
            },
            rotations: Arc::clone(&self.rotations),
        };
        let decided = self.path_start + self.path.len() > 0;
        let first_frame = self.received - self.raw.len();
        let window = self.raw.make_contiguous();
        let floor = running_floor(self.floor.as_mut(), decided, window);
        let kept = self
            .kept
            .as_mut()
            .and_then(|k| k.update(window, self.received, !decided, self.band));
        let swapped = self
            .offline
            .as_ref()
            .map(|o| o.window(first_frame, window.len()))
            .unwrap_or_default();
        let stream = Stream {
            floor,
            kept,
            open_end: self.opts.open_end && decided,
        };
        let a = &mut self.analysed;
        let ws = &mut self.kernel_ws;
        analyse(
            self.prepared,
            self.ch,
            &reference,
            window,
            (&stream, &swapped),
            (ws, a),
        );
        drop(reference);
        let a = &self.analysed;
        let (Some(first), Some(q), Some(f)) = (a.query.first(), a.query.last(), a.on_floor.last())
        else {
            return;
        };
        // The kernel moves the root by the clip's pelvis since the clip's
        // first frame, here the window's: the window's first frame is put
        // back where it stood on the stream's trajectory (as analysed when
        // it was the newest), and the newest frame moved with it.
        let p = C::Pelvis.index();
        let shift = match self.roots.front() {
            Some(r) => *r - DVec2::new(first[p].x, first[p].z),
            None => DVec2::ZERO,
        };
        let by = DVec3::new(shift.x, 0.0, shift.y);
        let (q, f) = (q.map(|x| x + by), f.map(|x| x + by));
        self.roots.push_back(DVec2::new(q[p].x, q[p].z));
        // Every frame of the window as this analysis sees it (the frames
        // not yet output take it: it has more of their future).
        let newest = self.query_start + self.query.len();
        self.latest_start = newest + 1 - a.query.len();
        self.latest.clear();
        self.latest
            .extend(a.query.iter().map(|x| x.map(|x| x + by)));
        let undecided = self.trellis.pending();
        let from = self.query.len() - undecided.min(self.query.len());
        for (i, slot) in self.query.iter_mut().enumerate().skip(from) {
            if let Some(l) = (self.query_start + i)
                .checked_sub(self.latest_start)
                .and_then(|w| self.latest.get(w))
            {
                *slot = *l;
            }
        }
        // The undecided frames are retrieved on this analysis too: only
        // the frames that left the lag keep what they were decided with.
        for j in 0..undecided {
            let stream = newest - undecided + j;
            if let Some(f) = stream
                .checked_sub(self.latest_start)
                .and_then(|w| a.on_floor.get(w))
            {
                self.trellis.revise(j, &f.map(|x| x + by));
            }
        }
        self.clock.lap(Stage::Analysis, &mut self.stages);
        self.push_analysed_timed(&q, &f, out);
    }

    /// The query frame `k` is output with: its newest analysis, plus what
    /// the previous output frame's query differed from that analysis's
    /// view of it, less the `settle` fraction. Each stream frame is
    /// analysed again as the window slides (the kernel's ground, support
    /// and root height are decided over the window); this keeps the
    /// output's motion that of one analysis from frame to frame and lets
    /// the difference die away instead of jumping.
    fn settled(&self, k: usize, query: Pose) -> Pose {
        let view = |i: usize| {
            i.checked_sub(self.latest_start)
                .and_then(|w| self.latest.get(w))
        };
        match (&self.last_out, view(k), k.checked_sub(1).and_then(view)) {
            (Some((j, prev)), Some(_), Some(seen)) if *j + 1 == k => {
                let keep = 1.0 - self.opts.settle.clamp(0.0, 1.0);
                match self.opts.lift_settle {
                    None => std::array::from_fn(|i| query[i] + (prev[i] - seen[i]) * keep),
                    Some(l) => {
                        let keep_lift = 1.0 - l.clamp(0.0, 1.0);
                        settled_apart(&query, prev, seen, keep, keep_lift)
                    }
                }
            }
            _ => query,
        }
    }

    /// Takes the next frame already analysed (`query` on the character,
    /// `on_floor` with the stance height taken off, as in
    /// [`crate::drive::Analysed`]).
    pub fn push_analysed(
        &mut self,
        query: &Pose,
        on_floor: &Pose,
        out: &mut dyn FnMut(LiveFrame<'_>),
    ) {
        self.clock = StageClock::start();
        self.stages = FrameStages::default();
        self.pushes += 1;
        self.push_analysed_timed(query, on_floor, out);
    }

    /// [`Session::push_analysed`] on the running stage clock.
    fn push_analysed_timed(
        &mut self,
        query: &Pose,
        on_floor: &Pose,
        out: &mut dyn FnMut(LiveFrame<'_>),
    ) {
        self.query.push_back(*query);
        self.trellis.push_into(on_floor, &mut self.advance);
        self.clock.lap(Stage::Retrieval, &mut self.stages);
        self.emit(out);
    }

    /// Decides and outputs every frame still pending (the stream ended).
    pub fn finish(&mut self, out: &mut dyn FnMut(LiveFrame<'_>)) {
        self.clock = StageClock::start();
        self.stages = FrameStages::default();
        self.trellis.finish_into(&mut self.advance);
        self.clock.lap(Stage::Retrieval, &mut self.stages);
        self.emit(out);
        // A lone frame the overlap holds has no partner coming.
        if let Some(h) = self.held.take() {
            self.clock = StageClock::start();
            let (ch, d) = (self.ch, self.prepared.deformer());
            self.slots[h].deform_in_pool(ch, d);
            self.clock
                .lap(Stage::Deformation, &mut self.slots[h].stages);
            Slot::even_out(&mut self.slots);
            self.slots[h].pushed = self.pushes;
            self.output(h, out);
        }
    }

    /// Makes and outputs the frames the retrieval's last step decided
    /// (kept in `advance`).
    fn emit(&mut self, out: &mut dyn FnMut(LiveFrame<'_>)) {
        // Taken while the frames are made (no allocation), put back after.
        let adv = std::mem::take(&mut self.advance);
        let mut ids = std::mem::take(&mut self.ids);
        ids.clear();
        ids.extend(adv.committed.iter().map(|c| c.id));
        ids.extend(adv.lookahead.iter().copied());
        for (i, c) in adv.committed.iter().enumerate() {
            self.path.push_back(c.id);
            let ahead = &ids[i + 1..ids.len().min(i + 1 + self.opts.history.max(1))];
            let more = i + 1 < adv.committed.len();
            self.frame(c.index, c.id, ahead, more, out);
            // Keep `history` decided frames (and their query poses).
            while self.path.len() > self.opts.history.max(1) {
                self.path.pop_front();
                self.path_start += 1;
            }
            while self.query_start < self.path_start {
                self.query.pop_front();
                self.query_start += 1;
            }
        }
        (self.advance, self.ids) = (adv, ids);
    }

    /// Makes output frame `k` (decided as `id`; `ahead`, the continuation):
    /// blends it, then deforms and outputs it, or with the two-frame
    /// overlap holds it for the next frame (`more`: another frame of this
    /// push follows), or deforms it with the held one and outputs both in
    /// order.
    fn frame(
        &mut self,
        k: usize,
        id: FlatFrame,
        ahead: &[FlatFrame],
        more: bool,
        out: &mut dyn FnMut(LiveFrame<'_>),
    ) {
        let s = self.held.map_or(0, |h| 1 - h);
        self.blend_into(k, ahead, s);
        let slot = &mut self.slots[s];
        (slot.index, slot.id, slot.pushed) = (k, id, self.pushes);
        slot.stages = std::mem::take(&mut self.stages);
        let (ch, d) = (self.ch, self.prepared.deformer());
        let hold = match self.opts.overlap {
            Overlap::Off => false,
            Overlap::Queued => (more || self.waiting) && self.gain.worth_holding(),
            Overlap::Always => true,
        };
        match self.held.take() {
            None if hold && self.slots.len() > 1 => {
                self.held = Some(s);
            }
            None => {
                let (began, cpu) = (Instant::now(), process_cpu_seconds());
                self.slots[s].deform_in_pool(ch, d);
                self.gain.single(began.elapsed(), cpu_since(cpu));
                self.clock
                    .lap(Stage::Deformation, &mut self.slots[s].stages);
                Slot::even_out(&mut self.slots);
                self.output(s, out);
            }
            Some(h) => {
                let (a, b) = match &mut self.slots[..] {
                    [x, y] if h == 0 => (x, y),
                    [x, y] => (y, x),
                    _ => unreachable!("a frame is held only with two slots"),
                };
                let (began, cpu) = (Instant::now(), process_cpu_seconds());
                let (ta, tb) = rayon::join(|| a.deform(ch, d), || b.deform(ch, d));
                self.gain.pair(began.elapsed(), cpu_since(cpu));
                let share = if ta + tb > 0.0 { ta / (ta + tb) } else { 0.5 };
                self.clock
                    .lap_pair(Stage::Deformation, &mut a.stages, &mut b.stages, share);
                Slot::even_out(&mut self.slots);
                self.output(h, out);
                self.output(s, out);
            }
        }
        // The next frame of this arrival starts after the output.
        self.clock = StageClock::start();
    }

    /// Outputs the frame in slot `s`.
    fn output(&mut self, s: usize, out: &mut dyn FnMut(LiveFrame<'_>)) {
        self.turned_over += self.slots[s].after;
        let pushes = self.pushes;
        let slot = &mut self.slots[s];
        let stages = std::mem::take(&mut slot.stages);
        let slot = &self.slots[s];
        out(LiveFrame {
            index: slot.index,
            id: slot.id,
            positions: slot.positions(),
            query: &slot.target,
            stages,
            held: pushes - slot.pushed,
        });
    }

    /// Settles output frame `k`'s query, times and places it over the
    /// decided history and `ahead`, and blends it into slot `s` (its
    /// target set); the stages timed into the session's.
    fn blend_into(&mut self, k: usize, ahead: &[FlatFrame], s: usize) {
        let ch = self.ch;
        let h = k - self.path_start;
        if let Some(&q) = self.query.get(k - self.query_start) {
            let q = self.settled(k, q);
            self.query[k - self.query_start] = q;
            self.last_out = Some((k, q));
        }
        let pl = &mut self.place;
        pl.window.clear();
        pl.window
            .extend(self.path.iter().copied().chain(ahead.iter().copied()));
        pl.queries.clear();
        pl.queries.extend(
            self.query
                .iter()
                .skip(self.path_start - self.query_start)
                .take(pl.window.len())
                .copied(),
        );
        let window = &pl.window[..pl.queries.len()];
        timeline_into(window, ch, &self.opts.retarget.timeline, &mut pl.timeline);
        let frames = &pl.timeline.out;
        let smooth = self.opts.retarget.smooth;
        let within = (window, &frames[..], &pl.queries[..]);
        placements_into(ch, within, smooth, &mut pl.scratch, &mut pl.placed);
        self.clock.lap(Stage::Placement, &mut self.stages);
        let o = self.place.timeline.out[h];
        let primary = o.primary();
        let mut scratch = BlendScratch {
            ws: &mut self.blend_ws,
            buf: &mut self.buf,
            grads: &mut self.grads,
        };
        let slot = &mut self.slots[s];
        blend_placed(
            ch,
            self.prepared.blender(),
            o.used(),
            primary,
            self.place.placed[h],
            |f| f == primary,
            &mut scratch,
            &mut slot.blended,
        );
        slot.target = self.place.queries[h];
        self.clock.lap(Stage::Blending, &mut self.stages);
    }
}

/// The floor the kernel stands the raw `window` on: `running`'s estimate
/// once a frame has been `decided` (before, none is output and the
/// kernel's own floor over the window, all the frames seen while it
/// starts at the stream's first, stands: a lag covering the stream keeps
/// the offline result bit for bit).
fn running_floor(
    running: Option<&mut RunningFloor>,
    decided: bool,
    window: &[Pose],
) -> Option<f64> {
    let e = running?.update(window, !decided);
    if decided { e } else { None }
}

/// What the session decides for the pose kernel over a window.
struct Stream {
    /// The running floor (when given).
    floor: Option<f64>,
    /// The kept levelling and floor (when kept).
    kept: Option<(DQuat, f64)>,
    /// The window ends at the stream's newest frame ([`Given::open_end`]).
    open_end: bool,
}

/// The window's rotations into `kept` (one per raw frame when every
/// frame of `raw` has them, else none): written in place while the
/// length stays and nothing else holds them (the last analysis's
/// reference is gone by the next push), so a full window allocates
/// nothing; one new `Arc` a push while the window fills.
fn window_rotations(raw: &VecDeque<Option<JointRotations>>, kept: &mut Arc<[JointRotations]>) {
    let n = if raw.iter().all(Option::is_some) {
        raw.len()
    } else {
        0
    };
    match Arc::get_mut(kept) {
        Some(k) if k.len() == n => {
            for (k, r) in k.iter_mut().zip(raw.iter().flatten()) {
                *k = *r;
            }
        }
        // From an iterator of known length (a range mapped), so the `Arc`
        // is one allocation of exactly `n`: a flattened iterator was
        // collected into a `Vec` first, doubling as it went (issue 45: 7
        // allocation calls a push while a 128-frame window filled).
        _ => *kept = (0..n).map(|i| raw[i].unwrap_or([None; C::COUNT])).collect(),
    }
}

/// The pose kernel over the raw `window` on what the `stream` decides
/// and with what `swapped` takes from the offline analysis (first), in
/// the session's buffers `ws`, into the session's `out`.
fn analyse(
    prepared: &Prepared,
    ch: &Character,
    reference: &ClipNeutral,
    window: &[Pose],
    (stream, swapped): (&Stream, &WindowGround),
    (ws, out): (&mut KernelWorkspace, &mut Analysed),
) {
    let replace = |_: &[Pose], s: &mut Support| {
        if let Some(o) = &swapped.support {
            *s = o.clone();
        }
    };
    let given = Given {
        tilt: swapped.tilt.or(stream.kept.map(|k| k.0)),
        floor: swapped.floor.or(stream.kept.map(|k| k.1)).or(stream.floor),
        support: swapped
            .support
            .as_ref()
            .map(|_| &replace as &dyn Fn(&[Pose], &mut Support)),
        open_end: stream.open_end,
    };
    prepared.analyse_into(ch, reference, window, (&given, ws), out);
}

/// `query` settled from the previous output frame `prev` and this
/// analysis's view of it `seen`: their difference kept by `keep`, but its
/// vertical part common to all joints (the body's lift) by `keep_lift`.
fn settled_apart(query: &Pose, prev: &Pose, seen: &Pose, keep: f64, keep_lift: f64) -> Pose {
    let n = query.len().max(1) as f64;
    let lift = (0..query.len()).map(|i| prev[i].y - seen[i].y).sum::<f64>() / n;
    std::array::from_fn(|i| {
        let mut d = prev[i] - seen[i];
        d.y -= lift;
        query[i] + d * keep + DVec3::Y * (lift * keep_lift)
    })
}
