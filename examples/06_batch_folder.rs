//! Tutorial 6: convert a whole folder of clips through a database, in
//! parallel and resumably (the batch runs any `batch::Converter`: the
//! retarget job here, `ScanTransferJob` for a scan).
//!
//! cargo run --release --example 06_batch_folder -- DB_DIR ../shared/data/mocap/cmu-amc/03 OUT_DIR

use surfmotion::db::Quiet;
use surfmotion::jobs::{BatchOptions, RetargetJob, batch_folder};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let [db, clips, out] = &a[..] else {
        return Err("usage: 06_batch_folder DB_DIR CLIPS_DIR OUT_DIR".into());
    };
    let job = RetargetJob::load(db.as_ref(), Default::default(), &Quiet)?;
    let opts = BatchOptions::default();
    let r = batch_folder(clips.as_ref(), out.as_ref(), &job, &opts, &|_| {})?;
    println!("{}", r.summary.line());
    Ok(())
}
