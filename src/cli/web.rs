//! `surfmotion web`: export the character (or a result) as a static site,
//! or serve it locally.

use std::path::PathBuf;
use surfmotion::jobs::web::{TempSite, WebSource, check_listen, exported_site};
use surfmotion::web::{self, EncodeOptions, ExportOptions, Predictor};

/// Subcommands of `web`.
#[derive(clap::Subcommand)]
pub enum Cmd {
    /// Write a self-contained static site: index.html, the engine and
    /// renderer (JavaScript modules, WebGL2), the compact 4D geometry and
    /// the Surface Motion Graph's transition table. Any static host serves
    /// it; no network access at run time.
    #[command(after_help = "Example:\n  surfmotion web export --db samba_synth -o site")]
    Export(ExportArgs),
    /// Export into a temporary folder and serve it on 127.0.0.1 (prints the
    /// URL; Ctrl-C stops).
    #[command(after_help = "Example:\n  surfmotion web serve --db samba_synth")]
    Serve(ServeArgs),
}

/// What to export.
#[derive(clap::Args)]
pub struct Source {
    /// The database directory: the interactive character.
    #[arg(long, required_unless_present_any = ["result", "site"], conflicts_with = "result")]
    pub db: Option<PathBuf>,
    /// A result to view with a timeline instead (`.glb`, or `.pc2`/`.mdd`
    /// with the `.obj` of the same name or --topology).
    #[arg(long, value_name = "FILE")]
    pub result: Option<PathBuf>,
    /// Topology of a `--result` point cache.
    #[arg(long, value_name = "OBJ", requires = "result")]
    pub topology: Option<PathBuf>,
    /// Largest vertex error of the compressed geometry, in millimetres, at
    /// most 100 (guaranteed: checked after encoding).
    #[arg(long, default_value_t = EncodeOptions::default().max_error * 1e3, value_name = "MM", value_parser = super::max_error_mm)]
    pub max_error: f64,
    /// Prediction of the geometry codec (measured: spatio-temporal is smaller).
    #[arg(long, value_enum, default_value_t = EncodeOptions::default().predictor.into())]
    pub predictor: PredictorArg,
    /// DEFLATE level of the geometry (0-9): higher is smaller and slower
    /// (level 6: 1.8 % smaller, 20 % slower to export).
    #[arg(long, default_value_t = EncodeOptions::default().level, value_parser = clap::value_parser!(u32).range(0..=9))]
    pub level: u32,
    /// Let the page blend transitions linearly on the GPU instead of
    /// precomputing each window's non-linear blend (smaller, faster export).
    #[arg(long)]
    pub linear_transitions: bool,
}

/// The codec's predictor.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum PredictorArg {
    /// The previous frame.
    Temporal,
    /// The previous frame plus a neighbour's motion.
    SpatioTemporal,
}

super::mirror::mirror!(PredictorArg, Predictor, Temporal, SpatioTemporal);

/// Arguments of `web export`.
#[derive(clap::Args)]
pub struct ExportArgs {
    #[command(flatten)]
    pub source: Source,
    /// The site folder to write (an earlier export there is replaced; a
    /// folder holding anything else, or an input, is refused).
    #[arg(short, long)]
    pub out: PathBuf,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `web serve`.
#[derive(clap::Args)]
pub struct ServeArgs {
    #[command(flatten)]
    pub source: Source,
    /// Serve this already exported site instead.
    #[arg(long, conflicts_with_all = ["db", "result"])]
    pub site: Option<PathBuf>,
    /// Port (0 picks a free one).
    #[arg(long, default_value_t = 8080)]
    pub port: u16,
    /// Address to listen on: an IP address of this machine (127.0.0.1,
    /// 0.0.0.0 for every interface, ::1) or localhost.
    #[arg(long, default_value = "127.0.0.1", value_parser = bind_address)]
    pub bind: String,
}

/// `--bind`: an IP address or `localhost` (`--bind 999.1.1.1` exported
/// the whole site, then failed on a name lookup).
fn bind_address(s: &str) -> Result<String, String> {
    if s == "localhost" || s.parse::<std::net::IpAddr>().is_ok() {
        Ok(s.to_string())
    } else {
        Err("expected an IP address (127.0.0.1, 0.0.0.0, ::1) or localhost".into())
    }
}

pub(super) fn options(s: &Source) -> anyhow::Result<ExportOptions> {
    Ok(ExportOptions {
        codec: EncodeOptions {
            max_error: s.max_error * 1e-3,
            predictor: s.predictor.into(),
            level: s.level,
        },
        linear_transitions: s.linear_transitions,
    })
}

/// What `--db` or `--result` asked to export.
fn source(s: &Source) -> anyhow::Result<WebSource> {
    Ok(match (&s.db, &s.result) {
        (Some(db), _) => WebSource::Database(db.clone()),
        (None, Some(r)) => WebSource::Result {
            path: r.clone(),
            topology: s.topology.clone(),
        },
        (None, None) => return Err(super::Usage.into()),
    })
}

fn export(s: &Source, out: &std::path::Path) -> anyhow::Result<web::ExportReport> {
    let opts = options(s)?;
    Ok(source(s)?.export(out, &opts)?)
}

/// Runs `web`.
pub fn run(c: Cmd) -> anyhow::Result<()> {
    match c {
        Cmd::Export(a) => {
            let bar = super::spinner("exporting the site (geometry, transitions, spaces)");
            let r = export(&a.source, &a.out);
            bar.finish_and_clear();
            let r = r?;
            super::report(a.json, &r, || surfmotion::jobs::text::web_export(&r))
        }
        Cmd::Serve(a) => {
            // The address is tried before the export (seconds to minutes):
            // one this machine does not have, or a port in use, failed
            // only after it.
            let addr = format!("{}:{}", a.bind, a.port);
            check_listen(&addr)?;
            let mut _tmp = None;
            let root = match &a.site {
                Some(s) => exported_site(s)?,
                None => {
                    let t = TempSite::new(&std::env::temp_dir(), &mut |d| {
                        crate::errln!(
                            "removed {}: the export of an earlier `web serve` that was stopped",
                            d.display()
                        )
                    })?;
                    let site = t.site();
                    let bar = super::spinner("exporting the site");
                    let r = export(&a.source, &site);
                    bar.finish_and_clear();
                    let r = r?;
                    crate::errln!("{}", surfmotion::jobs::text::web_export(&r).trim_end());
                    _tmp = Some(t);
                    site
                }
            };
            let server = web::SiteServer::bind(&root, &addr)?;
            // Ctrl-C or SIGTERM stop the server and the temporary export
            // is removed (it stayed behind). A signal during the export
            // still ends the process: the next `web serve` removes it.
            let stop = super::signals::stop_on_signals();
            crate::outln!("serving {} at {}", root.display(), server.url())?;
            server.run_until(stop);
            match _tmp.map(TempSite::close) {
                Some((p, Ok(()))) => {
                    crate::errln!("stopped; removed the temporary export {}", p.display())
                }
                Some((p, Err(e))) => {
                    crate::errln!("stopped; could not remove {}: {e}", p.display())
                }
                None => {}
            }
            Ok(())
        }
    }
}
