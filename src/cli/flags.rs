//! The library's messages name options as its callers set them, in
//! backticks (`` `force` ``, `` `mocap_dir` ``); the CLI prints its flags
//! instead, so a refusal names what the user types.

/// Option names in the library's messages and the flag each is on the
/// command line. Each entry is replaced as written, backticks included.
/// Longer phrases come first.
const FLAGS: &[(&str, &str)] = &[
    ("`InitOptions::parts` of `db::init`", "`db init --parts`"),
    (
        "`ScanTransferOptions` (groups, markers, fps) apply to a scan target",
        "--group, --marker-count, --marker-margin and --fps apply to --scan",
    ),
    (
        "`RetargetJobOptions` (deform, t_skel, w_retr, interpolate, blend, skeleton, repair_budget) apply to a database target",
        "--deform, --no-deform, --t-skel, --w-retr, --no-interpolate, --no-blend, --skeleton and --repair-budget apply to --db",
    ),
    (
        "(`InitOptions::sequences` of `db::init`: NAME=PATH)",
        "(`surfmotion db init --sequence NAME=PATH`)",
    ),
    (
        "a `jobs::keyframe` key from POSE.json",
        "`keyframe --from POSE.json`",
    ),
    (
        "`jobs::play::play_session` checks it",
        "`play --db DB --script` checks it",
    ),
    (
        "the report of `jobs::keyframe::grid`",
        "`keyframe --grid --report`",
    ),
    ("(`RigEmbedOptions::png` draws", "(`rig embed --png` draws"),
    ("picture (`InitSetup::png`)", "picture (`--png`)"),
    ("  ... (the graph of ", "  ... (`surfmotion graph "),
    (" in JSON lists all)", " --json` lists all)"),
    (
        "(see `jobs::rig::embed_rig`)",
        "(see `surfmotion rig embed --help`)",
    ),
    (
        "set `InitOptions::human_sized` to false",
        "pass --not-human-sized",
    ),
    (
        "give the `TransferSource::Template` markers or landmarks",
        "give --template-markers or --template-landmarks",
    ),
    ("`TransferSource::Template` frame", "--template-frame"),
    ("`GlbOptions::normals` false", "--glb-no-normals"),
    ("`UsdOptions::normals` false", "--usd-no-normals"),
    ("the `GlbOptions` apply", "the --glb-* options apply"),
    ("fewer via key-frames", "fewer --via"),
    ("nearer via key-frames", "nearer --via"),
    ("`KeyframeJobOptions::w_dist`", "--w-dist"),
    ("`KeyframeJobOptions::w_heading`", "--w-heading"),
    ("`KeyframeJobOptions::w_time`", "--w-time"),
    ("give `landmarks`", "give --landmarks"),
    ("`AmcOptions::fps`", "--input-fps"),
    ("`BatchOptions::shard`", "--shard"),
    ("`BlendOptions::alpha`", "--alpha"),
    ("`BvhOptions::fps`", "--input-fps"),
    ("`GlbOptions::quantize`", "--glb-quantize"),
    ("`InitOptions::choose_rest` off", "--keep-rest-frame"),
    ("`InitOptions::gltf_skin`", "--gltf-skin"),
    ("`InitOptions::landmarks`", "--landmarks"),
    ("`InitOptions::mesh`", "--mesh"),
    ("`InitOptions::name`", "--name"),
    ("`InitOptions::parts`", "--parts"),
    ("`InitOptions::rig_map`", "--rig-map"),
    ("`InitOptions::sequences`", "--sequence"),
    ("`InitOptions::units`", "--input-units"),
    ("`InitOptions::up`", "--up"),
    ("`LoadOptions::asf`", "--asf"),
    ("`LoadOptions::fps`", "--input-fps"),
    ("`LoadOptions::rig_map`", "--rig-map"),
    ("`LoadOptions::topology`", "--topology"),
    ("`LoadOptions::units`", "--input-units"),
    ("`Targets::distance`", "--distance"),
    ("`Targets::time`", "--time"),
    ("`ProceduralOptions::fps`", "--fps"),
    ("`ProceduralOptions::gaits`", "--gait"),
    ("`ProceduralOptions::output`", "-o"),
    ("`ProceduralOptions::seconds`", "--seconds"),
    ("`PickOptions::landmarks`", "--landmarks FILE"),
    ("`RenderOptions::facing`", "--facing"),
    ("`RenderOptions::size`", "--size"),
    ("`RenderOptions::up`", "--up"),
    ("`RigEmbedOptions::groups`", "--group"),
    ("`RigEmbedOptions::landmarks`", "--landmarks"),
    ("`RigEmbedOptions::parts`", "--parts"),
    ("`RigEmbedOptions::skin`", "--skin"),
    ("`TransferSpec::landmarks`", "--landmarks"),
    ("`TransferSpec::markers`", "--markers"),
    ("`force`", "--force"),
    ("`shard_count`", "--shard-count"),
    ("`mocap_dir`", "--mocap-dir"),
];

/// `message` with each option name of [`FLAGS`] replaced by its flag.
pub fn as_flags(message: &str) -> String {
    FLAGS.iter().fold(message.to_string(), |s, (option, flag)| {
        s.replace(option, flag)
    })
}

#[cfg(test)]
mod tests {
    /// A refusal of the output policy reads as it did when the CLI
    /// formatted it itself.
    #[test]
    fn option_names_become_flags() {
        assert_eq!(
            super::as_flags("-o out: the folder already holds 2 files; pass `force` to replace"),
            "-o out: the folder already holds 2 files; pass --force to replace"
        );
        assert_eq!(super::as_flags("no option here"), "no option here");
    }

    /// A key-frame path's summary, written by the library with the job's
    /// option names, prints the flags it printed when the CLI wrote it.
    #[test]
    fn keyframe_summary_options_read_as_flags() {
        assert_eq!(
            super::as_flags(
                "(fewer or nearer via key-frames shorten it); `KeyframeJobOptions::w_dist` and `KeyframeJobOptions::w_time` weigh the two; `KeyframeJobOptions::w_heading` weighs it"
            ),
            "(fewer or nearer --via shorten it); --w-dist and --w-time weigh the two; --w-heading weighs it"
        );
    }

    /// The library's refusals that name options read as flags on the
    /// command line: the pick page's and the batch scheduler's.
    #[test]
    fn pick_and_shard_refusals_name_flags() {
        let e = surfmotion::jobs::pick::PickError::NoLandmarks {
            mesh: "db".into(),
            why: "no contact".into(),
            db: true,
        };
        let m = super::as_flags(&e.to_string());
        assert!(m.contains("(--landmarks FILE: chin"), "{m}");
        assert!(m.ends_with("or run `db init` with --landmarks"), "{m}");
        let none = |_: &str| None;
        let e = surfmotion::batch::schedule::resolve(Some("1/2"), Some(3), &none).unwrap_err();
        let m = super::as_flags(&e.to_string());
        assert_eq!(
            m,
            "--shard 1/2 and --shard-count 3 name different splits; give one"
        );
    }

    /// `batch`'s refusals of the other target's options, made by
    /// `jobs::batch_target` with the option groups' names, print the
    /// flags the CLI printed when it made them itself.
    #[test]
    fn batch_target_option_refusals_print_as_before() {
        use surfmotion::jobs::batch_target::check_target_options;
        let e = check_target_options(true, false, true).unwrap_err();
        assert_eq!(
            super::as_flags(&e.to_string()),
            "--group, --marker-count, --marker-margin and --fps apply to --scan (a database has its own frame rate)"
        );
        let e = check_target_options(false, true, false).unwrap_err();
        assert_eq!(
            super::as_flags(&e.to_string()),
            "--deform, --no-deform, --t-skel, --w-retr, --no-interpolate, --no-blend, --skeleton and --repair-budget apply to --db"
        );
        assert!(check_target_options(true, true, false).is_ok());
        assert!(check_target_options(false, false, true).is_ok());
    }

    /// Session 37: the library's messages that named a verb's flags name
    /// the option (or the job) now; printed, they read as before.
    #[test]
    fn messages_that_named_flags_print_as_before() {
        for (library, printed) in [
            (
                "part labels (`InitOptions::parts` of `db::init`): head 2",
                "part labels (`db init --parts`): head 2",
            ),
            (
                "a key-frame pose (a `jobs::keyframe` key from POSE.json): 22 joints",
                "a key-frame pose (`keyframe --from POSE.json`): 22 joints",
            ),
            (
                "spaces -; `jobs::play::play_session` checks it against",
                "spaces -; `play --db DB --script` checks it against",
            ),
            (
                "a key-frame grid (the report of `jobs::keyframe::grid`): a",
                "a key-frame grid (`keyframe --grid --report`): a",
            ),
            (
                "rig from (`RigEmbedOptions::png` draws a glTF skin's)",
                "rig from (`rig embed --png` draws a glTF skin's)",
            ),
            (
                "look at the picture (`InitSetup::png`) and correct",
                "look at the picture (`--png`) and correct",
            ),
            (
                "  ... (the graph of db dir in JSON lists all)\n",
                "  ... (`surfmotion graph db dir --json` lists all)\n",
            ),
            (
                "entries (`InitOptions::sequences` of `db::init`: NAME=PATH)",
                "entries (`surfmotion db init --sequence NAME=PATH`)",
            ),
            (
                "under [rig] (see `jobs::rig::embed_rig`)",
                "under [rig] (see `surfmotion rig embed --help`)",
            ),
        ] {
            assert_eq!(super::as_flags(library), printed);
        }
    }

    /// The format-only writer options, refused by the library in its
    /// options' names, print the flags they printed when the CLI refused
    /// them itself.
    #[test]
    fn format_only_refusals_name_flags() {
        use surfmotion::jobs::format_options::{refuse_unless_glb, refuse_unless_usda};
        use surfmotion::mesh::io::{glb::GlbOptions, usd::UsdOptions};
        let glb = GlbOptions {
            quantize: true,
            normals: false,
        };
        let e = refuse_unless_glb(&glb, false, "--format pc2").unwrap_err();
        assert_eq!(
            super::as_flags(&e.to_string()),
            "--glb-quantize and --glb-no-normals apply to .glb output only, not --format pc2: leave them out or write a .glb"
        );
        let e = refuse_unless_usda(&UsdOptions { normals: false }, false, "o.glb").unwrap_err();
        assert_eq!(
            super::as_flags(&e.to_string()),
            "--usd-no-normals applies to .usda output only, not o.glb: leave it out or write a .usda"
        );
    }
}
