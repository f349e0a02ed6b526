//! What the retrieval sees of a clip with the feet on its footfalls
//! (issue 44): the query poses the trellis compares (`Analysed::on_floor`)
//! of a clip on the real samba capture, written out so that two runs (one
//! per `SURFMOTION_PLACEMENT`) can be compared frame by frame with the
//! database's skeletons.

use crate::common;

use surfmotion::db::Character;
use surfmotion::deform::DeformMode;
use surfmotion::drive::query::load_mocap;
use surfmotion::drive::{DriveOptions, Prepared};

/// Writes to `FOOTFALL_QUERY` (a JSON path) the query poses of the clip
/// `FOOTFALL_CLIP` (a path under the shared data; default CMU 03_02) on
/// the samba capture as the tests build it, with the placement of the
/// environment, and the database's frame skeletons: `{"on_floor": [[[x,
/// y, z]; 19]; frames], "query": …, "db": …}` (what retrieval compares,
/// what the surface follows, the database). A measurement: writes a file.
#[test]
#[ignore = "measurement: writes the query poses the retrieval compares"]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_query_the_retrieval_sees() {
    let Some(d) = common::data_dir() else { return };
    let Ok(out) = std::env::var("FOOTFALL_QUERY") else {
        eprintln!("FOOTFALL_QUERY not set: nothing to write");
        return;
    };
    let clip = std::env::var("FOOTFALL_CLIP").unwrap_or("mocap/cmu-amc/03/03_02.amc".into());
    let ch = Character::load(&crate::deform::samba_capture_db(&d), &surfmotion::db::Quiet).unwrap();
    let opts = DriveOptions {
        deform: DeformMode::None,
        ..DriveOptions::default()
    };
    let prep = Prepared::new(&ch, &opts).unwrap();
    let m = load_mocap(&d.join(clip), &Default::default(), ch.manifest().fps).unwrap();
    let a = prep.analyse(&ch, &m.reference, &m.poses);
    let arr = |p: &[surfmotion::pose::Pose]| -> Vec<Vec<[f64; 3]>> {
        p.iter()
            .map(|q| q.iter().map(|v| v.to_array()).collect())
            .collect()
    };
    let json = serde_json::json!({
        "on_floor": arr(&a.on_floor),
        "query": arr(&a.query),
        "db": arr(ch.poses()),
    });
    std::fs::write(&out, json.to_string()).unwrap();
}
