//! Tutorial 7: key-frame animation (Huang et al. 2015, Sec. 5.1): the path
//! through the Surface Motion Graph from one database frame to another
//! that travels a distance in a time (Eq. 7), its transitions blended,
//! written frame by frame. The options are those of `surfmotion keyframe`.
//!
//! cargo run --release --example 07_keyframe_path -- synth_db walk:0 run:40 kf.pc2
//! (`synth_db`: tutorials 2 and 3; key-frames SEQUENCE:FRAME)

use surfmotion::db::{Character, Quiet};
use surfmotion::jobs::keyframe::{KeyframeJobOptions, resolve_keys, write_path};
use surfmotion::keyframe::Targets;

/// 10 m in 6 s (met within 1 % on `synth_db`).
const TARGETS: Targets = Targets::Global {
    distance: 10.0,
    time: 6.0,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let [db, from, to, out] = &a[..] else {
        return Err("usage: 07_keyframe_path DB_DIR FROM TO OUT".into());
    };
    let ch = Character::load(db.as_ref(), &Quiet)?;
    let keys = resolve_keys(&ch, &[from, to], &Default::default())?;
    let opts = KeyframeJobOptions::default().keyframe_options(ch.manifest().fps);
    let r = write_path(&ch, &keys, &TARGETS, &opts, out.as_ref(), &mut |_| {})?.report;
    println!("{:.3} m in {:.3} s", r.report.distance, r.report.time);
    Ok(())
}
