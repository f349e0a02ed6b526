//! One source of truth for defaults (issue 40): a verb given only its
//! required arguments runs with the library's documented defaults. The
//! flags read their defaults off the library's options; these tests parse
//! each verb's arguments with nothing optional given and compare the
//! options the CLI builds with the library's `Default`, so a flag's
//! conversion (millimetres, clamps, inversions) cannot drift either.

use clap::Parser;
use surfmotion::db::CharacterOptions;
use surfmotion::drive::DriveOptions;

/// Parses `argv` (without the program name) into the arguments `T` of
/// one verb, through a wrapper that flattens them.
macro_rules! parse {
    ($t:ty, $($arg:expr),* $(,)?) => {{
        #[derive(clap::Parser)]
        struct Wrapper {
            #[command(flatten)]
            args: $t,
        }
        match Wrapper::try_parse_from(["surfmotion", $($arg),*]) {
            Ok(w) => w.args,
            Err(e) => panic!("{}", e),
        }
    }};
}

/// `format!("{:?}")` of both, for option structs without `PartialEq`.
fn same<A: std::fmt::Debug, B: std::fmt::Debug>(cli: &A, library: &B) {
    assert_eq!(format!("{cli:?}"), format!("{library:?}"));
}

#[test]
fn retarget_defaults_are_the_librarys() {
    let a = parse!(super::retarget::JobOpts,);
    assert_eq!(a.options(), DriveOptions::default());
    assert_eq!(a.character(), CharacterOptions::default());
    let a = parse!(super::retarget::JobOpts, "--w-retr", "2");
    assert_eq!(a.options().trellis.w_retr, 2.0);
    let a = parse!(super::retarget::JobOpts, "--no-deform");
    assert_eq!(a.options().deform, surfmotion::deform::DeformMode::None);
}

#[test]
fn transfer_defaults_are_the_librarys() {
    let a = parse!(super::transfer::JobOpts,);
    let job = a.job().expect("the default markers are valid");
    let d = surfmotion::jobs::ScanTransferOptions::default();
    assert_eq!(job.markers, d.markers);
    assert_eq!(job.fps, d.fps);
    assert!(job.groups.is_empty());
    let a = parse!(
        super::transfer::Args,
        "--scan",
        "s.obj",
        "--mocap",
        "m.bvh",
        "-o",
        "o.pc2"
    );
    let auto = surfmotion::jobs::transfer::AutoScanLandmarks::default();
    assert_eq!(a.min_confidence, auto.min_confidence);
    let scan = surfmotion::embed::scan_landmarks::ScanOptions::default();
    assert_eq!(auto.min_confidence, scan.min_confidence);
}

#[test]
fn live_defaults_are_the_librarys() {
    let a = parse!(super::live::Args, "--db", "d", "--replay", "c.bvh");
    let o = super::live::options(&a).expect("default options");
    same(&o, &surfmotion::jobs::live::LiveOptions::default());
}

/// The options `live` builds from `--db d --replay c.bvh` and `extra`,
/// or the message of clap's or the options' refusal.
fn live_options(extra: &[&str]) -> Result<surfmotion::jobs::live::LiveOptions, String> {
    #[derive(clap::Parser)]
    struct Wrapper {
        #[command(flatten)]
        args: super::live::Args,
    }
    let mut argv = vec!["surfmotion", "--db", "d", "--replay", "c.bvh"];
    argv.extend_from_slice(extra);
    let w = Wrapper::try_parse_from(argv).map_err(|e| e.to_string())?;
    super::live::options(&w.args).map_err(|e| e.to_string())
}

/// `--overlap` alone is `queued`, as is no `--overlap` (the library's
/// default); each named choice is its mode.
#[test]
fn live_overlap_forms() {
    use surfmotion::live::Overlap;
    let with = |extra: &[&str]| live_options(extra).map(|o| o.overlap);
    assert_eq!(with(&[]), Ok(Overlap::Queued), "the default (session 40)");
    assert_eq!(with(&["--overlap"]), Ok(Overlap::Queued));
    assert_eq!(with(&["--overlap", "queued"]), Ok(Overlap::Queued));
    assert_eq!(with(&["--overlap=always"]), Ok(Overlap::Always));
    assert_eq!(with(&["--overlap", "off"]), Ok(Overlap::Off));
    assert!(with(&["--overlap", "sometimes"]).is_err());
}

/// `--repair-budget` (issue 45): live's default is the live bound,
/// `none` gives offline's deformation options exactly (the meshes the
/// live-against-offline tests compare), a budget by keys is read key by
/// key; text that is not a budget is refused with the bad part quoted.
/// `retarget`'s default stays unbounded.
#[test]
fn repair_budget_forms() {
    use surfmotion::deform::RepairBudget;
    let with = |extra: &[&str]| live_options(extra).map(|o| o.retarget);
    let budget = |extra: &[&str]| with(extra).map(|o| o.deform_options.repair_budget);
    assert_eq!(budget(&[]), Ok(RepairBudget::LIVE));
    assert_eq!(budget(&["--repair-budget", "live"]), Ok(RepairBudget::LIVE));
    assert_eq!(
        with(&["--repair-budget", "none"]),
        Ok(DriveOptions::default()),
        "none is offline's synthesis"
    );
    let b = budget(&["--repair-budget=patch=10,per-triangle-projections=7"]).unwrap();
    assert_eq!(b.most.patch_vertices, 10);
    assert_eq!(b.per_triangle.projections, 7);
    assert_eq!(b.most.projections, usize::MAX);
    for (bad, quoted) in [
        ("fast", "\"fast\""),
        ("patch=many", "\"many\""),
        ("rings=3", "\"rings\""),
        ("patch=1,patch=2", "\"patch\""),
    ] {
        let e = budget(&["--repair-budget", bad]).unwrap_err();
        assert!(
            e.contains(quoted) && e.contains("--repair-budget"),
            "{bad}: {e}"
        );
    }
    let a = parse!(super::retarget::JobOpts,);
    assert_eq!(a.options().deform_options.repair_budget, RepairBudget::NONE);
    let a = parse!(super::retarget::JobOpts, "--repair-budget", "live");
    assert_eq!(a.options().deform_options.repair_budget, RepairBudget::LIVE);
}

#[test]
fn synth_defaults_are_the_librarys() {
    let a = parse!(
        super::synth::Args,
        "--mesh",
        "rest.obj",
        "--landmarks",
        "lm.json",
        "--mocap",
        "a.bvh",
        "-o",
        "out"
    );
    let o = super::synth::options(&a).expect("default options");
    same(&o, &surfmotion::jobs::SynthOptions::default());
}

#[test]
fn web_export_defaults_are_the_librarys() {
    let a = parse!(super::web::Source, "--db", "d");
    let o = super::web::options(&a).expect("default options");
    same(&o, &surfmotion::web::ExportOptions::default());
}

#[test]
fn preview_render_procedural_and_init_defaults_are_the_librarys() {
    let a = parse!(super::render::PreviewOpts,);
    same(
        &a.options(),
        &surfmotion::tools::render::preview::PreviewOptions::default(),
    );
    let a = parse!(super::render::Args, "m.obj", "-o", "m.png");
    let r = surfmotion::jobs::render::RenderOptions::default();
    assert_eq!((a.frame, a.size), (r.frame, r.size));
    let a = parse!(super::mocap::ProceduralArgs, "-o", "out");
    let p = surfmotion::jobs::mocap::ProceduralOptions::default();
    assert_eq!((a.seconds, a.fps), (p.seconds, p.fps));
    let a = parse!(super::db_init::InitArgs, "dir", "--mesh", "m.obj");
    let i = surfmotion::db::init::InitOptions::default();
    assert_eq!((a.fps, &a.units, &a.up), (i.fps, &i.units, &i.up));
}
