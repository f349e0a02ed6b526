//! `jobs::live`: live retargeting (issue 45) — a stream of mocap frames
//! drives the character through the online path ([`crate::live`]) on a
//! character prepared once, each mesh handed on as soon as it is made,
//! optionally recorded to any sequence format when the stream ends.

use crate::db::{BuildProgress, Character};
use crate::drive::query::{QueryError, load_mocap};
use crate::drive::trellis::TrellisInput;
use crate::drive::{Prepared, RetargetError, RetargetOptions};
use crate::live::bvh_tcp;
use crate::live::online::{OnlineOptions, OnlineStats};
use crate::live::page::{Meta, PageFrame, PageServer};
use crate::live::replay::Replay;
use crate::live::report::{Counters, Latencies, LatencySummary};
use crate::live::rokoko::Rokoko;
use crate::live::session::{LiveFrame, Session, SessionOptions};
use crate::live::source::{Event, Source, SourceError};
use crate::live::stream;
use crate::live::vmc::Vmc;
use crate::mesh::MeshSequence;
use crate::pose::Pose;
use crate::rig::LoadOptions;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Options of [`run_live`] (the defaults are the CLI's).
#[derive(Debug, Clone)]
pub struct LiveOptions {
    /// Synthesis (retrieval, timeline, placement, deformation) as offline.
    pub retarget: RetargetOptions,
    /// Frames of future before a frame is decided. Default: 3.
    pub lag: usize,
    /// Extra cost of a jump at lag 0. Default: 1.
    pub hysteresis: f64,
    /// Decided frames kept for blending and placement. Default: 64.
    pub history: usize,
    /// Frames the pose kernel analyses each frame with. Default: 32.
    pub analysis_window: usize,
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
}

impl Default for LiveOptions {
    fn default() -> Self {
        LiveOptions {
            retarget: RetargetOptions::default(),
            lag: 3,
            hysteresis: 1.0,
            history: 64,
            analysis_window: 32,
            speed: 1.0,
            load: LoadOptions::default(),
            seconds: None,
            until_idle: None,
            lossless: false,
            serve: None,
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

/// The stream `input` names, taken at `fps`; a network source's address
/// told to `listening`.
fn open_source(
    input: &LiveInput,
    opts: &LiveOptions,
    fps: f64,
    listening: &mut dyn FnMut(Listening),
) -> Result<Box<dyn Source>, LiveError> {
    let (load, lossless) = (opts.load.clone(), opts.lossless);
    let (source, addr): (Box<dyn Source>, _) = match input {
        LiveInput::Replay(clip) => (
            Box::new(Replay::new(load_mocap(clip, &opts.load, fps)?, opts.speed)),
            None,
        ),
        network => {
            let s = match network {
                LiveInput::BvhTcp(addr) => bvh_tcp::listen(*addr, fps, load, lossless)?,
                LiveInput::Vmc(addr) => stream::listen(*addr, Vmc::default(), fps, load, lossless)?,
                LiveInput::Rokoko(addr) => stream::listen(*addr, Rokoko, fps, load, lossless)?,
                LiveInput::Replay(_) => unreachable!("matched above"),
            };
            let a = s.local_addr();
            (Box::new(s), Some(a))
        }
    };
    if let Some(a) = addr {
        listening(Listening::Stream(a));
    }
    Ok(source)
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
    Retarget(#[from] RetargetError),
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
    /// The incoming frames: received, dropped, duplicated, late, malformed.
    pub input: Counters,
    /// The retrieval: frames decided, jumps, cuts, widened, the scales.
    pub retrieval: OnlineStats,
    /// Triangle-frames left turned over by the deformation.
    pub turned_over: usize,
    /// Files written by the recording.
    pub recorded: Vec<PathBuf>,
}

/// Frames per second since `first`.
fn rate(frames: u64, first: Option<Instant>) -> f64 {
    let s = first.map_or(0.0, |f| f.elapsed().as_secs_f64());
    if s > 0.0 { frames as f64 / s } else { 0.0 }
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
    let mut source = open_source(input, opts, fps, listening)?;
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
    let successor = |id: u32| ch.successor(id);
    let dissimilarity = |a: u32, b: u32| ch.matrix().get(a as usize, b as usize);
    let trellis = TrellisInput {
        poses: ch.poses(),
        adjacency: ch.adjacency(),
        successor: &successor,
        dissimilarity: &dissimilarity,
    };
    let sopts = SessionOptions {
        retarget: opts.retarget,
        online: OnlineOptions {
            lag: opts.lag,
            hysteresis: opts.hysteresis,
        },
        history: opts.history,
        analysis_window: opts.analysis_window,
    };
    let mut session: Option<Session<'_>> = None;
    let mut held: Vec<[f64; 3]> = Vec::new();
    let mut latencies = Latencies::default();
    let mut work = Latencies::default();
    let mut frames_out = 0u64;
    // The incoming skeletons not yet answered (at most lag + 1).
    let mut incoming: std::collections::VecDeque<Pose> = std::collections::VecDeque::new();
    let mut first: Option<Instant> = None;
    let mut last = Instant::now();
    let deadline = opts.seconds.map(Duration::from_secs_f64);
    let idle = opts.until_idle.map(Duration::from_secs_f64);
    let mut last_frame = Instant::now();
    loop {
        if stop.load(Ordering::Relaxed) {
            break;
        }
        if let (Some(f), Some(d)) = (first, deadline)
            && f.elapsed() >= d
        {
            break;
        }
        let ev = source.next(Duration::from_millis(50))?;
        let (pose, rotations, arrived) = match ev {
            Event::Idle => {
                if let (Some(_), Some(d)) = (first, idle)
                    && last_frame.elapsed() >= d
                {
                    break;
                }
                continue;
            }
            Event::End => break,
            Event::Frame(f) => (f.pose, f.rotations, f.arrived),
        };
        first.get_or_insert(arrived);
        last_frame = Instant::now();
        if session.is_none() {
            let reference = source.reference().ok_or(LiveError::NoReference)?;
            session = Some(Session::new(&ch, &prepared, &trellis, reference, sopts));
        }
        let Some(s) = session.as_mut() else { continue };
        incoming.push_back(pose);
        let began = Instant::now();
        let mut emit = |f: LiveFrame<'_>| {
            let now = Instant::now();
            let lat = now.saturating_duration_since(arrived);
            latencies.add(lat);
            work.add(now - began);
            frames_out += 1;
            if record.is_some() {
                held.extend_from_slice(f.positions);
            }
            let inc = incoming.pop_front().unwrap_or(pose);
            on_frame(FrameOut {
                frame: f,
                incoming: &inc,
                latency_ms: lat.as_secs_f64() * 1e3,
                output_fps: rate(frames_out, first),
            });
        };
        s.push(&pose, rotations.as_ref(), &mut emit);
        last = Instant::now();
    }
    if let Some(s) = session.as_mut() {
        let arrived = Instant::now();
        let mut emit = |f: LiveFrame<'_>| {
            frames_out += 1;
            if record.is_some() {
                held.extend_from_slice(f.positions);
            }
            let inc = incoming.pop_front().unwrap_or(*f.query);
            on_frame(FrameOut {
                frame: f,
                incoming: &inc,
                latency_ms: arrived.elapsed().as_secs_f64() * 1e3,
                output_fps: rate(frames_out, first),
            });
        };
        s.finish(&mut emit);
        last = Instant::now();
    }
    let seconds = first.map_or(0.0, |f| last.saturating_duration_since(f).as_secs_f64());
    let mut recorded = Vec::new();
    if let Some(out) = record
        && frames_out > 0
    {
        let seq = MeshSequence::new(prepared.topology_metres().clone(), held, Some(fps))?;
        recorded = crate::mesh::io::save_sequence(&seq, out, Some(fps))?;
    }
    Ok(LiveReport {
        fps,
        vertices: ch.n(),
        lag: opts.lag,
        frames_out,
        output_fps: if seconds > 0.0 {
            frames_out as f64 / seconds
        } else {
            0.0
        },
        seconds,
        prepare_seconds,
        latency: latencies.summary(),
        work_median_ms: work.quantile_ms(0.5),
        input: source.counters(),
        retrieval: session.as_ref().map(|s| s.stats()).unwrap_or_default(),
        turned_over: session.as_ref().map_or(0, |s| s.turned_over()),
        recorded,
    })
}
