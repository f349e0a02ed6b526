//! `surfmotion retarget`.

use std::path::PathBuf;
use surfmotion::db::CharacterOptions;
use surfmotion::drive::RetargetOptions;
use surfmotion::jobs::retarget::per_frame_seconds;
use surfmotion::jobs::transfer::PLAUSIBILITY_BYTES;
use surfmotion::jobs::{RetargetJob, RetargetJobOptions, RetargetSummary};

/// Arguments of `retarget`.
#[derive(clap::Args)]
pub struct Args {
    /// The character database (its graph is built first if needed).
    #[arg(long)]
    pub db: PathBuf,
    /// The mocap clip (BVH or AMC, any detected rig convention).
    #[arg(long)]
    pub mocap: PathBuf,
    /// Output: .glb (animated morph targets), .pc2 (+ .obj), .mdd, or a
    /// folder of OBJ frames (a path without extension).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write -o into a folder that already holds files (its OBJ frames are
    /// replaced).
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub job: JobOpts,
    /// Write a JSON report: the retrieved path (sequence, frame) per output
    /// frame, blends, transitions and cuts, costs, timings.
    #[arg(long, value_name = "JSON")]
    pub report: Option<PathBuf>,
    #[command(flatten)]
    pub run: super::RunOpts,
    #[command(flatten)]
    pub glb: super::mesh::GlbArgs,
}

/// The options of one retarget job, shared by `retarget` and `batch --db`
/// (one definition, so the two verbs cannot drift).
#[derive(clap::Args, Clone, Debug)]
pub struct JobOpts {
    /// Skip the deformation that makes the surface follow the mocap
    /// skeleton (same as --deform none): the output is the retrieved,
    /// blended and interpolated 4D frames.
    #[arg(long, conflicts_with = "deform")]
    pub no_deform: bool,
    /// How the retrieved frames follow the query skeleton: part-based PCA
    /// Laplacian deformation (the paper), one whole-body space, plain linear
    /// blend skinning, or none.
    #[arg(long, value_enum, default_value_t = super::values::DeformModeArg::Part)]
    pub deform: super::values::DeformModeArg,
    /// Skeleton dissimilarity threshold T_skel (metres, summed over 19
    /// joints), at most 1000. Default: chosen from the query's
    /// nearest-frame costs.
    #[arg(long, value_parser = t_skel)]
    pub t_skel: Option<f64>,
    /// Weight of matching the skeleton against avoiding transitions, at
    /// most 1e6.
    #[arg(long, default_value_t = 1.0, value_parser = super::weight)]
    pub w_retr: f64,
    /// No temporal interpolation of repeated frames.
    #[arg(long)]
    pub no_interpolate: bool,
    /// No blending across transitions.
    #[arg(long)]
    pub no_blend: bool,
    /// How each database frame's skeleton is read off its surface for
    /// retrieval, placement, the deformation's binding and the
    /// plausibility checks: the measured regressor joints, the character's
    /// rigid skeleton, or part centroids.
    #[arg(long, value_enum, default_value_t = super::values::SkeletonKindArg::Regressor)]
    pub skeleton: super::values::SkeletonKindArg,
}

/// `--t-skel`: metres summed over 19 joints, finite, ≥ 0 and at most 1000
/// (every frame is admitted long before; `--t-skel 1e308` printed a
/// 309-digit threshold).
fn t_skel(s: &str) -> Result<f64, String> {
    let v = super::non_negative(s)?;
    if v <= 1e3 {
        Ok(v)
    } else {
        Err(format!("{s}: expected metres in [0, 1000]"))
    }
}

impl JobOpts {
    /// The options of [`synthesise`].
    pub fn options(&self) -> RetargetOptions {
        let mut opts = RetargetOptions::default();
        opts.trellis.t_skel = self.t_skel;
        opts.trellis.w_retr = self.w_retr;
        opts.timeline.interpolate = !self.no_interpolate;
        opts.timeline.blend = !self.no_blend;
        opts.deform = if self.no_deform {
            surfmotion::deform::DeformMode::None
        } else {
            self.deform.into()
        };
        opts
    }

    /// How the database is loaded.
    pub fn character(&self) -> CharacterOptions {
        CharacterOptions {
            skeleton: self.skeleton.into(),
        }
    }

    /// True when every option has its default (they apply only to 4D
    /// characters).
    pub fn is_default(&self) -> bool {
        !self.no_deform
            && self.deform == super::values::DeformModeArg::Part
            && self.t_skel.is_none()
            && self.w_retr == 1.0
            && !self.no_interpolate
            && !self.no_blend
            && self.skeleton == super::values::SkeletonKindArg::Regressor
    }
}

/// Runs `retarget`: one [`RetargetJob`] and one clip.
pub fn run(a: Args) -> anyhow::Result<()> {
    super::warnings_in_summary(!a.run.json);
    surfmotion::jobs::outputs::check_mesh_output(&a.output)?;
    let mut inputs = vec![a.mocap.clone()];
    inputs.extend(a.run.clip.asf.clone());
    inputs.extend(a.run.clip.rig_map.clone());
    inputs.extend(surfmotion::jobs::outputs::database_inputs(&a.db));
    let mut outputs = super::mesh_outputs(&a.output);
    outputs.extend(a.report.clone().map(|p| ("--report", p)));
    outputs.extend(a.run.preview.preview.clone().map(|p| ("--preview", p)));
    surfmotion::jobs::outputs::refuse_colliding(&inputs, &outputs)?;
    a.glb.refuse_unless_glb(
        super::mesh::GlbArgs::is_glb(&a.output),
        &a.output.display().to_string(),
    )?;
    surfmotion::jobs::outputs::check_folder_output("-o", &a.output, a.force, &inputs)?;
    let opts = RetargetJobOptions {
        retarget: a.job.options(),
        character: a.job.character(),
        load: a.run.clip.load_options()?,
        glb: a.glb.options(),
    };
    let job = RetargetJob::load(&a.db, opts, &super::Bars::new())?;
    let ch = &job.character;
    if a.run.preview.preview.is_none() {
        // Nothing needs every frame at once: they go to the output as they
        // are made (issue 18, item 12); the plausibility is measured on the
        // first frames, as `transfer` does.
        let keep_bytes = PLAUSIBILITY_BYTES
            .min((surfmotion::util::budget::Budget::current().bytes / 4) as usize);
        let run = job.run_to(&a.mocap, &a.output, keep_bytes)?;
        let r = &run.report;
        let measured = run.kept.len() / ch.n().max(1);
        let plaus = job.plausibility_of_streamed(&run).map(|p| p.0);
        let partial = (measured < r.frames).then_some(measured);
        if let Some(k) = partial {
            tracing::info!(
                "plausibility measured on the first {k} of {} frames (streamed output)",
                r.frames
            );
        }
        return print_report(&a, r, run.written, &run.mocap.convention, plaus, partial);
    }
    let run = job.run(&a.mocap)?;
    let (out, convention) = (&run.output, &run.mocap.convention);
    let plaus = job.plausibility_of(&run);
    if let Some(path) = &a.run.preview.preview {
        // Each panel faced from its own body (`render`'s rule).
        surfmotion::tools::render::preview::write_preview(
            path,
            &out.positions,
            ch.n(),
            ch.topology().triangles(),
            Some(ch.rig()),
            None,
            plaus.as_ref().map(|p| p.1),
            &a.run.preview.options(),
        )?;
    }
    let plaus = plaus.map(|p| p.0);
    let convention = convention.clone();
    let r = &run.output.report;
    let written = job.write(run.output.positions, &a.output)?;
    print_report(&a, r, written, &convention, plaus, None)
}

/// Writes the `--report` file and prints the summary of a retarget
/// (`partial`: the plausibility was measured on that many first frames).
fn print_report(
    a: &Args,
    r: &surfmotion::drive::Report,
    written: Vec<PathBuf>,
    convention: &str,
    plaus: Option<surfmotion::tools::eval::Plausibility>,
    partial: Option<usize>,
) -> anyhow::Result<()> {
    let fps = r.fps;
    if let Some(p) = &a.report {
        let mut v = serde_json::to_value(r)?;
        v["plausibility"] = serde_json::to_value(&plaus)?;
        if let Some(k) = partial {
            v["plausibility_frames"] = serde_json::to_value(k)?;
        }
        surfmotion::util::fsutil::write_bytes_atomic(
            p,
            serde_json::to_string_pretty(&v)?.as_bytes(),
        )?;
    }
    let per_frame = per_frame_seconds(r);
    if a.run.json {
        let v = serde_json::to_value(RetargetSummary::new(written, r, plaus))?;
        return super::emit(&(serde_json::to_string_pretty(&v)? + "\n"));
    }
    let mut s = format!(
        "{} -> {}: {} at {} fps ({} rig)\n",
        a.mocap.display(),
        super::written_list(&written, ", "),
        super::count(r.frames, "frame"),
        fps,
        convention
    );
    s += &format!(
        "retrieval: T_skel {:.3} m (summed over the 19 joints), {}, {}, {}, {}\n",
        r.retrieval.t_skel,
        super::count(r.retrieval.nodes, "trellis node"),
        super::count(
            r.jumps.iter().filter(|j| j.transition).count(),
            "transition"
        ),
        super::count(r.retrieval.cuts.len(), "cut"),
        super::count(r.retrieval.widened.len(), "widened frame")
    );
    let mut runs: Vec<(String, usize, usize)> = Vec::new();
    for st in &r.steps {
        match runs.last_mut() {
            Some((n, _, b)) if *n == st.sequence && (st.frame == *b || st.frame == *b + 1) => {
                *b = st.frame
            }
            _ => runs.push((st.sequence.clone(), st.frame, st.frame)),
        }
    }
    s += "path:";
    for (n, a0, b0) in runs.iter().take(12) {
        s += &format!(" {n}[{a0}..{b0}]");
    }
    if runs.len() > 12 {
        s += " ...";
    }
    s += "\n";
    s += &format!(
        "time: query {:.3} s, retrieval {:.3} s, timeline {:.3} s, blend factor {:.3} s, meshes {:.3} s, deform factor {:.3} s, deform {:.3} s ({:.2} ms per output frame)\n",
        r.timings.query,
        r.timings.retrieval,
        r.timings.timeline,
        r.timings.factor,
        r.timings.meshes,
        r.timings.deform_factor,
        r.timings.deform,
        1e3 * per_frame
    );
    s += &format!("deformation: {}\n", r.deform);
    if matches!(
        r.deform,
        surfmotion::deform::DeformMode::Part | surfmotion::deform::DeformMode::Global
    ) {
        s += &format!(
            "triangle-frames turned over against the retrieved frames (the database frames each output frame blends): {} after the solve, {} after the repair (the plausibility below counts against the rest frame)\n",
            r.turned_over.before, r.turned_over.after
        );
    }
    if let Some(p) = &plaus {
        if let Some(k) = partial {
            s += &format!(
                "plausibility measured on the first {} of {} (streamed output):\n",
                super::count(k, "frame"),
                r.frames
            );
        }
        s += &p.text();
    }
    super::emit(&s)
}
