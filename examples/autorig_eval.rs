//! Evaluation of the automatic rig (issue 41):
//! [`surfmotion::tools::autorig`] makes the tables (standard output)
//! and the details (standard error).
//!
//! cargo run --release --example autorig_eval -- [DATA]
//!     [real|synth|bodies|headless|confusion [BODY [DIR]]|tips|all|held-parts|facing|orders|contact [FRAMES]|joints|spread [SALTS] [renumbered]]
//! (DATA defaults to `../shared/data`; run from the repository, where
//! `tests/fixtures` is.) `SURFMOTION_AUTORIG` sets the rules as for `db init`.

use surfmotion::tools::autorig::{AutorigMode, evaluate_autorig};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.get(1).map(String::as_str) == Some("headless") {
        let data = std::path::PathBuf::from(&args[0]);
        let report = surfmotion::tools::autorig_headless::evaluate_headless(&data)?;
        eprint!("{}", report.details);
        print!("{report}");
        return Ok(());
    }
    if args.get(1).map(String::as_str) == Some("confusion") {
        let data = std::path::PathBuf::from(&args[0]);
        let only = args.get(2).map(String::as_str);
        let dir = args.get(3).map(std::path::Path::new);
        let report = surfmotion::tools::autorig_confusion::evaluate_confusion(&data, only, dir)?;
        eprint!("{}", report.details);
        print!("{report}");
        return Ok(());
    }
    if args.get(1).map(String::as_str) == Some("tips") {
        let data = std::path::PathBuf::from(&args[0]);
        let report = surfmotion::tools::autorig_tips::evaluate_tips(&data);
        eprint!("{}", report.details);
        print!("{report}");
        return Ok(());
    }
    let (data, mode) = AutorigMode::parse(&args)?;
    let report = evaluate_autorig(&data, &mode)?;
    eprint!("{}", report.details);
    print!("{report}");
    Ok(())
}
