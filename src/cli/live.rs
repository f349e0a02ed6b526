//! `surfmotion live`'s arguments: a mocap stream drives the 4D character
//! now (issue 45). [`super::live_run`] checks them, calls
//! [`surfmotion::jobs::live::run_live`] and prints.

use std::path::PathBuf;
use surfmotion::jobs::live::LiveOptions;

/// Arguments of `live`.
#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct Args {
    /// `live send`: send a clip as a stream.
    #[command(subcommand)]
    pub send: Option<Cmd>,
    /// The character database (built and cached on first use, as `db build`
    /// does).
    #[arg(long, required = true)]
    pub db: Option<PathBuf>,
    /// Play a clip file (any format `retarget` reads) as the stream, at its
    /// real frame rate (see --speed).
    #[arg(
        long,
        value_name = "CLIP",
        required_unless_present_any = ["bvh_tcp", "vmc", "rokoko"],
        conflicts_with_all = ["bvh_tcp", "vmc", "rokoko"]
    )]
    pub replay: Option<PathBuf>,
    /// Listen for BVH over TCP (a BVH header, then one frame line per
    /// sample, as Axis Studio / Perception Neuron broadcast) on ADDR:PORT,
    /// e.g. 127.0.0.1:7001. An address other than 127.0.0.1 accepts other
    /// machines and is printed as a warning.
    #[arg(long = "bvh-tcp", value_name = "ADDR:PORT", conflicts_with_all = ["vmc", "rokoko"])]
    pub bvh_tcp: Option<std::net::SocketAddr>,
    /// Listen for the VMC protocol (OSC over UDP: root and bone local
    /// transforms named as Unity's humanoid bones, as VTuber tools, Blender
    /// add-ons and suit bridges send) on ADDR:PORT; 127.0.0.1:39539 when
    /// given without a value. Another address than 127.0.0.1 is printed as
    /// a warning.
    #[arg(
        long,
        value_name = "ADDR:PORT",
        num_args = 0..=1,
        default_missing_value = "127.0.0.1:39539",
        conflicts_with = "rokoko"
    )]
    pub vmc: Option<std::net::SocketAddr>,
    /// Listen for Rokoko Studio Live (JSON over UDP: an actor's body joints,
    /// see --actor) on ADDR:PORT; 127.0.0.1:14043 when given without a value.
    #[arg(
        long,
        value_name = "ADDR:PORT",
        num_args = 0..=1,
        default_missing_value = "127.0.0.1:14043"
    )]
    pub rokoko: Option<std::net::SocketAddr>,
    /// The Rokoko actor that drives the character: name or index (from 0).
    #[arg(long, default_value = "0", requires = "rokoko")]
    pub actor: surfmotion::live::rokoko::ActorChoice,
    /// End the session when no frame came for this many seconds (a network
    /// stream otherwise waits for its sender to come back; stop with Ctrl-C).
    #[arg(long = "until-idle", value_name = "SECONDS", value_parser = super::positive)]
    pub until_idle: Option<f64>,
    /// Keep every network frame in order instead of the newest winning when
    /// the character falls behind (for recordings; latency then grows).
    #[arg(long)]
    pub lossless: bool,
    /// Two frames deformed at once: `queued` (default; `--overlap` alone) while
    /// the next one waits, `always` every frame (a frame more latency), `off` never.
    #[arg(long, value_enum, value_name = "WHEN", num_args = 0..=1, default_value_t = super::values::OverlapArg::from(LiveOptions::default().overlap), default_missing_value = "queued")]
    pub overlap: super::values::OverlapArg,
    /// The fold repair's work limit a frame, so each frame's deformation
    /// meets its deadline whatever the fold: `live` (the default: 30,000
    /// untangling projections and 4,000 patch unknowns a frame at most,
    /// 1,000 and 60 per triangle turned over, all spent on the repair
    /// against the surface's own turns, the skin's repair being its
    /// smoothing alone), `none` (the unbounded repair, as `retarget` runs
    /// it: offline's meshes, with a slow tail on clips that fold much), or
    /// `projections=N,patch=N[,per-triangle-projections=N,per-triangle-patch=N,skin-projections=N,skin-patch=N]`
    /// (a key left out is not bounded; the skin keys bound the frame's
    /// first repair, against the skin's turns, and 0 for both leaves it
    /// its smoothing alone). Counted work, not time: the same frames are
    /// bounded on any machine. `--report` and `--json` say on how many
    /// frames the repair stopped at the bound and how many triangles it
    /// left turned over (README, Live, session 52: CMU 02_02 on samba, 99
    /// triangle-frames turned over against the rest frame under `live`,
    /// 114 under `none`).
    #[arg(long = "repair-budget", value_name = "BUDGET")]
    pub repair_budget: Option<surfmotion::deform::RepairBudget>,
    /// Frames of future the retrieval sees before it decides a frame (the
    /// fixed-lag trellis); 0 decides each frame as it comes (greedy, with a
    /// hysteresis against flicker). Each lag frame adds one frame period
    /// of delay.
    #[arg(long, default_value_t = LiveOptions::default().lag)]
    pub lag: usize,
    /// Frames of the stream the pose kernel analyses each frame with,
    /// besides the undecided ones (up to --lag): it levels the ground and
    /// finds the floor and the feet's support over them (offline it sees
    /// the whole clip). Frames that left the lag keep what they were
    /// decided with; the undecided ones are analysed and retrieved again.
    #[arg(long = "analysis-window", default_value_t = LiveOptions::default().analysis_window, value_name = "FRAMES")]
    pub analysis_window: usize,
    /// Carry the floor the pose kernel stands the stream on from window to
    /// window, moving at most this many millimetres a frame once frames are
    /// output, instead of finding it anew over each window (measured, lag 3,
    /// live over offline velocity error with 0.5: samba 131_02 2.57 -> 2.24
    /// but 02_02, a walk on a sloping floor, 1.70 -> 2.46; off by default).
    #[arg(long = "floor-step", value_name = "MM", value_parser = super::non_negative)]
    pub floor_step: Option<f64>,
    /// The fraction of the body's lift that differs between the frame
    /// output last and the newest analysis of it given up per frame
    /// (default: the session's).
    #[arg(long = "lift-settle", value_name = "FRACTION", value_parser = super::fraction)]
    pub lift_settle: Option<f64>,
    /// Frames of the stream after which the pose kernel's levelling and
    /// floor are decided over the window and kept (decided again only when
    /// the window's own floor is more than the contact band from the kept
    /// one); 0 decides both over each window.
    #[arg(long = "keep-ground", value_name = "FRAMES")]
    pub keep_ground: Option<usize>,
    /// A foot that has left its support and not landed yet, at the
    /// window's end, counts with the floor under it instead of the support
    /// it left (as in a whole clip). Measured on CMU 03_01 (samba): better
    /// at lag 0, worse at lag 3 (README, Live).
    #[arg(long = "open-end")]
    pub open_end: bool,
    /// Decided frames kept for the timeline's blends and the placement's
    /// smoothing.
    #[arg(long, default_value_t = LiveOptions::default().history, value_name = "FRAMES")]
    pub history: usize,
    /// Replay speed: 1 plays the clip at its real rate, 2 twice as fast, 0
    /// as fast as meshes are made (for measuring throughput).
    #[arg(long, default_value_t = LiveOptions::default().speed, value_name = "FACTOR", value_parser = super::non_negative)]
    pub speed: f64,
    /// Play the replayed clip this many times (the stream's clock goes on).
    #[arg(long = "loop", default_value_t = LiveOptions::default().loops, requires = "replay")]
    pub loops: usize,
    /// Stop after this many seconds of streaming.
    #[arg(long, value_parser = super::positive)]
    pub seconds: Option<f64>,
    /// Sample rate, latency and resident memory every SECONDS into the report.
    #[arg(long = "sample-every", value_name = "SECONDS", value_parser = super::positive)]
    pub sample_every: Option<f64>,
    /// Record the output to any sequence format (.glb, .pc2, .mdd, .usda, a
    /// folder of OBJ frames), written atomically when the stream ends.
    #[arg(long, value_name = "OUT")]
    pub record: Option<PathBuf>,
    #[command(flatten)]
    pub glb: super::mesh::SequenceOutputArgs,
    /// Print the latency and throughput report (frames/s, arrival to mesh
    /// ready median and p99, drops, and where each frame's time went: the
    /// analysis, retrieval, timeline+placement, blending and deformation
    /// stages, wall and CPU) when the stream ends.
    #[arg(long)]
    pub report: bool,
    /// Serve the browser page (the character and the incoming skeleton side
    /// by side, with the latency and frame rates; frames streamed over a
    /// WebSocket) on ADDR:PORT; 127.0.0.1:8765 when given without a value.
    /// The page's URL is printed. Another address than 127.0.0.1 is printed
    /// as a warning.
    #[arg(long, value_name = "ADDR:PORT", num_args = 0..=1, default_missing_value = "127.0.0.1:8765")]
    pub serve: Option<std::net::SocketAddr>,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub clip: super::opts::ClipOpts,
}

/// `live` subcommands.
#[derive(clap::Subcommand)]
pub enum Cmd {
    /// Send a clip as a stream, so every input path can be tested without
    /// a suit.
    #[command(
        after_help = "Example:\n  surfmotion live --db samba_synth --bvh-tcp 127.0.0.1:7001 --until-idle 2 --report &\n  surfmotion live send 02_02.amc --to 127.0.0.1:7001 --protocol bvh\n  surfmotion live --db samba_synth --vmc --until-idle 2 --report &\n  surfmotion live send 02_02.amc --to 127.0.0.1:39539 --protocol vmc"
    )]
    Send(super::live_send::SendArgs),
}

/// The session's options from the arguments.
pub(super) fn options(a: &Args) -> anyhow::Result<LiveOptions> {
    let d = LiveOptions::default();
    let mut retarget = d.retarget;
    if let Some(b) = a.repair_budget {
        retarget.deform_options.repair_budget = b;
    }
    Ok(LiveOptions {
        retarget,
        lag: a.lag,
        speed: a.speed,
        seconds: a.seconds,
        until_idle: a.until_idle,
        lossless: a.lossless,
        overlap: a.overlap.into(),
        serve: a.serve,
        analysis_window: a.analysis_window.max(1),
        floor_step: a.floor_step.map(|mm| mm / 1000.0),
        lift_settle: a.lift_settle.or(d.lift_settle),
        keep_ground: a
            .keep_ground
            .map_or(d.keep_ground, |n| (n > 0).then_some(n)),
        open_end: d.open_end || a.open_end,
        history: a.history.max(1),
        loops: a.loops,
        actor: a.actor.clone(),
        sample_every: a.sample_every,
        load: a.clip.load_options()?,
        glb: a.glb.options(),
        usd: a.glb.usd_options(),
        ..d
    })
}
