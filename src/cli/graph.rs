//! `surfmotion graph`: export the Surface Motion Graph and draw its matrix.

use std::path::PathBuf;
use surfmotion::graph::plot::matrix_image;

/// Arguments of `graph`.
#[derive(clap::Args)]
pub struct Args {
    /// The database directory (built with `surfmotion db build`; built now
    /// if the cache is missing or stale).
    pub dir: PathBuf,
    /// Dissimilarity measure (default: the manifest's, else shape).
    #[arg(long, value_enum)]
    pub measure: Option<super::values::MeasureArg>,
    /// Print the graph in Graphviz DOT (`| dot -Tpng -o graph.png`).
    #[arg(long, conflicts_with = "json")]
    pub dot: bool,
    /// Print the graph as JSON: sequences, transitions (from, to, m, n,
    /// window, cost), sequence edges, and the frame-level adjacency.
    #[arg(long)]
    pub json: bool,
    /// Draw the similarity matrix with the transitions marked to this PNG
    /// (dark = similar; red crosses = transitions, pink = their windows).
    #[arg(long, value_name = "PNG", value_parser = super::png_path)]
    pub matrix: Option<PathBuf>,
    /// Size of the matrix picture in pixels, 16 to 8192.
    #[arg(long, default_value_t = 800, value_parser = super::bounded_count(16, super::render::MAX_SIZE))]
    pub size: usize,
}

/// Runs `graph`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let opts = surfmotion::db::BuildOptions {
        measure: a.measure.map(Into::into),
        force: false,
        ..Default::default()
    };
    let (mat, g, _) = surfmotion::db::build(&a.dir, &opts, &super::Bars::new())?;
    if let Some(p) = &a.matrix {
        matrix_image(&mat, &g, a.size).save_png(p)?;
        crate::errln!("wrote {}", p.display());
    }
    if a.dot {
        return super::emit(&g.to_dot());
    }
    if a.json {
        let v = surfmotion::jobs::short_text::graph_json(&g)?;
        return super::emit(&(serde_json::to_string(&v)? + "\n"));
    }
    if a.matrix.is_none() {
        super::emit(&surfmotion::jobs::short_text::graph(&g))?;
    }
    Ok(())
}
