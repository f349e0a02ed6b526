//! The arguments of `surfmotion keyframe`, their defaults those of
//! [`KeyframeJobOptions::DEFAULT`].

use std::path::PathBuf;
use surfmotion::jobs::keyframe::{DEFAULT_DISTANCES, DEFAULT_TIMES, KeyframeJobOptions};

/// The job's defaults, which the arguments' are.
const D: KeyframeJobOptions = KeyframeJobOptions::DEFAULT;

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
    #[arg(long, value_name = "DEG", allow_hyphen_values = true, value_parser = crate::cli::heading)]
    pub heading: Option<f64>,
    /// Weight of the heading error, per degree. Default: 1/30 (30° cost as
    /// much as 0.3 m of distance).
    #[arg(long, value_parser = crate::cli::weight)]
    pub w_heading: Option<f64>,
    /// The longest path a query may return is max(2 × --time, --time +
    /// this many seconds): a target out of reach gets Eq. 7's best
    /// compromise within that horizon (Eq. 7 alone can ask for a path
    /// hundreds of times longer than the target, e.g. 1000 m in 3 s).
    #[arg(long, value_name = "S", default_value_t = D.horizon_seconds, value_parser = crate::cli::horizon)]
    pub horizon: f64,
    /// Prefer a path within this percentage of both the distance and the
    /// time target over a cheaper one (Eq. 7) that is not, when the graph
    /// has one (0: Eq. 7 alone).
    #[arg(long, value_name = "PCT", default_value_t = D.within_pct, value_parser = crate::cli::non_negative)]
    pub within: f64,
    #[command(flatten)]
    pub clip: crate::cli::ClipOpts,
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
    #[command(flatten)]
    pub glb: crate::cli::mesh::SequenceOutputArgs,
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
    #[arg(long, value_parser = crate::cli::weight)]
    pub w_dist: Option<f64>,
    /// Weight of the time error, per frame. Default: 1/10 (the paper).
    #[arg(long, value_parser = crate::cli::weight)]
    pub w_time: Option<f64>,
    /// Optimality gap of the search (cost units: 1 = 30 cm of distance or
    /// 10 frames at the default weights; 0: the exact optimum).
    #[arg(long, default_value_t = D.gap, value_parser = crate::cli::non_negative)]
    pub gap: f64,
    /// Most distinct loops handed to one repetition problem (the slowest,
    /// the fastest and the cheapest per frame are kept).
    #[arg(long, default_value_t = D.max_loops)]
    pub max_loops: usize,
    /// Loop repetition solver (of the walks-and-loops search).
    #[arg(long, value_enum, default_value_t = SolverArg::from(D.solver))]
    pub solver: SolverArg,
    /// What a transition costs (Eq. 8): the graph's shape distortion (the
    /// paper), or its measured smoothness in metres (weighted Hausdorff
    /// distance of the blended frames; computed once per run, a few seconds
    /// on a large graph).
    #[arg(long, value_enum, default_value_t = CostArg::from(D.transition_cost))]
    pub transition_cost: CostArg,
    /// Which transitions the path may take: the graph's, or the local
    /// minima of the similarity matrix re-chosen (top N per sequence pair)
    /// and priced by their measured smoothness, with their windows
    /// (`--transition-cost` is then unused; the graph, and so `retarget`,
    /// is unchanged).
    #[arg(long, value_enum, default_value_t = TransitionsArg::from(D.transitions))]
    pub transitions: TransitionsArg,
    /// Which search finds the path.
    #[arg(long, value_enum, default_value_t = MethodArg::from(D.method))]
    pub search: MethodArg,
    /// Distance bins kept per (node, frame count) by the exact-length
    /// search (more: slower, closer to the optimum).
    #[arg(long, default_value_t = D.bins as u32, value_parser = clap::value_parser!(u32).range(1..=4096))]
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

/// `--plot`: a `.svg` or a `.png` (`--plot g.txt` ran the whole grid,
/// then wrote a PNG into g.txt).
fn plot_path(s: &str) -> Result<PathBuf, String> {
    let p = PathBuf::from(s);
    if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("svg")) {
        Ok(p)
    } else {
        crate::cli::png_path(s).map_err(|_| format!("{s}: expected a .svg or .png file name"))
    }
}
