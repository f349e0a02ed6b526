//! `jobs::live`: live retargeting (issue 45) — a stream of mocap frames
//! drives the character through the online path ([`crate::live`]) on a
//! character prepared once, each mesh handed on as soon as it is made,
//! optionally recorded to any sequence format when the stream ends.

use crate::db::{BuildProgress, Character};
use crate::deform::{DeformOptions, RepairBudget};
use crate::drive::query::{QueryError, load_mocap};
use crate::drive::trellis::DatabaseLinks;
use crate::drive::{DriveError, DriveOptions, Prepared};
use crate::live::bvh_tcp;
use crate::live::online::{OnlineOptions, OnlineStats};
use crate::live::overlap::Overlap;
use crate::live::page::{Meta, PageFrame, PageServer};
use crate::live::replay::Replay;
use crate::live::report::{Counters, Latencies, LatencySummary, Sample, resident_mib};
use crate::live::rokoko::{ActorChoice, Rokoko};
use crate::live::session::{LiveFrame, Session, SessionOptions};
use crate::live::source::{Event, Source, SourceError};
use crate::live::stages::{StageReport, StageTally};
use crate::live::stream;
use crate::live::vmc::Vmc;
use crate::mesh::io::glb::GlbOptions;
use crate::mesh::io::usd::UsdOptions;
use crate::pose::Pose;
use crate::rig::LoadOptions;
use serde::Serialize;
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Options of [`run_live`] (the defaults are the CLI's).
#[derive(Debug, Clone)]
pub struct LiveOptions {
    /// Synthesis (retrieval, timeline, placement, deformation) as offline,
    /// but for the fold repair's budget. Default: offline's with
    /// [`RepairBudget::LIVE`] (a frame's repair bounded, so it meets the
    /// frame's deadline; [`RepairBudget::NONE`] gives offline's meshes).
    pub retarget: DriveOptions,
    /// Frames of future before a frame is decided. Default: 3.
    pub lag: usize,
    /// Extra cost of a jump at lag 0. Default: 1.
    pub hysteresis: f64,
    /// Decided frames kept for blending and placement. Default: 64.
    pub history: usize,
    /// Frames of context the pose kernel analyses each frame with,
    /// besides the undecided ones (up to `lag`). Default: 128.
    pub analysis_window: usize,
    /// The most the running floor given to the pose kernel moves per frame
    /// (metres; `live::floor`); `None` (the default): the kernel finds its
    /// floor over each window.
    pub floor_step: Option<f64>,
    /// The settle of the body's lift ([`SessionOptions::lift_settle`]).
    /// Default: the session's.
    pub lift_settle: Option<f64>,
    /// Frames after which the levelling and floor are kept
    /// ([`SessionOptions::keep_ground`]). Default: the session's.
    pub keep_ground: Option<usize>,
    /// The window's end is the stream's newest frame
    /// ([`SessionOptions::open_end`]). Default: the session's.
    pub open_end: bool,
    /// A replay's speed (1: the clip's real rate; 0: as fast as frames are
    /// made). Default: 1.
    pub speed: f64,
    /// How a replayed clip is read (rig map, units...). Default: detected.
    pub load: LoadOptions,
    /// Stop after this many seconds of streaming. Default: none.
    pub seconds: Option<f64>,
    /// End the session when no frame came for this many seconds (after
    /// the first). Default: none (a network stream waits for its sender).
    pub until_idle: Option<f64>,
    /// Keep every network frame in order instead of the newest winning
    /// (for recordings and tests; latency grows when the session is slower
    /// than the stream). Default: false.
    pub lossless: bool,
    /// Serve the browser page (the character and the incoming skeleton,
    /// streamed over a WebSocket) on this address. Default: none.
    pub serve: Option<std::net::SocketAddr>,
    /// Times a replayed clip is played (the stream goes on across the
    /// loops). Default: 1.
    pub loops: usize,
    /// Sample the rate, latency and resident memory every this many
    /// seconds into the report. Default: none.
    pub sample_every: Option<f64>,
    /// The Rokoko actor that drives the character. Default: the first.
    pub actor: ActorChoice,
    /// A GLB recording's options. Default: [`GlbOptions::DEFAULT`].
    pub glb: GlbOptions,
    /// A `.usda` recording's options. Default: [`UsdOptions::DEFAULT`]
    /// (normals on).
    pub usd: UsdOptions,
    /// When to deform two frames at once ([`SessionOptions::overlap`]).
    /// Default: the session's ([`Overlap::Queued`]).
    pub overlap: Overlap,
}

impl Default for LiveOptions {
    fn default() -> Self {
        LiveOptions {
            retarget: DriveOptions {
                deform_options: DeformOptions {
                    repair_budget: RepairBudget::LIVE,
                    ..Default::default()
                },
                ..Default::default()
            },
            lag: 3,
            hysteresis: 1.0,
            history: 64,
            analysis_window: 128,
            floor_step: None,
            lift_settle: SessionOptions::default().lift_settle,
            keep_ground: SessionOptions::default().keep_ground,
            open_end: SessionOptions::default().open_end,
            speed: 1.0,
            load: LoadOptions::default(),
            seconds: None,
            until_idle: None,
            lossless: false,
            serve: None,
            loops: 1,
            sample_every: None,
            actor: ActorChoice::default(),
            glb: GlbOptions::DEFAULT,
            usd: UsdOptions::DEFAULT,
            overlap: SessionOptions::default().overlap,
        }
    }
}

/// Where the stream comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum LiveInput {
    /// A clip file played at its rate.
    Replay(PathBuf),
    /// BVH over TCP, listening on the address.
    BvhTcp(std::net::SocketAddr),
    /// The VMC protocol (OSC over UDP), listening on the address.
    Vmc(std::net::SocketAddr),
    /// Rokoko Studio Live (JSON over UDP), listening on the address.
    Rokoko(std::net::SocketAddr),
}

impl LiveInput {
    /// What the input is, for messages ("BVH over TCP", ...).
    pub fn protocol(&self) -> &'static str {
        use crate::live::stream::Protocol;
        match self {
            LiveInput::Replay(_) => "a replayed clip",
            LiveInput::BvhTcp(_) => "BVH over TCP",
            LiveInput::Vmc(_) => crate::live::vmc::Vmc::NAME,
            LiveInput::Rokoko(_) => crate::live::rokoko::Rokoko::NAME,
        }
    }
}

/// What a session listens on, as it starts.
#[derive(Debug, Clone, PartialEq)]
pub enum Listening {
    /// The stream's address (a network input).
    Stream(std::net::SocketAddr),
    /// The browser page's URL (`serve`).
    Page(String),
}

/// The browser page on `opts.serve`, if asked for.
fn start_page(
    opts: &LiveOptions,
    prepared: &Prepared,
    fps: f64,
    listening: &mut dyn FnMut(Listening),
) -> Result<Option<PageServer>, LiveError> {
    let Some(addr) = opts.serve else {
        return Ok(None);
    };
    let mesh = prepared.topology_metres();
    let (joints, parents) = crate::live::page::skeleton();
    let meta = Meta {
        vertices: mesh.vertex_count(),
        triangles: mesh.triangles().iter().flatten().copied().collect(),
        fps,
        lag: opts.lag,
        joints,
        parents,
    };
    let page = PageServer::start(addr, &meta)?;
    listening(Listening::Page(page.url().to_string()));
    Ok(Some(page))
}

/// The Rokoko actors' names seen by a source (shared with its thread).
type ActorsSeen = Option<std::sync::Arc<std::sync::Mutex<Vec<String>>>>;

/// The stream `input` names, taken at `fps`; a network source's address
/// told to `listening`; the actors seen, for Rokoko.
fn open_source(
    input: &LiveInput,
    opts: &LiveOptions,
    fps: f64,
    listening: &mut dyn FnMut(Listening),
) -> Result<(Box<dyn Source>, ActorsSeen), LiveError> {
    let mut seen = None;
    let (load, lossless) = (opts.load.clone(), opts.lossless);
    let (source, addr): (Box<dyn Source>, _) = match input {
        LiveInput::Replay(clip) => (
            Box::new(Replay::new(
                load_mocap(clip, &opts.load, fps)?,
                opts.speed,
                opts.loops,
            )),
            None,
        ),
        network => {
            let s = match network {
                LiveInput::BvhTcp(addr) => bvh_tcp::listen(*addr, fps, load, lossless)?,
                LiveInput::Vmc(addr) => stream::listen(*addr, Vmc::default(), fps, load, lossless)?,
                LiveInput::Rokoko(addr) => {
                    let r = Rokoko::new(opts.actor.clone());
                    seen = Some(r.seen());
                    stream::listen(*addr, r, fps, load, lossless)?
                }
                LiveInput::Replay(_) => unreachable!("matched above"),
            };
            let a = s.local_addr();
            (Box::new(s), Some(a))
        }
    };
    if let Some(a) = addr {
        listening(Listening::Stream(a));
    }
    Ok((source, seen))
}

/// What can go wrong in [`run_live`].
#[derive(Debug, thiserror::Error)]
pub enum LiveError {
    /// The database could not be read or built.
    #[error(transparent)]
    Db(#[from] crate::db::DbError),
    /// A replayed clip could not be read.
    #[error(transparent)]
    Query(#[from] QueryError),
    /// The character could not be prepared.
    #[error(transparent)]
    Retarget(#[from] DriveError),
    /// The stream failed.
    #[error(transparent)]
    Source(#[from] SourceError),
    /// The recording could not be written.
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    /// The recording does not fit the character's topology.
    #[error(transparent)]
    Topology(#[from] crate::mesh::TopologyError),
    /// The browser page could not be served.
    #[error(transparent)]
    Page(#[from] crate::live::page::PageError),
    /// The stream gave no frame to decide its neutral pose from.
    #[error("the stream ended before its skeleton was known")]
    NoReference,
}

/// One output frame as [`run_live`] hands it on.
pub struct FrameOut<'a> {
    /// The frame itself.
    pub frame: LiveFrame<'a>,
    /// The incoming skeleton it answers (the stream's joints, metres, Y-up).
    pub incoming: &'a Pose,
    /// Milliseconds from the arrival of the frame that let it be decided
    /// to its mesh being ready.
    pub latency_ms: f64,
    /// Output frames per second since the first frame arrived.
    pub output_fps: f64,
}

/// The report of a live session.
#[derive(Debug, Clone, Serialize)]
pub struct LiveReport {
    /// The database's frame rate (the stream's, resampled).
    pub fps: f64,
    /// Vertices of the character.
    pub vertices: usize,
    /// The lag (frames).
    pub lag: usize,
    /// Frames output.
    pub frames_out: u64,
    /// Output frames per second over the streaming time.
    pub output_fps: f64,
    /// Seconds from the first frame's arrival to the last mesh.
    pub seconds: f64,
    /// Seconds preparing the character (once).
    pub prepare_seconds: f64,
    /// Arrival (of the frame that let a frame be decided) to mesh ready.
    pub latency: LatencySummary,
    /// Milliseconds making each mesh (analysis to deformation), median.
    pub work_median_ms: f64,
    /// Milliseconds making each mesh, mean (the stages' means add up to it).
    pub work_mean_ms: f64,
    /// Where each mesh's time went, stage by stage (wall and CPU).
    pub stages: StageReport,
    /// Milliseconds handing each mesh on after it is ready (recording it,
    /// the page, the caller): not in the latency, but in the frame rate.
    pub output: LatencySummary,
    /// The incoming frames: received, dropped, duplicated, late, malformed.
    pub input: Counters,
    /// The retrieval: frames decided, jumps, cuts, widened, the scales.
    pub retrieval: OnlineStats,
    /// Triangle-frames left turned over by the deformation (after its
    /// repair; what the budget cost shows here).
    pub turned_over: usize,
    /// The fold repair's budget in force ([`LiveOptions::retarget`]'s
    /// [`crate::deform::DeformOptions::repair_budget`]; its text form,
    /// `none` when unbounded).
    pub repair_budget: RepairBudget,
    /// Output frames the two-frame overlap held for the next
    /// ([`LiveOptions::overlap`]; each deformed in a pair with it).
    pub frames_held: u64,
    /// The rate, latency and memory every `sample_every` seconds (and at
    /// the end), when asked for.
    pub samples: Vec<Sample>,
    /// The Rokoko actors seen (names, in order of appearance); empty for
    /// the other inputs.
    pub actors: Vec<String>,
    /// Files written by the recording.
    pub recorded: Vec<PathBuf>,
}

impl LiveReport {
    /// The report in one line (`live` without `--report`).
    pub fn line(&self) -> String {
        let l = &self.latency;
        format!(
            "{} frames at {:.1} frames/s, latency median {:.1} ms, p99 {:.1} ms",
            self.frames_out, self.output_fps, l.median_ms, l.p99_ms
        )
    }

    /// The report as the CLI prints it (`live --report`).
    pub fn text(&self) -> String {
        use std::fmt::Write;
        let r = self;
        let mut t = String::new();
        let _ = writeln!(
            t,
            "live: {} frames out over {:.2} s = {:.1} frames/s ({} vertices, database at {} fps, lag {})",
            r.frames_out, r.seconds, r.output_fps, r.vertices, r.fps, r.lag
        );
        if r.frames_held > 0 {
            let _ = writeln!(
                t,
                "overlap: {} frames held for the next and deformed in pairs",
                r.frames_held
            );
        }
        let _ = writeln!(
            t,
            "arrival -> mesh ready: median {:.2} ms, p99 {:.2} ms, max {:.2} ms (mesh work median {:.2} ms)",
            r.latency.median_ms, r.latency.p99_ms, r.latency.max_ms, r.work_median_ms
        );
        let c = &r.input;
        let _ = writeln!(
            t,
            "input: {} received, {} dropped, {} duplicated, {} late, {} malformed, {} reconnects",
            c.received, c.dropped, c.duplicated, c.late, c.malformed, c.reconnects
        );
        let _ = writeln!(
            t,
            "stages (ms per frame; wall median / p99 / max / mean, CPU mean / p99 / max):"
        );
        for g in &r.stages.stages {
            let _ = writeln!(
                t,
                "  {:<19} {:7.2} {:7.2} {:7.2} {:7.2}   CPU {:7.2} {:7.2} {:7.2}",
                g.stage,
                g.median_ms,
                g.p99_ms,
                g.max_ms,
                g.mean_ms,
                g.cpu_mean_ms,
                g.cpu_p99_ms,
                g.cpu_max_ms
            );
        }
        let st = &r.stages;
        let _ = writeln!(
            t,
            "  (mesh work mean {:.2} ms; fold repair on {} frames: deformation mean {:.2} ms, p99 {:.2} ms, against {:.2} / {:.2} ms without; handing on: median {:.2} ms, p99 {:.2} ms)",
            r.work_mean_ms,
            st.repaired_frames,
            st.deformation_repaired_mean_ms,
            st.deformation_repaired_p99_ms,
            st.deformation_plain_mean_ms,
            st.deformation_plain_p99_ms,
            r.output.median_ms,
            r.output.p99_ms
        );
        let _ = writeln!(
            t,
            "fold repair budget: {}; stopped at it on {} frames; {} triangle-frames left turned over",
            r.repair_budget, st.budget_reached_frames, r.turned_over
        );
        let s = &r.retrieval;
        let _ = writeln!(
            t,
            "retrieval: {} decided, {} jumps, {} cuts, {} widened; T_skel {:.3} m; prepared in {:.2} s",
            s.committed, s.jumps, s.cuts, s.widened, s.t_skel, r.prepare_seconds
        );
        if !r.actors.is_empty() {
            let _ = writeln!(t, "actors seen: {}", r.actors.join(", "));
        }
        for p in &r.samples {
            let rss = p.rss_mib.map_or("?".to_string(), |m| format!("{m:.1}"));
            let cpu = p
                .cpu_ms_per_frame
                .map_or("?".to_string(), |m| format!("{m:.2}"));
            let _ = writeln!(
                t,
                "  at {:7.1} s: {} out, {} dropped, {:.1} frames/s, median {:.2} ms, CPU {cpu} ms a frame, RSS {rss} MiB",
                p.seconds, p.frames_out, p.dropped, p.output_fps, p.latency_median_ms
            );
        }
        t
    }
}

/// Frames per second since `first`.
fn rate(frames: u64, first: Option<Instant>) -> f64 {
    let s = first.map_or(0.0, |f| f.elapsed().as_secs_f64());
    if s > 0.0 { frames as f64 / s } else { 0.0 }
}

/// What a session counts as it goes: latencies, frames, the recording,
/// the samples of a long run.
struct Tally {
    latencies: Latencies,
    work: Latencies,
    stages: StageTally,
    output: Latencies,
    frames_out: u64,
    frames_held: u64,
    /// The recording's frames, spooled to disk (`None` unless recording).
    spool: Option<super::spool::Spool>,
    /// The incoming skeletons not yet answered (at most lag + 1).
    incoming: VecDeque<Pose>,
    first: Option<Instant>,
    /// The process's CPU seconds when the first frame arrived.
    first_cpu: Option<f64>,
    last: Instant,
    /// The samples' period, the latencies since the last sample, when it
    /// was taken, the frames out and the process's CPU seconds then.
    sample_every: Option<Duration>,
    interval: Latencies,
    sampled: Option<(Instant, u64, Option<f64>)>,
    samples: Vec<Sample>,
}

impl Tally {
    fn new(spool: Option<super::spool::Spool>, sample_every: Option<f64>) -> Tally {
        Tally {
            latencies: Latencies::default(),
            work: Latencies::default(),
            stages: StageTally::default(),
            output: Latencies::default(),
            frames_out: 0,
            frames_held: 0,
            spool,
            incoming: VecDeque::new(),
            first: None,
            first_cpu: None,
            last: Instant::now(),
            sample_every: sample_every.map(Duration::from_secs_f64),
            interval: Latencies::default(),
            sampled: None,
            samples: Vec::new(),
        }
    }

    /// Counts an output frame made `latency` after its arrival and hands
    /// it on with the incoming skeleton it answers (`fallback` when none
    /// is waiting).
    fn out(
        &mut self,
        f: LiveFrame<'_>,
        latency: Duration,
        fallback: &Pose,
        on_frame: &mut dyn FnMut(FrameOut<'_>),
    ) {
        let began = Instant::now();
        self.frames_out += 1;
        if let Some(s) = self.spool.as_mut() {
            s.push(f.positions);
        }
        let inc = self.incoming.pop_front().unwrap_or(*fallback);
        on_frame(FrameOut {
            frame: f,
            incoming: &inc,
            latency_ms: latency.as_secs_f64() * 1e3,
            output_fps: rate(self.frames_out, self.first),
        });
        self.output.add(began.elapsed());
    }

    /// Takes a sample when one is due (every `sample_every`, from the first
    /// frame on).
    fn sample(&mut self, counters: Counters, force: bool) {
        let (Some(every), Some(first)) = (self.sample_every, self.first) else {
            return;
        };
        let now = Instant::now();
        let (since, frames_then, cpu_then) =
            *self.sampled.get_or_insert((first, 0, self.first_cpu));
        let dt = now.saturating_duration_since(since);
        if dt < every && !(force && dt.as_secs_f64() > 0.0) {
            return;
        }
        let cpu = crate::util::cpu::process_cpu_seconds();
        self.samples.push(Sample {
            seconds: now.saturating_duration_since(first).as_secs_f64(),
            frames_out: self.frames_out,
            received: counters.received,
            dropped: counters.dropped,
            output_fps: (self.frames_out - frames_then) as f64 / dt.as_secs_f64(),
            latency_median_ms: self.interval.quantile_ms(0.5),
            rss_mib: resident_mib(),
            cpu_ms_per_frame: match (cpu_then, cpu) {
                (Some(a), Some(b)) if self.frames_out > frames_then => {
                    Some((b - a) * 1e3 / (self.frames_out - frames_then) as f64)
                }
                _ => None,
            },
        });
        self.interval.clear();
        self.sampled = Some((now, self.frames_out, cpu));
    }
}

/// The session's options from the job's.
fn session_options(opts: &LiveOptions) -> SessionOptions {
    SessionOptions {
        retarget: opts.retarget,
        online: OnlineOptions {
            lag: opts.lag,
            hysteresis: opts.hysteresis,
        },
        history: opts.history,
        analysis_window: opts.analysis_window,
        floor_step: opts.floor_step,
        lift_settle: opts.lift_settle,
        keep_ground: opts.keep_ground,
        open_end: opts.open_end,
        overlap: opts.overlap,
        ..SessionOptions::default()
    }
}

/// True when the session should end now (stopped, out of time or idle),
/// before waiting for the next event.
fn should_stop(opts: &LiveOptions, stop: &AtomicBool, first: Option<Instant>) -> bool {
    if stop.load(Ordering::Relaxed) {
        return true;
    }
    matches!((first, opts.seconds), (Some(f), Some(d)) if f.elapsed().as_secs_f64() >= d)
}

/// Runs a live session from `input` on the database in `db` until the
/// stream ends, `stop` is set, `opts.seconds` pass or the stream is idle
/// `opts.until_idle` (a network source's address is told to `listening`): every output frame
/// to `on_frame` as it is made, recorded to `record` (any sequence format,
/// written atomically when the stream ends) if given.
#[allow(clippy::too_many_arguments)]
pub fn run_live(
    db: &Path,
    input: &LiveInput,
    record: Option<&Path>,
    opts: &LiveOptions,
    progress: &dyn BuildProgress,
    stop: &AtomicBool,
    listening: &mut dyn FnMut(Listening),
    on_frame: &mut dyn FnMut(FrameOut<'_>),
) -> Result<LiveReport, LiveError> {
    let ch = Character::load(db, progress)?;
    let fps = ch.manifest().fps;
    let t = Instant::now();
    let prepared = Prepared::new(&ch, &opts.retarget)?;
    let prepare_seconds = t.elapsed().as_secs_f64();
    let page = start_page(opts, &prepared, fps, listening)?;
    let (mut source, seen) = open_source(input, opts, fps, listening)?;
    let mut on_frame = |f: FrameOut<'_>| {
        if let Some(p) = &page {
            p.publish(&PageFrame {
                index: f.frame.index as u64,
                latency_ms: f.latency_ms,
                output_fps: f.output_fps,
                positions: f.frame.positions,
                incoming: f.incoming,
            });
        }
        on_frame(f)
    };
    let links = DatabaseLinks::of(&ch);
    let trellis = links.input();
    let sopts = session_options(opts);
    let mut session: Option<Session<'_>> = None;
    let spool = record
        .map(|out| super::spool::Spool::create(out, ch.n()))
        .transpose()?;
    let mut tally = Tally::new(spool, opts.sample_every);
    let idle = opts.until_idle.map(Duration::from_secs_f64);
    let mut last_frame = Instant::now();
    // The previous frame's arrival: a frame the overlap held was decided
    // on it.
    let mut previous: Option<Instant> = None;
    loop {
        if should_stop(opts, stop, tally.first) {
            break;
        }
        tally.sample(source.counters(), false);
        let (pose, rotations, arrived) = match source.next(Duration::from_millis(50))? {
            Event::Idle => {
                if matches!((tally.first, idle), (Some(_), Some(d)) if last_frame.elapsed() >= d) {
                    break;
                }
                continue;
            }
            Event::End => break,
            Event::Frame(f) => (f.pose, f.rotations, f.arrived),
        };
        if tally.first.is_none() {
            tally.first = Some(arrived);
            tally.first_cpu = crate::util::cpu::process_cpu_seconds();
        }
        last_frame = Instant::now();
        if session.is_none() {
            let reference = source.reference().ok_or(LiveError::NoReference)?;
            session = Some(Session::new(&ch, &prepared, &trellis, reference, sopts));
        }
        let Some(s) = session.as_mut() else { continue };
        tally.incoming.push_back(pose);
        let began = Instant::now();
        let decided_on = previous.unwrap_or(arrived);
        let mut emit = |f: LiveFrame<'_>| {
            let now = Instant::now();
            tally.frames_held += u64::from(f.held > 0);
            let (from, work) = match f.held {
                0 => (arrived, now - began),
                _ => (
                    decided_on,
                    Duration::from_secs_f64(f.stages.total_wall_ms() / 1e3),
                ),
            };
            let lat = now.saturating_duration_since(from);
            tally.latencies.add(lat);
            tally.interval.add(lat);
            tally.work.add(work);
            tally.stages.add(&f.stages);
            tally.out(f, lat, &pose, &mut on_frame);
        };
        s.set_waiting(source.waiting());
        s.push(&pose, rotations.as_ref(), &mut emit);
        previous = Some(arrived);
        tally.last = Instant::now();
    }
    if let Some(s) = session.as_mut() {
        let arrived = Instant::now();
        let mut emit = |f: LiveFrame<'_>| {
            let q = *f.query;
            tally.out(f, arrived.elapsed(), &q, &mut on_frame);
        };
        s.finish(&mut emit);
        tally.last = Instant::now();
    }
    tally.sample(source.counters(), true);
    let recorded = match (record, tally.spool.take()) {
        (Some(out), Some(spool)) if spool.frames() > 0 => {
            let save = crate::mesh::io::SaveOptions {
                fps: Some(fps),
                glb: opts.glb,
                usd: opts.usd,
            };
            spool.finish(prepared.topology_metres(), out, &save)?
        }
        _ => Vec::new(),
    };
    let seconds = tally.first.map_or(0.0, |f| {
        tally.last.saturating_duration_since(f).as_secs_f64()
    });
    Ok(LiveReport {
        fps,
        vertices: ch.n(),
        lag: opts.lag,
        frames_out: tally.frames_out,
        frames_held: tally.frames_held,
        output_fps: if seconds > 0.0 {
            tally.frames_out as f64 / seconds
        } else {
            0.0
        },
        seconds,
        prepare_seconds,
        latency: tally.latencies.summary(),
        work_median_ms: tally.work.quantile_ms(0.5),
        work_mean_ms: tally.work.summary().mean_ms,
        stages: tally.stages.summary(),
        output: tally.output.summary(),
        input: source.counters(),
        retrieval: session.as_ref().map(|s| s.stats()).unwrap_or_default(),
        turned_over: session.as_ref().map_or(0, |s| s.turned_over()),
        repair_budget: opts.retarget.deform_options.repair_budget,
        samples: tally.samples,
        actors: seen.map_or_else(Vec::new, |s| {
            s.lock().unwrap_or_else(|e| e.into_inner()).clone()
        }),
        recorded,
    })
}
