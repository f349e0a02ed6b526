//! Command-line interface: one file per subcommand.

mod batch;
mod blend;
mod db;
mod demo;
mod graph;
mod inspect;
mod keyframe;
mod mesh;
mod mocap;
mod play;
mod render;
mod repair;
mod retarget;
mod rig;
mod synth;
mod transfer;
mod values;
mod web;

use clap::{CommandFactory, FromArgMatches, Subcommand};
use std::path::{Path, PathBuf};

/// surfmotion: drive 4D performance-capture characters from skeletal motion
/// capture, and transfer mocap onto scanned meshes.
///
/// Reads BVH and CMU ASF/AMC clips (any common rig naming: CMU, Reallusion
/// CC_Base, Bandai Namco, Mixamo, MotionBuilder HumanIK) and meshes or mesh
/// sequences (OBJ, PLY, PC2, MDD, OBJ folders, glTF/GLB). Exit codes: 0 ok,
/// 1 bad input (the message names the file and line), 2 internal error.
#[derive(clap::Parser)]
#[command(name = "surfmotion", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the embedded demo (no files needed).
    #[command(after_help = "Example:\n  surfmotion demo -o demo_out")]
    Demo(demo::Args),
    /// Show what any supported file holds: joints, frames, fps, units and up
    /// axis assumed, rig convention; or vertices, triangles, frames, bounds,
    /// skin, morph targets; a database folder's sequences, skeletons and
    /// cache state; any report, manifest, cache, graph or picture the tool
    /// writes; and any problems found.
    #[command(
        after_help = "Examples:\n  surfmotion inspect walk.bvh\n  surfmotion inspect samba.pc2 --json\n  surfmotion inspect samba_db            # a database: sequences, skeletons, cache up to date?\n  surfmotion inspect graph.dot           # what `graph --dot` wrote"
    )]
    Inspect(inspect::Args),
    /// Mocap clips: joint positions, conversion, rig maps.
    #[command(subcommand)]
    Mocap(mocap::Cmd),
    /// Meshes and mesh sequences: conversion between formats.
    #[command(subcommand)]
    Mesh(mesh::Cmd),
    /// Character databases: write a manifest, check what it holds, extract
    /// per-frame skeletons, build the Surface Motion Graph.
    #[command(subcommand)]
    Db(db::Cmd),
    /// Blend two meshes of one connectivity: non-linear (rotations slerped,
    /// stretch lerped, Poisson-stitched) or --linear; reports edge-length and
    /// volume distortion of both.
    #[command(
        after_help = "Example:\n  surfmotion blend crane.pc2:0 crane.pc2:100 --alpha 0.5 -o mid.obj"
    )]
    Blend(blend::Args),
    /// Repair a mesh: weld duplicate vertices, drop degenerate and duplicate
    /// triangles and unreferenced vertices, report connected components.
    #[command(after_help = "Example:\n  surfmotion repair scan.obj -o body.obj --keep-largest")]
    Repair(repair::Args),
    /// Draw a mesh (or a frame of a sequence) to PNG, front and side views;
    /// with --rig, coloured by body part with the skeleton drawn in.
    #[command(
        after_help = "Examples:\n  surfmotion render samba.pc2 --frame 90 --rig samba.rig.json -o samba_90.png\n  surfmotion render out.pc2:40 --up +z -o out_40.png   # a result on a Z-up scan, drawn standing"
    )]
    Render(render::Args),
    /// Rigs: embed the canonical skeleton, skin weights, body parts and joint
    /// regressors in a rest mesh from a few landmarks.
    #[command(subcommand)]
    Rig(rig::Cmd),
    /// Build a synthetic multi-motion 4D database from a rest mesh, its
    /// landmarks and mocap clips: linear blend skinning with the embedded
    /// weights plus secondary dynamics (a damped-spring lag on soft regions
    /// and loose clothing). The driving skeletons are kept in DIR/truth.
    #[command(
        after_help = "Example:\n  surfmotion synth --mesh samba.obj --landmarks samba.landmarks.json --mocap 02_01.amc 02_03.amc -o samba_synth"
    )]
    Synth(synth::Args),
    /// Export a database's Surface Motion Graph (sequences as nodes,
    /// transitions as edges) as DOT or JSON, or draw its similarity matrix
    /// with the transitions marked (--matrix OUT.png).
    #[command(
        after_help = "Examples:\n  surfmotion graph samba_synth --matrix samba_synth.png\n  surfmotion graph samba_synth --dot > graph.dot   # dot -Tsvg graph.dot -o graph.svg"
    )]
    Graph(graph::Args),
    /// Drive a 4D character from a mocap clip (Huang et al. 2015, Sec. 5.2):
    /// find the path through the database's Surface Motion Graph whose
    /// skeletons best follow the clip (skeletal trellis + shortest path),
    /// blend across transitions and interpolate repeated frames with
    /// non-linear mesh blending, and place the result on the clip's root
    /// trajectory.
    #[command(
        after_help = "Example:\n  surfmotion retarget --db samba_synth --mocap 02_02.amc -o walk.glb --report walk.json"
    )]
    Retarget(retarget::Args),
    /// Key-frame animation (Huang et al. 2015, Sec. 5.1): the path through
    /// the Surface Motion Graph from one database frame to another (via
    /// others, in order) that best meets a travel distance and time; loops
    /// repeated as an integer programme decides, transitions blended, the
    /// character placed along its accumulated travel. --grid evaluates a
    /// grid of targets (Table III).
    #[command(
        after_help = "Example:\n  surfmotion keyframe --db synth3 --from 02_01:0 --to dataset-1_walk_normal_001:150 --distance 15 --time 10 -o kf.pc2"
    )]
    Keyframe(Box<keyframe::Args>),
    /// Score a retargeted result: the average joint-velocity difference
    /// (cm/frame) between the clip on the character's skeleton and the
    /// skeleton extracted from the result (Huang et al. 2015, Sec. 6.2).
    #[command(
        after_help = "Example:\n  surfmotion eval --db samba_synth --mocap 02_02.amc --result walk.glb"
    )]
    Eval(retarget::EvalArgs),
    /// Animate a static scan from a mocap clip or a moving template mesh
    /// (Confluent Motion, de Aguiar et al. 2007): marker triangles on the
    /// scan (placed from landmarks, or from a file) take their rotations
    /// from the clip's bones or the template's triangles; the rotations are
    /// spread over the scan as harmonic quaternion fields and the mesh is
    /// rebuilt by a prefactored Poisson solve each frame.
    #[command(
        after_help = "Example:\n  surfmotion transfer --scan armadillo.obj --landmarks armadillo.landmarks.json --mocap 02_01.amc -o arm.pc2"
    )]
    Transfer(Box<transfer::Args>),
    /// Convert a whole mocap library: every BVH/AMC clip under a folder,
    /// driven onto a 4D character (--db) or transferred onto a scan
    /// (--scan --landmarks), in parallel, one output per clip in a mirrored
    /// tree. Resumable (complete outputs are skipped), shardable for
    /// cluster array jobs (--shard i/n); bad clips are reported, not fatal
    /// (exit 1 if any failed). Writes batch.json/.html/.svg.
    #[command(
        after_help = "Example:\n  surfmotion batch --db samba_synth --mocap-dir clips -o out"
    )]
    Batch(Box<batch::Args>),
    /// Play a scripted session of parametric motion (Casas et al. 2013): the database's [[space]] motion spaces steered by timed requests (space, speed, turn), with online transitions; writes any mesh output and a report of parameters asked vs achieved.
    #[command(
        after_help = "Example:\n  surfmotion play --db gaits --script control.json -o session.glb --report session.json"
    )]
    Play(play::Args),
    /// The character in a web browser (Volino et al. 2015): export a
    /// static site (compact 4D geometry, the Surface Motion Graph, a WebGL2
    /// page with an animation engine) or serve it locally.
    #[command(subcommand)]
    Web(web::Cmd),
}

/// Entry point of the CLI.
pub fn main() -> anyhow::Result<()> {
    // clap exits 2 on a usage error, which the exit-code contract keeps for
    // internal errors: print its message and exit 1 (help and version 0).
    let cli = match allow_negative_numbers(Cli::command())
        .try_get_matches()
        .and_then(|m| Cli::from_arg_matches(&m))
    {
        Ok(c) => c,
        // clap's "invalid UTF-8 was detected in one or more arguments"
        // and its usage text named neither the argument nor the option.
        Err(e) if e.kind() == clap::error::ErrorKind::InvalidUtf8 => {
            anyhow::bail!(non_utf8_argument(std::env::args_os().collect()))
        }
        // A value the option does not take: one line in the tool's words
        // (`render --frame -1` printed clap's "invalid digit found in
        // string" and three lines of usage).
        Err(e)
            if matches!(
                e.kind(),
                clap::error::ErrorKind::ValueValidation | clap::error::ErrorKind::InvalidValue
            ) =>
        {
            anyhow::bail!(bad_value(&e))
        }
        Err(e) => {
            let usage = e.use_stderr();
            // Help read by `| head` closed the pipe: not an error (it said
            // "surfmotion: Broken pipe (os error 32)", exit 1).
            if let Err(p) = e.print()
                && p.kind() != std::io::ErrorKind::BrokenPipe
            {
                return Err(p.into());
            }
            return if usage { Err(Usage.into()) } else { Ok(()) };
        }
    };
    // Warnings (a cache rebuilt, a graph edit that matched nothing, an
    // implausible result) show by default; SURFMOTION_LOG=debug etc. for more.
    // Notices of the jobs layer (target `surfmotion::notice`) are plain
    // lines on stderr, as the verbs printed them before they moved into
    // the library.
    use tracing_subscriber::prelude::*;
    // Reader warnings (target `surfmotion::warning`) are kept in the reports
    // the verbs print (inspect, rig check), so they are not printed again.
    let is_notice = |m: &tracing::Metadata<'_>| m.target() == surfmotion::jobs::batch::NOTICE;
    let is_reader_warning =
        |m: &tracing::Metadata<'_>| m.target() == surfmotion::util::fsutil::WARNING;
    // A result's plausibility warnings, when the verb prints them in its
    // text summary (see [`warnings_in_summary`]).
    let is_summarised = |m: &tracing::Metadata<'_>| {
        WARNINGS_IN_SUMMARY.load(std::sync::atomic::Ordering::Relaxed)
            && m.module_path() == Some(PLAUSIBILITY_MODULE)
    };
    tracing_subscriber::registry()
        .with(
            tracing_subscriber::fmt::layer()
                .without_time()
                .with_target(false)
                .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
                .with_writer(std::io::stderr)
                .with_filter(
                    tracing_subscriber::EnvFilter::builder()
                        .with_default_directive(tracing::level_filters::LevelFilter::WARN.into())
                        .with_env_var("SURFMOTION_LOG")
                        .from_env_lossy(),
                )
                .with_filter(tracing_subscriber::filter::filter_fn(move |m| {
                    !is_notice(m) && !is_reader_warning(m) && !is_summarised(m)
                })),
        )
        .with(PlainNotices.with_filter(tracing_subscriber::filter::filter_fn(is_notice)))
        .init();
    match cli.command {
        Command::Demo(a) => demo::run(a),
        Command::Inspect(a) => inspect::run(a),
        Command::Mocap(c) => mocap::run(c),
        Command::Mesh(c) => mesh::run(c),
        Command::Db(c) => db::run(c),
        Command::Blend(a) => blend::run(a),
        Command::Repair(a) => repair::run(a),
        Command::Render(a) => render::run(a),
        Command::Rig(c) => rig::run(c),
        Command::Synth(a) => synth::run(a),
        Command::Graph(a) => graph::run(a),
        Command::Retarget(a) => retarget::run(a),
        Command::Keyframe(a) => keyframe::run(*a),
        Command::Eval(a) => retarget::eval(a),
        Command::Transfer(a) => transfer::run(*a),
        Command::Batch(a) => batch::run_batch(*a),
        Command::Play(a) => play::run(a),
        Command::Web(c) => web::run(c),
    }
}

/// The one line for a command line whose argument is not UTF-8: which
/// argument, the option it belongs to, and its bytes (`\xFF` for each one
/// that is not UTF-8). Options and mesh specs (`SEQ.pc2:FRAME`) are text.
fn non_utf8_argument(args: Vec<std::ffi::OsString>) -> String {
    let Some(i) = args.iter().position(|a| a.to_str().is_none()) else {
        return "an argument is not valid UTF-8".into();
    };
    let mut shown = String::new();
    for c in args[i].as_encoded_bytes().utf8_chunks() {
        shown.extend(c.valid().chars().flat_map(char::escape_debug));
        for b in c.invalid() {
            shown += &format!("\\x{b:02X}");
        }
    }
    let option = match shown.split_once('=') {
        Some((o, v)) if o.starts_with("--") => Some((o.to_string(), v.to_string())),
        _ => args[..i]
            .last()
            .and_then(|p| p.to_str())
            .filter(|p| i > 1 && p.starts_with('-') && p.len() > 1 && !p.contains('='))
            .map(|p| (p.to_string(), shown.clone())),
    };
    match option {
        Some((o, v)) => format!(
            "{o} '{v}': not valid UTF-8 (argument {i}); this value is read as text: pass it in UTF-8 (rename the file if it is one)"
        ),
        None => format!(
            "argument {i} '{shown}' is not valid UTF-8; this value is read as text: pass it in UTF-8 (rename the file if it is one)"
        ),
    }
}

/// The module whose warnings are a result's plausibility warnings
/// ([`surfmotion::tools::eval::Plausibility`]'s `logged`).
const PLAUSIBILITY_MODULE: &str = "surfmotion::tools::eval::plausibility";

static WARNINGS_IN_SUMMARY: std::sync::atomic::AtomicBool =
    std::sync::atomic::AtomicBool::new(false);

/// Called by a verb whose text summary prints the plausibility report with
/// its warnings (`retarget`, `transfer`, `synth` without `--json`): the
/// same warnings are then not logged on stderr as well (`synth` printed
/// its penetration warning twice, once without the sequence's name). With
/// `--json` they are logged, as the JSON goes to a program.
pub fn warnings_in_summary(text: bool) {
    WARNINGS_IN_SUMMARY.store(text, std::sync::atomic::Ordering::Relaxed);
}

/// A progress bar on a terminal (hidden when stderr is not one).
pub fn progress(len: u64, what: &str) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{{bar:40}} {{pos}}/{{len}} {what} {{elapsed}} (eta {{eta}}) {{msg}}"
        ))
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}

/// A spinner with a message and the elapsed time on a terminal (hidden
/// when stderr is not one), for work whose library call reports no
/// progress (`web export`: 10 s on samba with nothing on the screen;
/// `play`'s model build). Clear it with `finish_and_clear`.
pub fn spinner(what: &str) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new_spinner();
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {msg} {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    bar.set_message(what.to_string());
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    bar
}

/// The first frame of a mesh file, keeping only the named OBJ groups when
/// any are given.
pub fn load_mesh_groups(spec: &str, groups: &[String]) -> anyhow::Result<surfmotion::mesh::Mesh> {
    let seq = surfmotion::mesh::io::load_sequence(spec, &Default::default())?;
    let mesh = seq.frame_mesh(0);
    if groups.is_empty() {
        return Ok(mesh);
    }
    let known: Vec<&str> = seq
        .mesh()
        .groups()
        .iter()
        .map(|g| g.name.as_str())
        .collect();
    let mut m = seq.mesh().select_groups(groups).ok_or_else(|| {
        anyhow::anyhow!(
            "{spec}: no group named {} (groups: {})",
            groups.join(", "),
            if known.is_empty() {
                "none".to_string()
            } else {
                known.join(", ")
            }
        )
    })?;
    m.set_positions(mesh.positions())?;
    Ok(m)
}

/// Prints a notice event's message as one plain line on stderr.
struct PlainNotices;

impl<S: tracing::Subscriber> tracing_subscriber::Layer<S> for PlainNotices {
    fn on_event(&self, e: &tracing::Event<'_>, _: tracing_subscriber::layer::Context<'_, S>) {
        struct Message(String);
        impl tracing::field::Visit for Message {
            fn record_debug(&mut self, f: &tracing::field::Field, v: &dyn std::fmt::Debug) {
                if f.name() == "message" {
                    self.0 = format!("{v:?}");
                }
            }
            fn record_str(&mut self, f: &tracing::field::Field, v: &str) {
                if f.name() == "message" {
                    self.0 = v.to_string();
                }
            }
        }
        let mut m = Message(String::new());
        e.record(&mut m);
        crate::errln!("{}", m.0);
    }
}

/// Stdout was closed by the reader (e.g. `| head`): not an error.
#[derive(Debug, thiserror::Error)]
#[error("output closed")]
pub struct OutputClosed;

/// `n` and a noun, plural when `n` is not one: "1 frame", "2 frames",
/// "3 vertices" ([`surfmotion::batch::summary::count`]).
pub fn count(n: usize, noun: &str) -> String {
    surfmotion::batch::summary::count(n, noun)
}

/// Every option of every verb takes negative numbers as values, so that
/// `--fps -30` reaches the option's parser ("expected a frame rate") instead
/// of being read as a flag `-3` (issue 18, item 17). A numeric option (one
/// value, parsed as a number) takes any value beginning with `-`, so that
/// `--t-skel -inf`, `-nan` or `-.5` reach its check too instead of clap's
/// "unexpected argument '-i'" (clap counts only digits, one dot and one
/// exponent as a negative number).
fn allow_negative_numbers(cmd: clap::Command) -> clap::Command {
    cmd.mut_args(|a| {
        if !a.get_action().takes_values() {
            a
        } else if is_numeric_option(&a) {
            a.allow_hyphen_values(true)
        } else {
            a.allow_negative_numbers(true)
        }
    })
    .mut_subcommands(allow_negative_numbers)
}

/// An option (not a positional) that takes one value parsed as a number.
/// Options taking a list stay as they are, so `--frames 1,2 --out x` still
/// ends the list at `--out`.
fn is_numeric_option(a: &clap::Arg) -> bool {
    use std::any::TypeId;
    let one_value = a
        .get_num_args()
        .is_none_or(|n| n.max_values() == 1 && n.min_values() == 1);
    let t = a.get_value_parser().type_id();
    let numeric = [
        TypeId::of::<f64>(),
        TypeId::of::<f32>(),
        TypeId::of::<usize>(),
        TypeId::of::<u64>(),
        TypeId::of::<u32>(),
        TypeId::of::<u16>(),
        TypeId::of::<u8>(),
        TypeId::of::<i64>(),
        TypeId::of::<i32>(),
        TypeId::of::<isize>(),
    ]
    .into_iter()
    .any(|n| t == n);
    a.get_long().is_some() && one_value && numeric && a.get_value_delimiter().is_none()
}

/// One line for a value an option does not take: the option, the value
/// and what it takes (a whole number ≥ 0 for counts and frame indices,
/// the possible values of a choice, or the option's own check).
fn bad_value(e: &clap::Error) -> String {
    use clap::error::{ContextKind, ContextValue};
    use std::num::IntErrorKind;
    let text = |k| match e.get(k) {
        Some(ContextValue::String(s)) => Some(s.clone()),
        _ => None,
    };
    // "--frame <FRAME>" → "--frame"; a positional "<DIR>" stays.
    let arg = text(ContextKind::InvalidArg).unwrap_or_else(|| "an argument".into());
    let flag = if arg.starts_with('-') {
        arg.split([' ', '=']).next().unwrap_or(&arg).to_string()
    } else {
        arg.clone()
    };
    let value = text(ContextKind::InvalidValue).unwrap_or_default();
    let source = std::error::Error::source(e);
    let why = if let Some(p) = source.and_then(|s| s.downcast_ref::<std::num::ParseIntError>()) {
        match p.kind() {
            IntErrorKind::Empty => "expected a whole number, got nothing".to_string(),
            IntErrorKind::PosOverflow | IntErrorKind::NegOverflow => {
                "a whole number too large for this option".to_string()
            }
            _ if flag == "--frame" || flag == "--frames" => {
                "expected a frame number: a whole number from 0 (the first frame)".to_string()
            }
            _ => "expected a whole number ≥ 0".to_string(),
        }
    } else if let Some(s) = source {
        s.to_string()
    } else if let Some(ContextValue::Strings(v)) = e.get(ContextKind::ValidValue)
        && !v.is_empty()
    {
        format!("expected one of {}", v.join(", "))
    } else if value.is_empty() {
        return format!("{flag} needs a value");
    } else {
        "not a value this option takes".to_string()
    };
    format!("{flag} '{value}': {why}")
}

/// Refuses an output folder that is a file or lies under one, before any
/// work (it said "X: File exists (os error 17)" or "Not a directory" after
/// it). `flag` names the option (empty for a positional argument), `writes`
/// says what goes into the folder.
pub fn output_folder(flag: &str, dir: &Path, writes: &str) -> anyhow::Result<()> {
    let named = if flag.is_empty() {
        dir.display().to_string()
    } else {
        format!("{flag} {}", dir.display())
    };
    for p in dir.ancestors().filter(|p| !p.as_os_str().is_empty()) {
        if p.exists() && !p.is_dir() {
            let what = if p == dir {
                "a file".to_string()
            } else {
                format!("{} is a file", p.display())
            };
            anyhow::bail!("{named}: {what}, not a folder ({writes})");
        }
    }
    Ok(())
}

/// A mesh argument (a file, a folder of frames or `SEQ.pc2:FRAME`): not
/// empty. (An empty one named the current folder: "`: a character
/// database folder`" or "no .obj files in the folder".)
pub fn mesh_spec(s: &str) -> Result<String, String> {
    if s.trim().is_empty() {
        Err("expected a mesh file (.obj .ply .pc2 .mdd .gltf .glb), a folder of .obj frames or SEQ.pc2:FRAME; got nothing".into())
    } else {
        Ok(s.to_string())
    }
}

/// A frame rate on the command line: a finite number in
/// [[`MIN_FPS`](surfmotion::util::budget::MIN_FPS),
/// [`MAX_FPS`](surfmotion::util::budget::MAX_FPS)] (1-1000). (A typo such as
/// `--input-fps 1e-4` or `--fps 1e9` would otherwise ask for billions of
/// frames; issue 18, item 12.)
pub fn frame_rate(s: &str) -> Result<f64, String> {
    use surfmotion::util::budget::{MAX_FPS, MIN_FPS, is_frame_rate};
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number"))?;
    if is_frame_rate(v) {
        Ok(v)
    } else {
        Err(format!(
            "{s} frames per second: expected a frame rate in [{MIN_FPS}, {MAX_FPS}]"
        ))
    }
}

/// A duration or size on the command line: a finite number > 0.
pub fn positive(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number"))?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("{s}: expected a finite number > 0"))
    }
}

/// A fraction on the command line: a finite number in [0, 1].
pub fn fraction(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number"))?;
    if v.is_finite() && (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{s}: expected a number in [0, 1]"))
    }
}

/// An angle or signed quantity on the command line: any finite number
/// (NaN or infinity would make every cost NaN; issue 18, item 13).
pub fn finite(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number"))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("{s}: expected a finite number"))
    }
}

/// A weight or distance on the command line: a finite number ≥ 0 (NaN made
/// the trellis panic; issue 18, item 13).
pub fn non_negative(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number"))?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("{s}: expected a finite number ≥ 0"))
    }
}

/// A cost weight of Eq. 7 (`--w-dist`, `--w-time`, `--w-heading`): finite,
/// ≥ 0 and at most 1e6. Larger weights overflow the search's costs to
/// infinity (`--w-time 1e308` reported "no path" for a reachable target).
pub fn weight(s: &str) -> Result<f64, String> {
    let v = non_negative(s)?;
    if v <= 1e6 {
        Ok(v)
    } else {
        Err(format!("{s}: a weight above 1e6 overflows the path costs"))
    }
}

/// A picture output on the command line: a name ending in `.png`, or an
/// existing device or pipe (`/dev/stdout`). Any other name had a PNG
/// written into it (`render -o r.txt`, `graph --matrix m.obj`, exit 0).
pub fn png_path(s: &str) -> Result<PathBuf, String> {
    let p = PathBuf::from(s);
    let png = p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
    let special = std::fs::metadata(&p).is_ok_and(|m| !m.is_file() && !m.is_dir());
    if png || special {
        Ok(p)
    } else {
        Err(format!(
            "{s}: expected a .png file name (a PNG picture is written)"
        ))
    }
}

/// A count on the command line (pixels, frames) in `[lo, hi]`: clap's
/// "0 is not in 16..=8192" instead of a silent clamp (`render --size 0`
/// drew 16 pixels).
pub fn bounded_count(lo: u64, hi: u64) -> clap::builder::RangedU64ValueParser<usize> {
    clap::builder::RangedU64ValueParser::<usize>::new().range(lo..=hi)
}

/// Metres per unit a length unit given as a number may have: a
/// micrometre to a kilometre. (`--input-units 1e300` printed joint
/// positions of 1e300 metres, exit 0.)
pub const UNIT_RANGE: std::ops::RangeInclusive<f64> = 1e-6..=1e3;

/// A length unit on the command line (`flag` names the option): a name
/// or a number of metres per unit in [`UNIT_RANGE`].
pub fn length_unit(flag: &str, u: &str) -> anyhow::Result<surfmotion::mocap::Units> {
    let units = surfmotion::mocap::units::parse_unit(u).ok_or_else(|| {
        anyhow::anyhow!("{flag} '{u}': expected m, cm, mm, dm, inch, cmu or a number")
    })?;
    if !UNIT_RANGE.contains(&units.metres_per_unit) {
        anyhow::bail!(
            "{flag} '{u}': {:e} metres per unit is not a length unit (expected {:e} to {})",
            units.metres_per_unit,
            UNIT_RANGE.start(),
            UNIT_RANGE.end()
        );
    }
    Ok(units)
}

/// Whether `a` and `b` name one file on disk, existing or not (compared by
/// their canonical folder and file name).
fn same_file(a: &Path, b: &Path) -> bool {
    let key = |p: &Path| -> Option<PathBuf> {
        if let Ok(c) = p.canonicalize() {
            return Some(c);
        }
        let dir = p
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        Some(dir.canonicalize().ok()?.join(p.file_name()?))
    };
    matches!((key(a), key(b)), (Some(x), Some(y)) if x == y)
}

/// Refuses a command line that would write over one of its `inputs`, or
/// write two of its `outputs` (option, path) to one file, before any work.
/// (`retarget --report CLIP.bvh` replaced the clip with the report,
/// `--report out.glb` the result, `--preview CLIP.bvh` the clip with a
/// PNG; each exited 0.)
pub fn refuse_colliding(inputs: &[PathBuf], outputs: &[(&str, PathBuf)]) -> anyhow::Result<()> {
    for (k, (flag, o)) in outputs.iter().enumerate() {
        if let Some(i) = inputs.iter().find(|i| same_file(i, o)) {
            anyhow::bail!(
                "{flag} {}: writing it would overwrite the input {}; choose another name",
                o.display(),
                i.display()
            );
        }
        if let Some((other, _)) = outputs[..k].iter().find(|(_, p)| same_file(p, o)) {
            anyhow::bail!(
                "{flag} {}: {other} writes the same file; choose another name",
                o.display()
            );
        }
    }
    Ok(())
}

/// The files a mesh output wrote, for a summary line: each named, except
/// a folder of OBJ frames, named once with its count and first and last
/// frame (`mesh convert x.pc2 frames` listed all 180 frames joined by
/// "and", a line of 5 kB).
pub fn written_list(files: &[PathBuf], sep: &str) -> String {
    let name = |p: &PathBuf| p.display().to_string();
    let folder = files.first().and_then(|f| f.parent());
    let frames = files.len() > 2
        && files.iter().all(|f| {
            f.parent() == folder && f.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj"))
        });
    match (frames, folder, files.first(), files.last()) {
        (true, Some(dir), Some(a), Some(b)) => format!(
            "{}{} ({} OBJ frames, {} .. {})",
            dir.display(),
            std::path::MAIN_SEPARATOR,
            files.len(),
            a.file_name().unwrap_or_default().to_string_lossy(),
            b.file_name().unwrap_or_default().to_string_lossy()
        ),
        _ => files.iter().map(name).collect::<Vec<_>>().join(sep),
    }
}

/// The files `-o OUT` writes (a point cache's topology OBJ beside it),
/// labelled for [`refuse_colliding`].
pub fn mesh_outputs(out: &Path) -> Vec<(&'static str, PathBuf)> {
    surfmotion::mesh::io::output_files(out)
        .into_iter()
        .map(|p| ("-o", p))
        .collect()
}

/// Refuses a mesh output path before any work: a folder named like a
/// file, or an extension no writer has (found only after the whole job).
pub fn check_mesh_output(out: &Path) -> anyhow::Result<()> {
    use surfmotion::mesh::io::MeshFormat;
    surfmotion::mesh::io::refuse_folder_as_file(out)?;
    match MeshFormat::of(out) {
        None => anyhow::bail!(
            "{}: unknown output format (use .glb .pc2 .mdd .obj .ply or a folder)",
            out.display()
        ),
        Some(MeshFormat::Gltf) => {
            anyhow::bail!(
                "{}: writing .gltf is not supported; use .glb",
                out.display()
            )
        }
        Some(_) => Ok(()),
    }
}

/// Refuses a folder-of-OBJ-frames output (a name without extension) that
/// exists and already holds files, unless `force`, as `synth -o` and `db
/// init` refuse an existing database: frames written among other files, or
/// over a longer run's frames (whose last ones stayed behind and read back
/// as part of the new sequence), made a folder that is not this run's
/// result (`keyframe -o DIR` wrote into a folder of files, exit 0). With
/// `force` the OBJ frames a previous run wrote there (`frame_*.obj`) are
/// removed first; other files stay.
///
/// `--force` never extends to inputs: a folder that is or holds one of
/// `inputs` (the verb's input files and folders, resolved before this is
/// called) is
/// refused, naming it, before anything is removed (issue 46, item 3:
/// `keyframe -o DB --force` removed the database's own `frame_*.obj`
/// sequence and topology, then failed to load it).
pub fn check_folder_output(out: &Path, force: bool, inputs: &[PathBuf]) -> anyhow::Result<()> {
    if out.extension().is_some() || !out.is_dir() {
        return Ok(());
    }
    let entries: Vec<PathBuf> = std::fs::read_dir(out)
        .map_err(|e| anyhow::anyhow!("{}: {e}", out.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    if entries.is_empty() {
        return Ok(());
    }
    if let Ok(dir) = out.canonicalize() {
        let inside = |i: &&PathBuf| {
            i.canonicalize()
                .is_ok_and(|c| c == dir || c.parent() == Some(dir.as_path()))
        };
        // An input among the frames --force would remove is named first.
        let frame = |p: &PathBuf| {
            p.file_name()
                .and_then(|n| n.to_str())
                .and_then(|n| n.strip_prefix("frame_"))
                .is_some_and(|n| n.to_ascii_lowercase().ends_with(".obj"))
        };
        if let Some(i) = inputs.iter().filter(inside).min_by_key(|p| !frame(p)) {
            anyhow::bail!(
                "-o {}: the folder holds the input {}; write the frames to another folder (--force replaces earlier outputs, never inputs)",
                out.display(),
                i.display()
            );
        }
    }
    if !force {
        anyhow::bail!(
            "-o {}: the folder already holds {}; pass --force to replace its OBJ frames, or choose an empty or new folder",
            out.display(),
            count(entries.len(), "file")
        );
    }
    let is_frame = |p: &Path| {
        p.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj"))
            && p.file_stem()
                .and_then(|s| s.to_str())
                .and_then(|s| s.strip_prefix("frame_"))
                .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
    };
    for p in entries.iter().filter(|p| is_frame(p) && p.is_file()) {
        std::fs::remove_file(p).map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))?;
    }
    Ok(())
}

/// The files a database is read from (its manifest, topology, sequences
/// and rig files), which no output may replace.
pub fn database_inputs(db: &Path) -> Vec<PathBuf> {
    use surfmotion::db::{MANIFEST, Manifest};
    let mut v = vec![db.join(MANIFEST)];
    if let Ok(m) = Manifest::load(db) {
        v.push(Manifest::resolve(db, &m.topology));
        for s in &m.sequences {
            let p = Manifest::resolve(db, &s.path);
            v.extend(surfmotion::mesh::io::input_files(
                &p.to_string_lossy(),
                None,
            ));
        }
        let r = &m.rig;
        for p in [&r.landmarks, &r.parts, &r.gltf_skin, &r.rig_map]
            .into_iter()
            .flatten()
        {
            v.push(Manifest::resolve(db, p));
        }
    }
    v
}

/// A command line clap refused (it has printed why): exit 1.
#[derive(Debug, thiserror::Error)]
#[error("bad command line")]
pub struct Usage;

/// Writes to stdout; a closed pipe becomes [`OutputClosed`] instead of a panic.
pub fn emit(text: &str) -> anyhow::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|_| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Err(OutputClosed.into()),
        // Named: "surfmotion: No space left on device" did not say where.
        Err(e) => Err(anyhow::anyhow!("writing to standard output: {e}")),
    }
}

/// `println!` through [`emit`].
#[macro_export]
macro_rules! outln {
    ($($t:tt)*) => { $crate::cli::emit(&format!("{}\n", format!($($t)*))) };
}

/// `eprintln!` that never panics: a line on stderr, dropped when stderr
/// is closed or full (`eprintln!` panicked there: `mesh convert A B
/// 2>&-` and every other verb that reports on stderr exited 2).
#[macro_export]
macro_rules! errln {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($t)*);
    }};
}

/// An error and its causes on one line. A cause already said is left
/// out, and a cause that begins with what its context said continues it
/// rather than repeating it (`eval --result FOLDER` printed "FOLDER:
/// FOLDER: no .obj files in the folder").
pub fn one_line(e: &anyhow::Error) -> String {
    let mut s = e.to_string();
    for c in e.chain().skip(1) {
        let c = c.to_string();
        if s.contains(&c) {
            continue;
        }
        // The longest tail of `s` (whole, or after a ": ") that `c` begins with.
        let tails = std::iter::once(0).chain(s.match_indices(": ").map(|(i, _)| i + 2));
        match tails.into_iter().find(|&i| c.starts_with(&s[i..])) {
            Some(i) => {
                s.truncate(i);
                s.push_str(&c);
            }
            None => {
                s.push_str(": ");
                s.push_str(&c);
            }
        }
    }
    without_os_error_numbers(&s.replace('\n', " "))
}

/// `s` without the OS's " (os error N)" suffixes: "x.bvh: No such file or
/// directory (os error 2)" says what is wrong without them.
pub fn without_os_error_numbers(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(i) = rest.find(" (os error ") {
        let tail = &rest[i + " (os error ".len()..];
        let digits = tail.bytes().take_while(u8::is_ascii_digit).count();
        if digits > 0 && tail[digits..].starts_with(')') {
            out.push_str(&rest[..i]);
            rest = &tail[digits + 1..];
        } else {
            out.push_str(&rest[..i + 1]);
            rest = &rest[i + 1..];
        }
    }
    out.push_str(rest);
    out
}

/// Options shared by the verbs that read clips and show their result
/// (`retarget`, `transfer`, `synth`; flattened in place, so their help
/// lists them where each verb declared them before).
#[derive(clap::Args, Clone, Debug)]
pub struct RunOpts {
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub clip: ClipOpts,
    #[command(flatten)]
    pub preview: render::PreviewOpts,
}

/// Options shared by every command that reads a clip.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct ClipOpts {
    /// Frame rate of the input, overriding the file's (BVH with a wrong
    /// Frame Time; AMC files store none and default to CMU's 120).
    #[arg(long = "input-fps", value_name = "FPS", value_parser = frame_rate)]
    pub input_fps: Option<f64>,
    /// The ASF skeleton of an AMC clip (default: the only .asf beside it).
    #[arg(long, value_name = "PATH")]
    pub asf: Option<std::path::PathBuf>,
    /// Length unit of the input: m, cm, mm, dm, inch, cmu (1/0.45 inch) or a
    /// number of metres per unit. Default: from the ASF header, else guessed
    /// from the skeleton's size (see `inspect`).
    // Unit options are named alike on every verb: `--input-units` for the
    // files read (with `--input-fps`), `--output-units` for what is
    // written. `--assume-units` was this option's name before.
    #[arg(long = "input-units", alias = "assume-units", value_name = "UNIT")]
    pub input_units: Option<String>,
    /// Up axis of the input (y or z). Default: guessed from head above pelvis.
    #[arg(long, value_name = "AXIS")]
    pub up: Option<String>,
    /// A JSON rig map (canonical joint → joint name) for rigs whose naming
    /// is not detected; `mocap rigmap CLIP -o map.json` writes one to edit.
    #[arg(long = "rig-map", value_name = "JSON")]
    pub rig_map: Option<std::path::PathBuf>,
}

impl ClipOpts {
    /// The library's load options.
    pub fn load_options(&self) -> anyhow::Result<surfmotion::rig::LoadOptions> {
        let units = match &self.input_units {
            None => None,
            Some(u) => Some(length_unit("--input-units", u)?),
        };
        let up = match self.up.as_deref().map(str::to_ascii_lowercase).as_deref() {
            None => None,
            Some("y") => Some(surfmotion::mocap::UpAxis::Y),
            Some("z") => Some(surfmotion::mocap::UpAxis::Z),
            Some(o) => anyhow::bail!("--up '{o}': expected y or z"),
        };
        let rig_map = match &self.rig_map {
            Some(p) => Some(surfmotion::rig::RigMap::load(p)?),
            None => None,
        };
        Ok(surfmotion::rig::LoadOptions {
            fps: self.input_fps,
            asf: self.asf.clone(),
            units,
            up,
            rig_map,
        })
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn count_says_one_frame_and_two_vertices() {
        assert_eq!(super::count(1, "frame"), "1 frame");
        assert_eq!(super::count(0, "transition"), "0 transitions");
        assert_eq!(super::count(3, "vertex"), "3 vertices");
        assert_eq!(super::count(2, "match"), "2 matches");
        assert_eq!(super::count(9, "query"), "9 queries");
        assert_eq!(super::count(2, "key"), "2 keys");
    }

    /// The OS's error numbers are not printed.
    #[test]
    fn os_error_numbers_are_left_out() {
        assert_eq!(
            super::without_os_error_numbers(
                "a.bvh: No such file or directory (os error 2); b: Permission denied (os error 13)"
            ),
            "a.bvh: No such file or directory; b: Permission denied"
        );
        assert_eq!(
            super::without_os_error_numbers("x (os error y) (os error 7"),
            "x (os error y) (os error 7"
        );
    }

    /// Regression (session 6 review): `eval --result FOLDER` printed the
    /// folder twice; a cause that begins with its context continues it.
    #[test]
    fn one_line_says_each_part_once() {
        #[derive(Debug, thiserror::Error)]
        #[error("{0}")]
        struct E(String, #[source] Option<Box<E>>);
        let e = |s: &str, c: Option<E>| E(s.into(), c.map(Box::new));
        let chain = |x: E| super::one_line(&anyhow::Error::new(x));
        let inner = || e("out: no .obj files in the folder", None);
        assert_eq!(
            chain(e("out", Some(inner()))),
            "out: no .obj files in the folder"
        );
        assert_eq!(
            chain(e("eval: out", Some(inner()))),
            "eval: out: no .obj files in the folder"
        );
        assert_eq!(
            chain(e("loading", Some(inner()))),
            "loading: out: no .obj files in the folder"
        );
        assert_eq!(chain(e("a: b", Some(e("b", None)))), "a: b");
    }
}
