//! `--pick` of `rig embed` and `db init`: serve the page to look at the rig
//! and correct its landmarks ([`surfmotion::jobs::pick`]) until Ctrl-C,
//! then say what was saved.

use surfmotion::jobs::pick::{Pick, PickReport, finish};

/// Set by SIGINT or SIGTERM while the page is served.
static STOP: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

#[cfg(unix)]
extern "C" fn on_stop_signal(_: libc::c_int) {
    // Only an atomic store: async-signal-safe.
    STOP.store(true, std::sync::atomic::Ordering::Relaxed);
}

/// Makes SIGINT and SIGTERM set [`STOP`] instead of ending the process
/// (as `web serve` does), so that the report is printed and, for a
/// database, the manifest pointed at the saved landmarks.
fn stop_on_signals() {
    #[cfg(unix)]
    // SAFETY: the handler only stores to an atomic.
    unsafe {
        let h = on_stop_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
        libc::signal(libc::SIGINT, h);
        libc::signal(libc::SIGTERM, h);
    }
}

/// Prints the URL, serves until Ctrl-C, prints what the page saved.
pub fn serve(p: Pick, json: bool) -> anyhow::Result<()> {
    stop_on_signals();
    crate::outln!(
        "pick: open {} (drag a landmark to re-embed, Save writes the landmark file; Ctrl-C stops)",
        p.url()
    )?;
    p.run_until(&STOP);
    let r = finish(p)?;
    if json {
        return crate::outln!(
            "{}",
            serde_json::to_string_pretty(&serde_json::to_value(&r)?)?
        );
    }
    super::emit(&text(&r))
}

fn text(r: &PickReport) -> String {
    let mut s = format!(
        "pick: stopped after {} and {}\n",
        super::count(r.requests, "request"),
        super::count(r.embeds, "embedding")
    );
    if r.saved.is_empty() {
        s += "  nothing saved\n";
    }
    for p in &r.saved {
        s += &format!("  saved {}\n", p.display());
    }
    if let Some(m) = &r.manifest {
        s += &format!("  {} now names the last one\n", m.display());
    }
    s
}
