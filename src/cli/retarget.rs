//! `surfmotion retarget`.

use std::path::PathBuf;
use surfmotion::db::CharacterOptions;
use surfmotion::drive::DriveOptions;
use surfmotion::jobs::output_set::OutputSet;
use surfmotion::jobs::{RetargetJob, RetargetJobOptions};

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
    pub glb: super::mesh::SequenceOutputArgs,
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
    #[arg(long, value_enum, default_value_t = DriveOptions::default().deform.into())]
    pub deform: super::values::DeformModeArg,
    /// Skeleton dissimilarity threshold T_skel (metres, summed over 19
    /// joints), at most 1000. Default: chosen from the query's
    /// nearest-frame costs.
    #[arg(long, value_parser = super::t_skel)]
    pub t_skel: Option<f64>,
    /// Weight of matching the skeleton against avoiding transitions, at
    /// most 1e6.
    #[arg(long, default_value_t = DriveOptions::default().trellis.w_retr, value_parser = super::weight)]
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
    #[arg(long, value_enum, default_value_t = CharacterOptions::default().skeleton.into())]
    pub skeleton: super::values::SkeletonKindArg,
    /// The fold repair's work limit a frame (as `live --repair-budget`):
    /// `none` (the default: the unbounded repair), `live` (live's bound:
    /// 30,000 projections and 4,000 patch unknowns a frame, 1,000 and 60
    /// per triangle turned over, all on the repair against the surface's
    /// own turns), or
    /// `projections=N,patch=N[,per-triangle-projections=N,per-triangle-patch=N,skin-projections=N,skin-patch=N]`
    /// (a key left out is not bounded). For comparing with live's output.
    #[arg(long = "repair-budget", value_name = "BUDGET", default_value_t = DriveOptions::default().deform_options.repair_budget)]
    pub repair_budget: surfmotion::deform::RepairBudget,
}

impl JobOpts {
    /// The options of [`synthesise`].
    pub fn options(&self) -> DriveOptions {
        let mut opts = DriveOptions::default();
        opts.trellis.t_skel = self.t_skel;
        opts.trellis.w_retr = self.w_retr;
        opts.timeline.interpolate = !self.no_interpolate;
        opts.timeline.blend = !self.no_blend;
        opts.deform = if self.no_deform {
            surfmotion::deform::DeformMode::None
        } else {
            self.deform.into()
        };
        opts.deform_options.repair_budget = self.repair_budget;
        opts
    }

    /// How the database is loaded.
    pub fn character(&self) -> CharacterOptions {
        CharacterOptions {
            skeleton: self.skeleton.into(),
        }
    }

    /// The options of a [`RetargetJob`]: these, the clip's `load` and the
    /// output formats `glb` (as `retarget` and `batch --db` give them).
    pub fn job_options(
        &self,
        load: surfmotion::rig::LoadOptions,
        glb: &super::mesh::SequenceOutputArgs,
    ) -> RetargetJobOptions {
        RetargetJobOptions {
            retarget: self.options(),
            character: self.character(),
            load,
            glb: glb.options(),
            usd: glb.usd_options(),
        }
    }
}

/// Runs `retarget`: one [`RetargetJob`] and one clip.
pub fn run(a: Args) -> anyhow::Result<()> {
    super::warnings_in_summary(!a.run.json);
    // The GLB/USD flags are refused after collisions, as they always were.
    let set = OutputSet::reading([a.mocap.clone()])
        .input(a.run.clip.asf.clone())
        .input(a.run.clip.rig_map.clone())
        .input(surfmotion::jobs::outputs::database_inputs(&a.db))
        .mesh("-o", &a.output, a.force)
        .file("--report", a.report.as_deref())
        .file("--preview", a.run.preview.preview.as_deref());
    set.check_mesh_format()?;
    set.refuse_colliding()?;
    a.glb.refuse_other_formats(&a.output)?;
    set.check_folder()?;
    let opts = a.job.job_options(a.run.clip.load_options()?, &a.glb);
    let job = RetargetJob::load(&a.db, opts, &super::Bars::new())?;
    let preview = a.run.preview.options();
    let preview = a.run.preview.preview.as_deref().map(|p| (p, &preview));
    let c = job.run_clip(&a.mocap, &a.output, preview)?;
    if let Some(p) = &a.report {
        job.write_report(&c, p)?;
    }
    super::report_with(
        a.run.json,
        || Ok(serde_json::to_value(c.summary())?),
        || surfmotion::jobs::text::retarget(&a.mocap, &c),
    )
}
