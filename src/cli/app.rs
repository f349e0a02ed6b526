//! The command enum, its parsing (usage errors in the tool's words, exit
//! codes) and its dispatch to one subcommand file each.

use super::argv::{Usage, allow_negative_numbers, bad_value, non_utf8_argument};
use super::{
    batch, blend, db, demo, eval, graph, inspect, keyframe, live, live_run, log, mesh, mocap, play,
    render, repair, retarget, rig, synth, transfer, transfer_run, web,
};
use clap::{CommandFactory, FromArgMatches, Subcommand};

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
    Eval(eval::Args),
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
    /// Drive the character live from a mocap stream (issue 45): each frame
    /// retrieved by a fixed-lag trellis, blended, placed and deformed as it
    /// arrives; a latency and throughput report, an optional recording.
    #[command(
        after_help = "Example:\n  surfmotion live --db samba_synth --replay 02_02.amc --report --record live.pc2"
    )]
    Live(Box<live::Args>),
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
    let (cli, matches) = match allow_negative_numbers(Cli::command())
        .try_get_matches()
        .and_then(|m| Cli::from_arg_matches(&m).map(|c| (c, m)))
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
    log::init();
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
        Command::Eval(a) => eval::run(a),
        Command::Transfer(a) => transfer_run::run(*a),
        Command::Batch(a) => batch::run_batch(*a, verb_matches(&matches)),
        Command::Play(a) => play::run(a),
        Command::Live(a) => live_run::run(*a),
        Command::Web(c) => web::run(c),
    }
}

/// The matches of the verb `m` (the whole command line's) names: what
/// [`super::given`] reads which options were typed from.
fn verb_matches(m: &clap::ArgMatches) -> &clap::ArgMatches {
    m.subcommand().map_or(m, |(_, verb)| verb)
}
