//! Which options the command line gave, whatever their values: `batch
//! --db --fps 30` gives `--fps` although 30 is its default, so a refusal
//! of options that do not apply cannot be passed by typing the default.

use clap::parser::ValueSource;

/// The long flags (`--fps`) of the options of group `G` that `m` (the
/// matches of a command that flattens `G`) took from the command line, in
/// `G`'s order; none when each was left out (at its default or unset).
pub fn given<G: clap::Args>(m: &clap::ArgMatches) -> Vec<String> {
    let group = G::augment_args(clap::Command::new("group"));
    group
        .get_arguments()
        .filter(|a| m.value_source(a.get_id().as_str()) == Some(ValueSource::CommandLine))
        .map(|a| format!("--{}", a.get_long().unwrap_or(a.get_id().as_str())))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::given;
    use clap::Args;

    /// The flags of `G` that `argv` (without the program name) gives.
    fn flags<G: Args>(argv: &[&str]) -> Vec<String> {
        let cmd = G::augment_args(clap::Command::new("t"));
        let m = cmd
            .try_get_matches_from(std::iter::once("t").chain(argv.iter().copied()))
            .expect("parses");
        given::<G>(&m)
    }

    /// A value equal to the default counts as given; nothing given is
    /// none; flags (`--no-deform`) and repeatable options count too.
    #[test]
    fn a_default_value_typed_counts_as_given() {
        use crate::cli::{retarget, transfer};
        let fps = transfer::JobOpts::augment_args(clap::Command::new("t"))
            .get_arguments()
            .find(|a| a.get_id() == "fps")
            .map(|a| a.get_default_values().to_vec());
        assert_eq!(fps, Some(vec!["30".into()]), "--fps's default is 30");
        assert_eq!(flags::<transfer::JobOpts>(&["--fps", "30"]), ["--fps"]);
        assert!(flags::<transfer::JobOpts>(&[]).is_empty());
        assert_eq!(
            flags::<transfer::JobOpts>(&["--group", "body", "--marker-count=180"]),
            ["--group", "--marker-count"]
        );
        assert!(flags::<retarget::JobOpts>(&[]).is_empty());
        assert_eq!(
            flags::<retarget::JobOpts>(&["--no-deform", "--w-retr", "1"]),
            ["--no-deform", "--w-retr"]
        );
        assert_eq!(
            flags::<retarget::JobOpts>(&["--deform", "part"]),
            ["--deform"]
        );
        assert_eq!(
            flags::<retarget::JobOpts>(&["--repair-budget", "none", "--skeleton=regressor"]),
            ["--skeleton", "--repair-budget"]
        );
    }

    /// `batch`'s refusal of each target's options, printed, names every
    /// flag of the group it refuses (`--skeleton` and `--repair-budget`
    /// were refused unnamed until session 52).
    #[test]
    fn the_refusals_name_every_flag_of_their_group() {
        use crate::cli::{retarget, transfer};
        use surfmotion::jobs::batch_target::check_target_options;
        let all = |cmd: clap::Command| -> Vec<String> {
            let longs = cmd.get_arguments().filter_map(|a| a.get_long());
            longs.map(|l| format!("--{l}")).collect()
        };
        let printed = |database: bool| {
            let e = check_target_options(database, !database, database).unwrap_err();
            crate::cli::flags::as_flags(&e.to_string())
        };
        let scan = all(transfer::JobOpts::augment_args(clap::Command::new("t")));
        let db = all(retarget::JobOpts::augment_args(clap::Command::new("t")));
        for (flags, m) in [(scan, printed(true)), (db, printed(false))] {
            for f in flags {
                let named = m.split([' ', ',']).any(|w| w == f);
                assert!(named, "{f} not named in: {m}");
            }
        }
    }
}
