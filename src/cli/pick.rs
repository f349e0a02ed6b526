//! `--pick` of `rig embed` and `db init`: serve the page to look at the rig
//! and correct its landmarks ([`surfmotion::jobs::pick`]) until Ctrl-C,
//! then say what was saved.

use surfmotion::jobs::pick::{Pick, finish};

/// Prints the URL, serves until Ctrl-C, prints what the page saved.
pub fn serve(p: Pick, json: bool) -> anyhow::Result<()> {
    // SIGINT and SIGTERM stop the page (as in `web serve`), so that the
    // report is printed and, for a database, the manifest pointed at the
    // saved landmarks.
    let stop = super::signals::stop_on_signals();
    crate::outln!(
        "pick: open {} (drag a landmark to re-embed, Save writes the landmark file; Ctrl-C stops)",
        p.url()
    )?;
    p.run_until(stop);
    let r = finish(p)?;
    super::report_sorted(json, &r, || surfmotion::jobs::short_text::pick(&r))
}
