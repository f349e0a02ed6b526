//! `surfmotion keyframe`: key-frame animation through the Surface Motion
//! Graph (Huang et al. 2015, Sec. 5.1), and its Table III grid evaluation.
//! Parses, calls [`surfmotion::jobs::keyframe`] and prints.

mod args;
mod parse;

pub use args::Args;
use parse::{flagged, grid_targets};
use surfmotion::db::Character;
use surfmotion::jobs::keyframe::summary;
use surfmotion::jobs::keyframe::text::{self, GRID_HEADER, LEAST_MEAN_HEADER};
use surfmotion::jobs::keyframe::{
    self as job, DEFAULT_DISTANCES, DEFAULT_TIMES, FloorStage, GridTargets, Keys,
};
use surfmotion::jobs::output_set::OutputSet;
use surfmotion::keyframe::{KeyframeOptions, Targets};

/// Refuses outputs over the inputs or over each other, and a folder
/// output that holds files without `--force` ([`OutputSet::check`]).
fn check_outputs(a: &Args) -> anyhow::Result<()> {
    let mut set = OutputSet::reading_database(&a.db)
        .input(a.clip.asf.clone())
        .input(a.clip.rig_map.clone());
    if let Some(o) = &a.output {
        set = set.mesh("-o", o, a.force);
    }
    set.file("--report", a.report.as_deref())
        .file("--plot", a.plot.as_deref())
        .check(|o| a.glb.refuse_other_formats(o))
}

/// Runs `keyframe`.
pub fn run(a: Args) -> anyhow::Result<()> {
    check_outputs(&a)?;
    // Grid targets are refused before the database loads (and its graph
    // builds): 8.9e9 targets aborted on a 1.28 TB allocation (issue 46.4).
    let grid_targets = if a.grid || a.floor {
        let t = grid_targets(&a)?;
        if a.grid {
            t.check_size().map_err(flagged)?;
        }
        Some(t)
    } else if a.distances != DEFAULT_DISTANCES || a.times != DEFAULT_TIMES {
        // Ignored without a word (`--times NaN` ran the single query).
        anyhow::bail!(
            "--distances and --times are the grid's (with --grid or --floor); one query takes --distance and --time"
        );
    } else {
        None
    };
    let ch = Character::load(&a.db, &super::Bars::new())?;
    let load = a.clip.load_options()?;
    let mut names = vec![a.from.as_str()];
    names.extend(a.via.iter().map(String::as_str));
    names.push(&a.to);
    let keys = job::resolve_keys(&ch, &names, &load).map_err(flagged)?;
    let opts = a.options().keyframe_options(ch.manifest().fps);
    let head = summary::resolved(&keys);
    match &grid_targets {
        Some(t) if a.floor => floor(&ch, &keys, &a, &opts, t, head),
        Some(t) => grid(&ch, &keys, &a, &opts, t, head),
        None => path(&ch, &keys, &a, &opts, head),
    }
}

/// One query: the path written to `-o`, its report, its summary.
fn path(
    ch: &Character,
    keys: &Keys,
    a: &Args,
    opts: &KeyframeOptions,
    head: String,
) -> anyhow::Result<()> {
    let (Some(d), Some(t), Some(out)) = (&a.distance, &a.time, &a.output) else {
        anyhow::bail!("--distance, --time and -o are needed (or --grid, --floor)");
    };
    let segments = keys.ids.len() - 1;
    let targets = Targets::from_lists(
        &super::targets("distance", d)?,
        &super::targets("time", t)?,
        segments,
    )?;
    // 10-20 s on the README's synth3 (preparing, searching, blending the
    // meshes) with nothing on the screen before.
    let bar = if a.json {
        indicatif::ProgressBar::hidden()
    } else {
        super::spinner("finding the path and blending its meshes")
    };
    let formats = surfmotion::mesh::io::SaveOptions {
        glb: a.glb.options(),
        usd: a.glb.usd_options(),
        ..Default::default()
    };
    let run = job::write_path_with(ch, keys, &targets, opts, out, &formats, &mut |m| {
        bar.set_message(m.to_string())
    });
    bar.finish_and_clear();
    let run = run.map_err(flagged)?;
    // The report and --json say which targets were missed, as the text does.
    let mut v = job::write_path_report(&run, a.report.as_deref()).map_err(flagged)?;
    if a.json {
        v["output"] = serde_json::to_value(&run.written)?;
        return super::emit_json(&v);
    }
    let text = summary::path_summary(&run, ch.manifest().fps);
    super::emit(&(head + &super::flags::as_flags(&text)))
}

/// A bar of `n` targets on a terminal, none with `--json`. Minutes on a
/// large database with nothing on the screen before, and no word of how
/// long (issue 46.4): a bar with its ETA, and each target's row printed as
/// it finishes.
fn bar(a: &Args, n: usize, what: &str) -> indicatif::ProgressBar {
    if a.json {
        indicatif::ProgressBar::hidden()
    } else {
        super::progress(n as u64, what)
    }
}

/// A grid report as its JSON summary ([`text::summary_json`]) with
/// `--json`, else `text()`.
fn report<T: serde::Serialize>(
    a: &Args,
    r: &T,
    text: impl FnOnce() -> String,
) -> anyhow::Result<()> {
    super::report_with(a.json, || Ok(text::summary_json(r)?), text)
}

/// `--grid` (Table III), or with `--least-mean` the least mean smoothness
/// per target.
fn grid(
    ch: &Character,
    keys: &Keys,
    a: &Args,
    opts: &KeyframeOptions,
    t: &GridTargets,
    head: String,
) -> anyhow::Result<()> {
    let n = t.distances.len() * t.times.len();
    let mut closed = false;
    let mut row = |bar: &indicatif::ProgressBar, line: String| {
        bar.inc(1);
        if !a.json && !closed {
            closed = bar.suspend(|| super::emit(&line)).is_err();
        }
    };
    if a.least_mean {
        let planner = job::least_mean_planner(ch, &keys.ids, opts).map_err(flagged)?;
        let bar = bar(a, n, "targets: least mean smoothness");
        if !a.json {
            super::emit(&(head + LEAST_MEAN_HEADER))?;
        }
        let r = job::least_mean(ch, &planner, opts, t, &mut |q| {
            row(&bar, text::least_mean_row(q))
        });
        bar.finish_and_clear();
        let r = r.map_err(flagged)?;
        job::write_report(a.report.as_deref(), &r.report).map_err(flagged)?;
        return report(a, &r.report, || text::least_mean_summary(&r));
    }
    let planner = job::grid_planner(ch, &keys.ids, opts).map_err(flagged)?;
    let bar = bar(a, n, "grid queries");
    if !a.json {
        super::emit(&(head + GRID_HEADER))?;
    }
    let g = job::grid(ch, &planner, opts, t, &mut |q| row(&bar, text::grid_row(q)));
    bar.finish_and_clear();
    let g = g.map_err(flagged)?;
    job::write_grid_files(&g, a.report.as_deref(), a.plot.as_deref()).map_err(flagged)?;
    report(a, &g, || text::grid_summary(&g))
}

/// `--floor`: the transition floor of the database and the path floor
/// between consecutive key-frames (`jobs::keyframe::floor`), with a
/// spinner or bar per stage on a terminal (116 s on synth3 with nothing
/// on the screen), none with `--json`.
fn floor(
    ch: &Character,
    keys: &Keys,
    a: &Args,
    opts: &KeyframeOptions,
    t: &GridTargets,
    head: String,
) -> anyhow::Result<()> {
    let mut shown: Option<(std::mem::Discriminant<FloorStage>, indicatif::ProgressBar)> = None;
    let r = job::floor(ch, &keys.ids, opts, t, &mut |stage| {
        let kind = std::mem::discriminant(&stage);
        if shown.as_ref().is_none_or(|(k, _)| *k != kind) {
            if let Some((_, b)) = shown.take() {
                b.finish_and_clear();
            }
            let b = match stage {
                _ if a.json => indicatif::ProgressBar::hidden(),
                FloorStage::Surfaces => super::spinner("measuring the frames' surfaces"),
                FloorStage::Pairs(..) => super::progress(0, "frame pairs: transition floor"),
                FloorStage::Paths => super::spinner("pricing the graph by smoothness; path floors"),
            };
            shown = Some((kind, b));
        }
        if let (FloorStage::Pairs(done, total), Some((_, b))) = (stage, &shown) {
            b.set_length(total);
            b.set_position(done);
        }
    });
    if let Some((_, b)) = shown {
        b.finish_and_clear();
    }
    super::report_sorted(a.json, &r, || head + &text::floor_summary(&r))
}
