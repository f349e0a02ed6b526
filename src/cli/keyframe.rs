//! `surfmotion keyframe`: key-frame animation through the Surface Motion
//! Graph (Huang et al. 2015, Sec. 5.1), and its Table III grid evaluation.

use std::path::PathBuf;
use surfmotion::keyframe::grid::{GridReport, evaluate_with, parse_range};
use surfmotion::keyframe::search::{Method, SearchOptions, Solver, Weights};
use surfmotion::keyframe::{
    KeyframeOptions, Planner, Streamed, Targets, TransitionCost, describe, key_graph, parse_key,
    plan_path, pose,
};
use surfmotion::mesh::io::SaveOptions;
use surfmotion::mesh::io::stream::SequenceWriter;
use surfmotion::retarget::character::Character;

/// Repetition solver on the command line.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum SolverArg {
    /// Exact dynamic programme over the loop frames (fast).
    Exact,
    /// The paper's four integer linear programmes (microlp).
    Ilp,
}

/// Search method on the command line.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum MethodArg {
    /// Exact-length dynamic programme over (node, frames) first (any path,
    /// nested loops included); the paper's walks and loops when it finds
    /// nothing within its tolerance.
    Lattice,
    /// The paper's loop-free walks plus repeated loops only (Eqs. 13-25).
    Walks,
}

/// Transition cost on the command line.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum CostArg {
    /// The graph's shape distortion (Eqs. 2-3, the paper).
    Graph,
    /// The measured smoothness (metres).
    Smoothness,
}

/// Transition set on the command line.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum TransitionsArg {
    /// The Surface Motion Graph's (the shape histogram's top N, Sec. 4.2).
    Graph,
    /// Re-chosen by measured distortion (weighted surface Hausdorff
    /// distance of the overlapping frames), priced by it; key-frame only.
    Measured,
}

/// Arguments of `keyframe`.
#[derive(clap::Args)]
pub struct Args {
    /// The character database (its graph is built first if needed).
    #[arg(long)]
    pub db: PathBuf,
    /// Start key-frame: SEQUENCE:FRAME (frames from 0), or a skeleton pose
    /// (CLIP.bvh:F, CLIP.amc:F at the database's frame rate, or POSE.json
    /// with the 19 canonical joints in metres, Y up) resolved to the
    /// nearest database frame by the skeleton measure (Eq. 28).
    #[arg(long, value_name = "SEQ:F")]
    pub from: String,
    /// End key-frame, as --from.
    #[arg(long, value_name = "SEQ:F")]
    pub to: String,
    /// Key-frames to pass in between, in order (repeat the option), as
    /// --from.
    #[arg(long, value_name = "SEQ:F")]
    pub via: Vec<String>,
    /// Target final facing, degrees relative to the start key-frame's
    /// (positive: from +Z towards +X); a cost term of the exact-length
    /// search and of the walks' search (--w-heading per degree).
    #[arg(long, value_name = "DEG", allow_hyphen_values = true, value_parser = heading)]
    pub heading: Option<f64>,
    /// Weight of the heading error, per degree. Default: 1/30 (30° cost as
    /// much as 0.3 m of distance).
    #[arg(long, value_parser = super::weight)]
    pub w_heading: Option<f64>,
    /// The longest path a query may return is max(2 × --time, --time +
    /// this many seconds): a target out of reach gets Eq. 7's best
    /// compromise within that horizon (Eq. 7 alone can ask for a path
    /// hundreds of times longer than the target, e.g. 1000 m in 3 s).
    #[arg(long, value_name = "S", default_value_t = 10.0, value_parser = horizon)]
    pub horizon: f64,
    /// Prefer a path within this percentage of both the distance and the
    /// time target over a cheaper one (Eq. 7) that is not, when the graph
    /// has one (0: Eq. 7 alone).
    #[arg(long, value_name = "PCT", default_value_t = 1.0, value_parser = super::non_negative)]
    pub within: f64,
    #[command(flatten)]
    pub clip: super::ClipOpts,
    /// Target travel distance in metres (0: as short as possible): one
    /// value for the whole path (split optimally over its segments), or a
    /// comma list with one per segment.
    #[arg(
        long,
        value_name = "M",
        allow_hyphen_values = true,
        required_unless_present_any = ["grid", "floor"]
    )]
    pub distance: Option<String>,
    /// Target time in seconds (0: as short as possible); one value or one
    /// per segment.
    #[arg(
        long,
        value_name = "S",
        allow_hyphen_values = true,
        required_unless_present_any = ["grid", "floor"]
    )]
    pub time: Option<String>,
    /// Output: .glb, .pc2 (+ .obj), .mdd, or a folder of OBJ frames.
    #[arg(short, long, required_unless_present_any = ["grid", "floor"])]
    pub output: Option<PathBuf>,
    /// Write -o into a folder that already holds files (its OBJ frames are
    /// replaced).
    #[arg(long)]
    pub force: bool,
    /// Write the JSON report: path (segments, loops, repetitions), cost
    /// terms, achieved distance and time, transitions and smoothness,
    /// search time.
    #[arg(long, value_name = "JSON")]
    pub report: Option<PathBuf>,
    /// Weight of the distance error, per metre. Default: 1/0.3 (the paper).
    #[arg(long, value_parser = super::weight)]
    pub w_dist: Option<f64>,
    /// Weight of the time error, per frame. Default: 1/10 (the paper).
    #[arg(long, value_parser = super::weight)]
    pub w_time: Option<f64>,
    /// Optimality gap of the search (cost units: 1 = 30 cm of distance or
    /// 10 frames at the default weights; 0: the exact optimum).
    #[arg(long, default_value_t = 0.03, value_parser = super::non_negative)]
    pub gap: f64,
    /// Most distinct loops handed to one repetition problem (the slowest,
    /// the fastest and the cheapest per frame are kept).
    #[arg(long, default_value_t = 64)]
    pub max_loops: usize,
    /// Loop repetition solver (of the walks-and-loops search).
    #[arg(long, value_enum, default_value_t = SolverArg::Exact)]
    pub solver: SolverArg,
    /// What a transition costs (Eq. 8): the graph's shape distortion (the
    /// paper), or its measured smoothness in metres (weighted Hausdorff
    /// distance of the blended frames; computed once per run, a few seconds
    /// on a large graph).
    #[arg(long, value_enum, default_value_t = CostArg::Graph)]
    pub transition_cost: CostArg,
    /// Which transitions the path may take: the graph's, or the local
    /// minima of the similarity matrix re-chosen (top N per sequence pair)
    /// and priced by their measured smoothness, with their windows
    /// (`--transition-cost` is then unused; the graph, and so `retarget`,
    /// is unchanged).
    #[arg(long, value_enum, default_value_t = TransitionsArg::Graph)]
    pub transitions: TransitionsArg,
    /// Which search finds the path.
    #[arg(long, value_enum, default_value_t = MethodArg::Lattice)]
    pub search: MethodArg,
    /// Distance bins kept per (node, frame count) by the exact-length
    /// search (more: slower, closer to the optimum).
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub bins: u32,
    /// No blending across transitions.
    #[arg(long)]
    pub no_blend: bool,
    /// Evaluate over a grid of targets instead (Table III): every
    /// --distances × --times, one query each; prints the errors, the
    /// smoothness and the query time.
    #[arg(long)]
    pub grid: bool,
    /// Grid distances (metres), A:B:STEP or a comma list.
    #[arg(long, default_value = DEFAULT_DISTANCES, allow_hyphen_values = true)]
    pub distances: String,
    /// Grid times (seconds), A:B:STEP or a comma list.
    #[arg(long, default_value = DEFAULT_TIMES, allow_hyphen_values = true)]
    pub times: String,
    /// With --grid: a heat-map of the errors over the grid (.svg with
    /// axes and legend, or .png).
    #[arg(long, value_name = "FILE", requires = "grid", value_parser = plot_path)]
    pub plot: Option<PathBuf>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    /// Print the smoothness floor instead (Sec. 6.1's measure over every
    /// frame pair and window of the database, and the least mean
    /// smoothness of a path between each pair of consecutive key-frames;
    /// `keyframe::floor`).
    #[arg(long, conflicts_with = "grid")]
    pub floor: bool,
    /// With --grid: print instead, per target, the least mean smoothness
    /// of any path within 1 % of both the distance and the time (the
    /// floor of the grid's smoothness figure: Dinkelbach's method over
    /// the exact-length search, the graph's transitions priced by their
    /// measured smoothness), with an exact lower bound (a Lagrangian
    /// relaxation of the distance band); `keyframe::smoothest`. Without
    /// a heading target; no heat-map.
    #[arg(long, requires = "grid", conflicts_with_all = ["plot", "heading"])]
    pub least_mean: bool,
}

/// The grid's distances by default (metres; the paper's Table III).
const DEFAULT_DISTANCES: &str = "1:20:1";
/// The grid's times by default (seconds).
const DEFAULT_TIMES: &str = "1:40:1";

/// `--horizon`: seconds in [0, MAX_TARGET_SECONDS] (`--horizon 1e7`
/// aborted on a 216 GB allocation).
fn horizon(s: &str) -> Result<f64, String> {
    use surfmotion::keyframe::MAX_TARGET_SECONDS;
    let v = super::non_negative(s)?;
    if v <= MAX_TARGET_SECONDS {
        Ok(v)
    } else {
        Err(format!("{s}: at most {MAX_TARGET_SECONDS} seconds"))
    }
}

/// `--heading`: degrees in [-360, 360] (`--heading 1e308` was taken and
/// printed back as a 309-digit target).
fn heading(s: &str) -> Result<f64, String> {
    let v = super::finite(s)?;
    if v.abs() <= 360.0 {
        Ok(v)
    } else {
        Err(format!("{s}: expected degrees in [-360, 360]"))
    }
}

/// `--plot`: a `.svg` or a `.png` (`--plot g.txt` ran the whole grid,
/// then wrote a PNG into g.txt).
fn plot_path(s: &str) -> Result<PathBuf, String> {
    let p = PathBuf::from(s);
    if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("svg")) {
        Ok(p)
    } else {
        super::png_path(s).map_err(|_| format!("{s}: expected a .svg or .png file name"))
    }
}

/// The grid's targets, parsed and bounded as a single query's are.
fn grid_targets(a: &Args) -> anyhow::Result<(Vec<f64>, Vec<f64>)> {
    use surfmotion::keyframe::{MAX_TARGET_METRES, MAX_TARGET_SECONDS};
    let ds = parse_range(&a.distances).map_err(|e| anyhow::anyhow!("--distances {e}"))?;
    let ts = parse_range(&a.times).map_err(|e| anyhow::anyhow!("--times {e}"))?;
    for (flag, v, max, unit) in [
        ("--distances", &ds, MAX_TARGET_METRES, "m"),
        ("--times", &ts, MAX_TARGET_SECONDS, "s"),
    ] {
        if let Some(x) = v.iter().find(|x| **x > max) {
            // `{x}` of 1e308 is 309 digits.
            let x = if *x < 1e9 {
                x.to_string()
            } else {
                format!("{x:e}")
            };
            anyhow::bail!(
                "{flag} {x}: at most {max} {unit} (the search's horizon grows with the target)"
            );
        }
    }
    Ok((ds, ts))
}

/// `--distance`/`--time`: a number or a comma list. A value above the
/// search's bound is refused here, quoted as typed (`--distance 1e308` was
/// printed back as 309 digits).
fn numbers(what: &str, s: &str) -> anyhow::Result<Vec<f64>> {
    use surfmotion::keyframe::{MAX_TARGET_METRES, MAX_TARGET_SECONDS};
    let (max, unit) = if what == "distance" {
        (MAX_TARGET_METRES, "m")
    } else {
        (MAX_TARGET_SECONDS, "s")
    };
    s.split(',')
        .map(|x| {
            let v = x.trim().parse::<f64>().map_err(|_| {
                anyhow::anyhow!("--{what} '{s}': expected a number or a comma list")
            })?;
            anyhow::ensure!(
                v.is_nan() || v <= max,
                "--{what} {}: at most {max} {unit} (the search's horizon grows with the target)",
                x.trim()
            );
            Ok(v)
        })
        .collect()
}

/// Runs `keyframe`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let mut outputs = Vec::new();
    if let Some(o) = &a.output {
        super::check_mesh_output(o)?;
        outputs = super::mesh_outputs(o);
    }
    outputs.extend(a.report.clone().map(|p| ("--report", p)));
    outputs.extend(a.plot.clone().map(|p| ("--plot", p)));
    let mut inputs = super::database_inputs(&a.db);
    inputs.extend(a.clip.asf.clone());
    inputs.extend(a.clip.rig_map.clone());
    super::refuse_colliding(&inputs, &outputs)?;
    if let Some(o) = &a.output {
        super::check_folder_output(o, a.force, &inputs)?;
    }
    if a.grid || a.floor {
        // Refused before the database loads (and its graph builds).
        let (ds, ts) = grid_targets(&a)?;
        if a.grid {
            // 8.9e9 targets aborted on a 1.28 TB allocation (issue 46.4).
            surfmotion::keyframe::grid::check_grid(ds.len(), ts.len())
                .map_err(|e| anyhow::anyhow!("--distances × --times: {e}"))?;
        }
    } else if a.distances != DEFAULT_DISTANCES || a.times != DEFAULT_TIMES {
        // Ignored without a word (`--times NaN` ran the single query).
        anyhow::bail!(
            "--distances and --times are the grid's (with --grid or --floor); one query takes --distance and --time"
        );
    }
    let ch = Character::load(&a.db, &super::db::Bars::new())?;
    let load = a.clip.load_options()?;
    let mut resolved = Vec::new();
    let mut key = |k: &str| -> anyhow::Result<u32> {
        if pose::is_pose_key(k) {
            let p = pose::read_pose(&ch, k, &load)?;
            // A pose of joints 1e308 m away resolved to walk:0 at "NaN m",
            // and 19 joints at one point to the frame least unlike a point.
            let span = p
                .iter()
                .flat_map(|a| p.iter().map(move |b| a.distance(*b)))
                .fold(0.0, f64::max);
            anyhow::ensure!(
                span.is_finite() && span <= 100.0,
                "key-frame '{k}': its joints span {} m: expected a body's 19 joints in metres, Y up",
                surfmotion::util::numfmt::Short(span)
            );
            anyhow::ensure!(
                span > 0.01,
                "key-frame '{k}': its 19 joints are at one point: expected a body's joints in metres, Y up"
            );
            let r = pose::nearest_frame(&ch, k, &p);
            let id = r.id;
            resolved.push(r);
            Ok(id)
        } else {
            Ok(parse_key(&ch, k)?)
        }
    };
    let mut keys = vec![key(&a.from)?];
    for v in &a.via {
        keys.push(key(v)?);
    }
    keys.push(key(&a.to)?);
    let defaults = Weights::default();
    let opts = KeyframeOptions {
        search: SearchOptions {
            weights: Weights {
                distance: a.w_dist.unwrap_or(defaults.distance),
                time: a.w_time.unwrap_or(defaults.time),
            },
            solver: match a.solver {
                SolverArg::Exact => Solver::Exact,
                SolverArg::Ilp => Solver::Ilp,
            },
            gap: a.gap,
            method: match a.search {
                MethodArg::Lattice => Method::Lattice,
                MethodArg::Walks => Method::Walks,
            },
            lattice: surfmotion::keyframe::lattice::LatticeOptions {
                bins: a.bins as usize,
                within: a.within / 100.0,
                ..Default::default()
            },
            heading: a
                .heading
                .map(|d| surfmotion::keyframe::lattice::HeadingTarget {
                    degrees: d,
                    weight: a.w_heading.unwrap_or(1.0 / 30.0),
                    sectors: 8,
                }),
            limits: surfmotion::keyframe::search::Limits {
                loops_per_walk: a.max_loops.max(2),
                ..Default::default()
            },
            horizon: surfmotion::keyframe::search::Horizon {
                factor: 2.0,
                slack: a.horizon * ch.manifest().fps,
            },
            ..Default::default()
        },
        timeline: surfmotion::retarget::timeline::TimelineOptions {
            blend: !a.no_blend,
            ..Default::default()
        },
        transition_cost: match a.transition_cost {
            CostArg::Graph => TransitionCost::Graph,
            CostArg::Smoothness => TransitionCost::Smoothness,
        },
        transitions: match a.transitions {
            TransitionsArg::Graph => surfmotion::keyframe::TransitionSet::Graph,
            TransitionsArg::Measured => surfmotion::keyframe::TransitionSet::Measured,
        },
    };
    let mut head = String::new();
    for r in &resolved {
        head += &format!(
            "key-frame {}: nearest database frame {} (skeleton distance {:.3} m{})\n",
            r.key,
            r.frame,
            r.distance,
            r.runner_up
                .as_ref()
                .map_or(String::new(), |(f, d)| format!("; next {f} at {d:.3} m"))
        );
    }
    if a.grid {
        return grid(&ch, &keys, &a, &opts, &head);
    }
    if a.floor {
        return floor(&ch, &keys, &a, &opts, &head);
    }
    let (Some(d), Some(t), Some(out)) = (&a.distance, &a.time, &a.output) else {
        anyhow::bail!("--distance, --time and -o are needed (or --grid, --floor)");
    };
    let targets = Targets::from_lists(
        &numbers("distance", d)?,
        &numbers("time", t)?,
        keys.len() - 1,
    )?;
    // 10-20 s on the README's synth3 (preparing, searching, blending the
    // meshes) with nothing on the screen before.
    let bar = if a.json {
        indicatif::ProgressBar::hidden()
    } else {
        super::spinner("finding the path and blending its meshes")
    };
    let o = write_path(&ch, &keys, &targets, &opts, out, &bar);
    bar.finish_and_clear();
    let (mut o, written) = o?;
    o.report.poses = resolved;
    let fps = ch.manifest().fps;
    let r = &o.report;
    let missed = missed_targets(r);
    // The report and --json say which targets were missed, as the text does.
    let mut v = serde_json::to_value(r)?;
    v["missed"] = serde_json::to_value(&missed)?;
    if let Some(p) = &a.report {
        surfmotion::util::fsutil::write_bytes_atomic(
            p,
            serde_json::to_string_pretty(&v)?.as_bytes(),
        )?;
    }
    if a.json {
        v["output"] = serde_json::to_value(&written)?;
        return super::emit(&(serde_json::to_string_pretty(&v)? + "\n"));
    }
    let mut s = head;
    s += &format!(
        "{} -> {}: {} at {} fps\n",
        r.keys.join(" -> "),
        super::written_list(&written, ", "),
        super::count(r.frames, "frame"),
        fps
    );
    s += &format!("achieved: {:.3} m in {:.3} s", r.distance, r.time);
    let mut compromise = None;
    if let (Some(de), Some(te)) = (r.distance_error, r.time_error) {
        s += &format!(" (error {de:+.3} m, {te:+.3} s)");
        // Flag a compromise: an error over 1 % of a non-zero target.
        if missed.contains(&"distance") || missed.contains(&"time") {
            compromise = Some((r.distance - de, r.time - te));
        }
    }
    s += "\n";
    if let Some((dt, tt)) = compromise {
        s += &format!(
            "not met within 1 %: {}\n",
            match r.reach {
                // The key-frames' own path is longer than the target's
                // horizon: it is taken as it is, no compromise is searched
                // (1000 --via gave "within the 13.0 s horizon" for 55.6 s).
                Some(x) if r.time > x.horizon + 0.5 / fps => format!(
                    "the path through the {} key-frames takes {:.1} s, longer than the {:.1} s horizon of {dt:.3} m in {tt:.3} s, and is taken as it is (fewer or nearer --via shorten it)",
                    r.keys.len(),
                    r.time,
                    x.horizon
                ),
                reach => format!(
                    "the best compromise for {dt:.3} m in {tt:.3} s under Eq. 7 within {} (the graph may not reach it; --w-dist and --w-time weigh the two)",
                    reach.map_or("the horizon".to_string(), |x| format!(
                        "the {:.1} s horizon",
                        x.horizon
                    ))
                ),
            }
        );
        if let Some(x) = r.reach {
            s += &format!(
                "reach: paths of {tt:.3} s travel {}; {dt:.3} m needs {}; at most {} within the horizon\n",
                x.at_time.map_or(
                    "- (no path has exactly that length)".to_string(),
                    |(a, b)| format!("{a:.3}-{b:.3} m")
                ),
                match (x.min_time, x.max_in_horizon) {
                    (Some(m), _) => format!("at least {m:.2} s"),
                    // Paths within the horizon travel farther, but no one
                    // length's range holds the distance within 1 % (it is
                    // below every path's, or between two lengths').
                    (None, Some(most)) if most >= dt => format!(
                        "a path length none within the {:.1} s horizon has (none of their distance ranges holds it)",
                        x.horizon
                    ),
                    (None, _) => format!("more than {:.1} s", x.horizon),
                },
                x.max_in_horizon
                    .map_or("-".to_string(), |m| format!("{m:.3} m"))
            );
        }
    }
    s += &format!("final facing {:+.1}°", r.final_facing_deg);
    if let (Some(h), Some(e)) = (r.heading_target_deg, r.heading_error_deg) {
        s += &format!(" (target {h:+.1}°, error {e:+.1}°)");
    }
    s += "\n";
    if let (true, Some(h)) = (missed.contains(&"heading"), r.heading_target_deg) {
        s += &format!(
            "heading not met within {HEADING_TOLERANCE_DEG}° (1 % of a turn): {:+.1}° for {h:+.1}°, the best compromise under Eq. 7 (the graph's transitions may not turn that far in this time; --w-heading weighs it against distance and time)\n",
            r.final_facing_deg
        );
    }
    s += &format!(
        "cost: transitions {:.4} + distance {:.4} + time {:.4}{} = {:.4}\n",
        r.cost.transition,
        r.cost.distance,
        r.cost.time,
        if r.heading_target_deg.is_some() {
            format!(" + heading {:.4}", r.cost.heading)
        } else {
            String::new()
        },
        r.cost.total
    );
    // Per-segment targets: each segment's target and error (the summary
    // printed the achieved totals alone, with no word that 11.6 m in 6.5 s
    // missed 5 m in 4 s twice).
    let mut missed_segments = 0;
    for seg in &r.segments {
        s += &format!(
            "segment {} -> {}: {:.3} m, {:.3} s",
            seg.from, seg.to, seg.distance, seg.time
        );
        if let (Some(td), Some(tt)) = (seg.target_distance, seg.target_time) {
            let (de, te) = (seg.distance - td, seg.time - tt);
            s += &format!(" (target {td:.3} m, {tt:.3} s; error {de:+.3} m, {te:+.3} s)");
            if (td > 0.0 && de.abs() > 0.01 * td) || (tt > 0.0 && te.abs() > 0.01 * tt) {
                missed_segments += 1;
            }
        }
        s += &format!("; walk {}", seg.walk.join(" "));
        for l in &seg.loops {
            s += &format!("; loop at {} ({}) x{}", l.at, l.frames.join(" "), l.repeats);
        }
        s += "\n";
    }
    if missed_segments > 0 {
        s += &format!(
            "not met within 1 % in {} of {}: the best compromise under Eq. 7 (the graph may not reach them; --w-dist and --w-time weigh the two)\n",
            super::count(missed_segments, "segment"),
            r.segments.len()
        );
    }
    s += &format!(
        "{}, smoothness {}\n",
        super::count(r.transitions.len(), "transition"),
        r.smoothness
            .map_or("- (none)".to_string(), |x| format!("{x:.4} m"))
    );
    s += &format!(
        "search: {} nodes, {}, {} solved, {} pruned; {:.1} ms preparing, {:.1} ms searching{}, {:.2} s meshes\n",
        r.stats.nodes,
        super::count(r.stats.cycles, "loop"),
        super::count(r.stats.walks, "walk"),
        r.stats.pruned,
        1e3 * r.prepare_seconds,
        1e3 * r.search_seconds,
        r.search_cpu_seconds
            .map_or(String::new(), |c| format!(" ({:.1} ms CPU)", 1e3 * c)),
        r.mesh_seconds
    );
    for b in &r.stats.bounds_hit {
        s += &format!("bound hit: {b}\n");
    }
    super::emit(&s)
}

/// Finds the path and writes its meshes to `out` frame by frame (a
/// [`SequenceWriter`]: point caches and OBJ folders stream, a GLB is
/// checked against the memory budget before the first frame is made);
/// returns the report and the files written. Every frame was held, then
/// the whole file's bytes (attack s14, item 3: 8.6 MB per output second,
/// 7.1 GB for an hour).
fn write_path(
    ch: &Character,
    keys: &[u32],
    targets: &Targets,
    opts: &KeyframeOptions,
    out: &std::path::Path,
    bar: &indicatif::ProgressBar,
) -> anyhow::Result<(Streamed, Vec<PathBuf>)> {
    let planned = plan_path(ch, keys, targets, opts, &mut |what| {
        bar.set_message(what.to_string())
    })?;
    let total = planned.frames();
    let fps = ch.manifest().fps;
    let mut writer = SequenceWriter::create(
        &ch.topology_metres(),
        out,
        planned.frames(),
        &SaveOptions {
            fps: Some(fps),
            ..Default::default()
        },
    )
    .map_err(|e| {
        // "a GLB of 16,559 frames would need 11.9 GB" for `--time 3600`
        // without a word that the search had stopped short of the target
        // (issue 46.12).
        let notes = planned.bounds_hit();
        if notes.is_empty() {
            anyhow::Error::from(e)
        } else {
            anyhow::anyhow!(
                "{e} (the path found has {total} frames; search bound: {})",
                notes.join("; ")
            )
        }
    })?;
    let s = planned.synthesise_each(ch, targets, opts, |k, p| -> anyhow::Result<()> {
        if k % 16 == 0 {
            bar.set_message(format!(
                "blending and writing the meshes: frame {k}/{total}"
            ));
        }
        if k + 1 == total {
            bar.set_message("measuring the transitions' smoothness");
        }
        Ok(writer.push(p)?)
    })?;
    Ok((s, writer.finish()?))
}

/// A heading target is flagged when the final facing misses it by more
/// than this (degrees): 1 % of a turn, as distance and time are flagged
/// beyond 1 % of their targets.
pub const HEADING_TOLERANCE_DEG: f64 = 3.6;

/// The targets a path misses: "distance" or "time" by more than 1 % of a
/// non-zero target, "heading" by more than [`HEADING_TOLERANCE_DEG`].
fn missed_targets(r: &surfmotion::keyframe::Report) -> Vec<&'static str> {
    let mut out = Vec::new();
    if let (Some(de), Some(te)) = (r.distance_error, r.time_error) {
        let (dt, tt) = (r.distance - de, r.time - te);
        if dt > 0.0 && de.abs() > 0.01 * dt {
            out.push("distance");
        }
        if tt > 0.0 && te.abs() > 0.01 * tt {
            out.push("time");
        }
    }
    if r.heading_error_deg
        .is_some_and(|e| e.abs() > HEADING_TOLERANCE_DEG)
    {
        out.push("heading");
    }
    out
}

fn grid(
    ch: &Character,
    keys: &[u32],
    a: &Args,
    opts: &KeyframeOptions,
    head: &str,
) -> anyhow::Result<()> {
    if a.least_mean {
        return least_mean(ch, keys, a, opts, head);
    }
    let mut planner = Planner::new(key_graph(ch, opts), keys, ch.manifest().fps, &opts.search)
        .map_err(|e| anyhow::anyhow!(describe(ch, &e)))?;
    planner.facing = surfmotion::keyframe::facing_change(ch, keys);
    let (ds, ts) = grid_targets(a)?;
    // Minutes on a large database with nothing on the screen before, and
    // no word of how long (issue 46.4): a bar with its ETA on a terminal,
    // and each target's row printed as it finishes (none with --json).
    let bar = if a.json {
        indicatif::ProgressBar::hidden()
    } else {
        super::progress((ds.len() * ts.len()) as u64, "grid queries")
    };
    if !a.json {
        super::emit(
            &(head.to_string()
                + "distance (m)  time (s)  achieved (m)  achieved (s)  within 1 %  reach  ms\n"),
        )?;
    }
    let mut closed = false;
    let g = evaluate_with(
        ch,
        &planner,
        &ds,
        &ts,
        &opts.search,
        &opts.timeline,
        &mut |q| {
            bar.inc(1);
            if !a.json && !closed {
                let row = format!(
                    "{} {} {:.3} {:.3} {} {} {:.1}\n",
                    q.distance,
                    q.time,
                    q.achieved_distance,
                    q.achieved_time,
                    if q.within_1pct { "yes" } else { "no" },
                    serde_json::to_value(q.reach)
                        .ok()
                        .and_then(|v| v.as_str().map(str::to_string))
                        .unwrap_or_default(),
                    1e3 * q.seconds
                );
                closed = bar.suspend(|| super::emit(&row)).is_err();
            }
        },
    );
    bar.finish_and_clear();
    let g = g.map_err(|e| anyhow::anyhow!(describe(ch, &e)))?;
    if let Some(p) = &a.report {
        surfmotion::util::fsutil::write_bytes_atomic(
            p,
            serde_json::to_string_pretty(&g)?.as_bytes(),
        )?;
    }
    if let Some(p) = &a.plot {
        surfmotion::keyframe::heatmap::save(&g, p)?;
    }
    if a.json {
        let mut v = serde_json::to_value(&g)?;
        if let Some(o) = v.as_object_mut() {
            o.remove("queries");
        }
        return super::emit(&(serde_json::to_string_pretty(&v)? + "\n"));
    }
    super::emit(&grid_text(&g))
}

/// `--grid --least-mean`: the least mean smoothness per target
/// (`keyframe::smoothest::floor_grid`).
fn least_mean(
    ch: &Character,
    keys: &[u32],
    a: &Args,
    opts: &KeyframeOptions,
    head: &str,
) -> anyhow::Result<()> {
    use surfmotion::keyframe::smoothest::{Summary, floor_grid_with};
    let priced = KeyframeOptions {
        transition_cost: TransitionCost::Smoothness,
        ..*opts
    };
    let planner = Planner::new(
        key_graph(ch, &priced),
        keys,
        ch.manifest().fps,
        &opts.search,
    )
    .map_err(|e| anyhow::anyhow!(describe(ch, &e)))?;
    let (ds, ts) = grid_targets(a)?;
    // A 100 × 100 grid ran for many minutes with no output (issue 46.4):
    // a bar with its ETA, and each target's row as it finishes.
    let bar = if a.json {
        indicatif::ProgressBar::hidden()
    } else {
        super::progress(
            (ds.len() * ts.len()) as u64,
            "targets: least mean smoothness",
        )
    };
    if !a.json {
        super::emit(
            &(head.to_string()
                + "distance (m)  time (s)  reachable  least mean (m)  lower bound (m)  s\n"),
        )?;
    }
    let t0 = std::time::Instant::now();
    let mut closed = false;
    let opt = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.4}"));
    let r = floor_grid_with(
        ch,
        &planner,
        &ds,
        &ts,
        &opts.search.lattice,
        &opts.timeline,
        &mut |q| {
            bar.inc(1);
            if !a.json && !closed {
                let row = format!(
                    "{} {} {} {} {} {:.2}\n",
                    q.distance,
                    q.time,
                    if q.reachable { "yes" } else { "no" },
                    opt(q.least_mean),
                    opt(q.lower_bound),
                    q.seconds
                );
                closed = bar.suspend(|| super::emit(&row)).is_err();
            }
        },
    );
    bar.finish_and_clear();
    let r = r.map_err(|e| anyhow::anyhow!(describe(ch, &e)))?;
    if let Some(p) = &a.report {
        surfmotion::util::fsutil::write_bytes_atomic(
            p,
            serde_json::to_string_pretty(&r)?.as_bytes(),
        )?;
    }
    if a.json {
        let mut v = serde_json::to_value(&r)?;
        if let Some(o) = v.as_object_mut() {
            o.remove("queries");
        }
        return super::emit(&(serde_json::to_string_pretty(&v)? + "\n"));
    }
    let sum = |s: &Option<Summary>| match s {
        Some(s) => format!(
            "mean {:.4} m, median {:.4}, min {:.4}, max {:.4} (over {})",
            s.mean, s.median, s.min, s.max, s.n
        ),
        None => "-".to_string(),
    };
    let text = format!(
        "least mean smoothness of a path within 1 % of distance and time, over the reachable targets ({} reachable, {} with such a path found, {:.1} s):\n  priced (each transition at its own window): {}\n  as the grid measures it: {}\n  exact lower bound (Lagrangian relaxation of the distance band): {}\n",
        r.reachable,
        r.kept,
        t0.elapsed().as_secs_f64(),
        sum(&r.least_mean),
        sum(&r.least_mean_measured),
        sum(&r.lower_bound),
    );
    super::emit(&text)
}

/// `--floor`: the transition floor of the database and the path floor
/// between consecutive key-frames, for paths of at most as many
/// transitions as the longest `--times` can hold (one per 4 frames, the
/// search's spacing; at most 250).
fn floor(
    ch: &Character,
    keys: &[u32],
    a: &Args,
    opts: &KeyframeOptions,
    head: &str,
) -> anyhow::Result<()> {
    use surfmotion::keyframe::floor::{FloorOptions, path_floor, transition_floor_with};
    let (_, ts) = grid_targets(a)?;
    let fps = ch.manifest().fps;
    let longest = ts.iter().copied().fold(0.0, f64::max);
    let k_max = ((longest * fps / 4.0).ceil() as usize).clamp(1, 250);
    // Progress on a terminal, none with --json (116 s on synth3 with
    // nothing on the screen).
    let spin = |what: &str| {
        if a.json {
            indicatif::ProgressBar::hidden()
        } else {
            super::spinner(what)
        }
    };
    let sp = spin("measuring the frames' surfaces");
    let frames = surfmotion::keyframe::smoothness::FrameSet::new(ch);
    sp.finish_and_clear();
    let fopts = FloorOptions::of_graph(&ch.graph().options);
    let bar = if a.json {
        indicatif::ProgressBar::hidden()
    } else {
        super::progress(0, "frame pairs: transition floor")
    };
    let t = transition_floor_with(ch, &frames, &fopts, &mut |done, total| {
        bar.set_length(total);
        bar.set_position(done);
    });
    bar.finish_and_clear();
    let sp = spin("pricing the graph by smoothness; path floors");
    let priced = KeyframeOptions {
        transition_cost: TransitionCost::Smoothness,
        ..*opts
    };
    let graph = key_graph(ch, &priced);
    let all = surfmotion::keyframe::graph::KeyGraph::of_character_with(ch, Some(&t.bounds));
    let name = |f: u32| {
        let (s, i) = ch.graph().frame_of(f);
        format!("{}:{i}", ch.graph().sequences[s].name)
    };
    let paths: Vec<serde_json::Value> = keys
        .windows(2)
        .map(|w| {
            serde_json::json!({
                "from": name(w[0]),
                "to": name(w[1]),
                "max_transitions": k_max,
                "graph": path_floor(&graph, w[0], w[1], k_max),
                "every_frame_pair": path_floor(&all, w[0], w[1], k_max),
            })
        })
        .collect();
    if a.json {
        sp.finish_and_clear();
        let v = serde_json::json!({ "transitions": t, "paths": paths });
        return super::emit(&(serde_json::to_string_pretty(&v)? + "\n"));
    }
    let win = |w: &Option<surfmotion::keyframe::floor::Window>| {
        w.as_ref().map_or("none".to_string(), |w| {
            format!(
                "{:.4} m ({}:{} ~ {}:{}, L = {})",
                w.smoothness, w.from, w.m, w.to, w.n, w.window
            )
        })
    };
    let mut s = head.to_string();
    s += &format!(
        "transition floor over {} frame pairs (L in [{}, {}], gap {} within a sequence): {}\n",
        t.candidates,
        fopts.min_window,
        fopts.max_window,
        fopts.min_gap,
        win(&t.best)
    );
    for p in &t.pairs {
        s += &format!(
            "  {} ~ {}: {}; <= {} m: {} distinct transitions ({} frame pairs by the bound); {} windows measured in full\n",
            p.a,
            p.b,
            win(&p.best),
            t.threshold,
            p.under_distinct,
            p.under_bound,
            p.measured
        );
    }
    for w in keys.windows(2) {
        for (what, g) in [
            ("graph transitions", &graph),
            ("every frame pair (bound)", &all),
        ] {
            let p = path_floor(g, w[0], w[1], k_max);
            let by = |k: usize| {
                p.by_count
                    .get(k - 1)
                    .copied()
                    .flatten()
                    .map_or("-".to_string(), |v| format!("{v:.4}"))
            };
            s += &format!(
                "path floor {} -> {}, {what}: k=1 {}, k=2 {}, k=3 {}; least over k <= {k_max}: {}{}\n",
                name(w[0]),
                name(w[1]),
                by(1),
                by(2),
                by(3),
                p.best
                    .map_or("none".to_string(), |(k, v)| format!("{v:.4} m (k = {k})")),
                if p.direct {
                    "; a path without transitions exists"
                } else {
                    ""
                }
            );
        }
    }
    sp.finish_and_clear();
    super::emit(&s)
}

fn grid_text(g: &GridReport) -> String {
    let n = g.queries.len();
    let mut s = format!(
        "{}: {} {} ({} distances x {} times)\n",
        g.keys.join(" -> "),
        n,
        if n == 1 { "query" } else { "queries" },
        g.distances.len(),
        g.times.len()
    );
    s += &format!(
        "reachable (some path within 1 % of both): {}; unreachable: {} ({} out of range, {} in a gap of the achievable distances; best compromise returned, flagged)\n",
        g.reachable.distance_m.count, g.unreachable.distance_m.count, g.out_of_range, g.gaps
    );
    for (what, e) in [("reachable", &g.reachable), ("unreachable", &g.unreachable)] {
        if e.distance_m.count == 0 {
            s += &format!("{what}: none\n");
            continue;
        }
        s += &format!(
            "{what} ({}): distance error min/rms/max {:.4}/{:.4}/{:.4} m = {:.3}/{:.3}/{:.3} %; time error {:.3}/{:.3}/{:.3} s = {:.3}/{:.3}/{:.3} %; {} within 1 %\n",
            e.distance_m.count,
            e.distance_m.min,
            e.distance_m.rms,
            e.distance_m.max,
            e.distance_pct.min,
            e.distance_pct.rms,
            e.distance_pct.max,
            e.time_s.min,
            e.time_s.rms,
            e.time_s.max,
            e.time_pct.min,
            e.time_pct.rms,
            e.time_pct.max,
            e.within_1pct
        );
    }
    if !g.missed.is_empty() {
        s += &format!(
            "reachable but missed by the search: {}\n",
            g.missed
                .iter()
                .map(|(d, t)| format!("{d} m in {t} s"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    s += &format!(
        "smoothness min/mean/max {:.4}/{:.4}/{:.4} m (vertex-set Hausdorff: mean {:.4} m) over {} queries with transitions; the graph's {} transitions: min/median/max {:.4}/{:.4}/{:.4} m\n",
        g.smoothness.min,
        g.smoothness_mean,
        g.smoothness.max,
        g.smoothness_vertex_mean,
        g.smoothness.count,
        g.graph_smoothness.count,
        g.graph_smoothness.min,
        g.graph_smoothness_median,
        g.graph_smoothness.max
    );
    let cpu = match (g.query_cpu_ms_mean, g.query_cpu_ms_std, g.query_cpu_ms_max) {
        (Some(m), Some(sd), Some(x)) => format!(" (CPU {m:.2} ± {sd:.2} ms, max {x:.1} ms)"),
        _ => String::new(),
    };
    s += &format!(
        "query time {:.2} ± {:.2} ms (max {:.1} ms){cpu}; preparation {:.1} ms once; {} hit a search bound; reachability oracle {:.0} ms in all\n",
        g.query_ms_mean, g.query_ms_std, g.query_ms_max, g.prepare_ms, g.bounded, g.oracle_ms
    );
    s
}
