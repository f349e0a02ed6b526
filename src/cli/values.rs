//! The command line's mirror of [`Overlap`], whose library docs are too
//! long for `--help`. The library's other option enums derive
//! `clap::ValueEnum` themselves (with the `cli` feature), so their
//! variants' doc comments are the help: one source.

use surfmotion::live::Overlap;

/// When `live` deforms two frames at once ([`Overlap`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum OverlapArg {
    /// One frame at a time.
    Off,
    /// Two at once while frames queue.
    Queued,
    /// Every frame held for the next.
    Always,
}

impl From<OverlapArg> for Overlap {
    fn from(o: OverlapArg) -> Overlap {
        match o {
            OverlapArg::Off => Overlap::Off,
            OverlapArg::Queued => Overlap::Queued,
            OverlapArg::Always => Overlap::Always,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum;

    /// The mirror accepts exactly the library's variants, each converting
    /// to the variant of the same name.
    #[test]
    fn the_overlap_mirror_is_the_library_enum() {
        for o in OverlapArg::value_variants() {
            let name = o.to_possible_value().unwrap().get_name().to_string();
            assert_eq!(format!("{:?}", Overlap::from(*o)).to_lowercase(), name);
        }
        assert_eq!(OverlapArg::value_variants().len(), 3);
    }
}
