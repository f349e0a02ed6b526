//! `surfmotion transfer`: the arguments ([`super::transfer::Args`]) checked,
//! the job ([`surfmotion::jobs::transfer_files`]) called, its report printed.

use super::transfer::{Args, ScanJob};
use surfmotion::jobs::output_set::OutputSet;
use surfmotion::jobs::transfer_files::{TransferFiles, transfer_files};
use surfmotion::jobs::{ScanTransferOptions, TransferSource, TransferSpec};
use surfmotion::transfer::{SignMode, TransferOptions};

/// Runs `transfer`.
pub fn run(a: Args) -> anyhow::Result<()> {
    super::warnings_in_summary(!a.run.json);
    check_options_and_outputs(&a)?;
    let job_opts = a.job.job()?;
    let scan = super::load_mesh_groups(&a.scan, &job_opts.groups)?;
    let spec = spec(&a, &job_opts)?;
    let files = TransferFiles {
        output: a.output.clone(),
        report: a.report.clone(),
        preview: (a.run.preview.preview.clone()).map(|p| (p, a.run.preview.options())),
    };
    // The number of frames is known once the source is read: the library
    // reports it with every frame solved.
    let bar = super::progress(0, "frames");
    let report = transfer_files(&scan, &spec, &files, &|p| {
        bar.set_length(p.total as u64);
        bar.inc(1);
    })?;
    bar.finish_and_clear();
    let truth = a.truth.as_deref();
    super::report_with(
        a.run.json,
        || Ok(report.summary_json()?),
        || report.summary_text(&a.scan, truth, a.write_landmarks.as_deref()),
    )
}

/// The job's spec from the arguments.
fn spec(a: &Args, job_opts: &ScanJob) -> anyhow::Result<TransferSpec> {
    let source = match (&a.mocap, &a.template) {
        (Some(m), _) => TransferSource::Mocap(m.clone()),
        (None, Some(t)) => TransferSource::Template {
            spec: t.clone(),
            markers: a.template_markers.clone(),
            landmarks: a.template_landmarks.clone(),
            frame: a.template_frame,
        },
        (None, None) => anyhow::bail!("give --mocap or --template"),
    };
    Ok(TransferSpec {
        scan_name: a.scan.clone(),
        landmarks: a.landmarks.clone(),
        automatic: surfmotion::jobs::transfer::AutoScanLandmarks {
            min_confidence: a.min_confidence,
            write: a.write_landmarks.clone(),
        },
        markers: a.markers.clone(),
        save_markers: a.save_markers.clone(),
        source,
        truth: a.truth.clone(),
        options: ScanTransferOptions {
            markers: job_opts.markers,
            fps: job_opts.fps,
            transfer: TransferOptions {
                signs: if a.naive_signs {
                    SignMode::Hemisphere
                } else {
                    SignMode::Consistent
                },
            },
            load: a.run.clip.load_options()?,
            glb: a.glb.options(),
            usd: a.glb.usd_options(),
        },
    })
}

/// Refuses, before any work, template options without a template and
/// outputs that would replace an input or another output, are not a
/// mesh format, or a folder that holds files without --force.
fn check_options_and_outputs(a: &Args) -> anyhow::Result<()> {
    super::confidence(a.min_confidence)?;
    // clap's `requires` let these through with --mocap, and they were
    // ignored without a word.
    if a.template.is_none() {
        for (flag, given) in [
            ("--template-markers", a.template_markers.is_some()),
            ("--template-landmarks", a.template_landmarks.is_some()),
            ("--template-frame", a.template_frame != 0),
        ] {
            anyhow::ensure!(
                !given,
                "{flag} applies to --template (a moving template mesh), not to --mocap"
            );
        }
    }
    use surfmotion::mesh::io::input_files;
    let mut meshes = input_files(&a.scan, None);
    if let Some(t) = &a.template {
        meshes.extend(input_files(t, None));
    }
    surfmotion::mesh::io::refuse_overwriting(&meshes, &a.output)?;
    // `--report LANDMARKS.json` replaced the scan's landmarks with the
    // report and exited 0: every file read is an input.
    let read = [
        &a.landmarks,
        &a.markers,
        &a.template_markers,
        &a.template_landmarks,
        &a.run.clip.asf,
        &a.run.clip.rig_map,
    ];
    let set = OutputSet::reading(meshes)
        .input(a.mocap.clone())
        .input(a.truth.iter().flat_map(|t| input_files(t, None)))
        .input(read.into_iter().flatten().cloned())
        .mesh("-o", &a.output, a.force)
        .file("--report", a.report.as_deref())
        .file("--preview", a.run.preview.preview.as_deref())
        .file("--save-markers", a.save_markers.as_deref())
        .file("--write-landmarks", a.write_landmarks.as_deref());
    set.refuse_colliding()?;
    surfmotion::mesh::io::refuse_folder_as_file(&a.output)?;
    a.glb.refuse_other_formats(&a.output)?;
    set.check_folder()?;
    anyhow::ensure!(
        surfmotion::mesh::io::MeshFormat::of(&a.output).is_some(),
        "{}: unknown output format (use .glb .pc2 .mdd .obj or a folder)",
        a.output.display()
    );
    Ok(())
}
