//! Fuzz target: a rig map file (`mocap rigmap -o`, `--rig-map`) read and
//! applied to a fixed clip must never panic: unknown joints, bad rules and
//! absurd numbers are errors.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;
use std::sync::OnceLock;

const BVH: &str = "HIERARCHY\nROOT Hips\n{\nOFFSET 0 90 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\nJOINT Spine\n{\nOFFSET 0 10 0\nCHANNELS 3 Zrotation Yrotation Xrotation\nEnd Site\n{\nOFFSET 0 50 0\n}\n}\nJOINT LeftUpLeg\n{\nOFFSET 9 -5 0\nCHANNELS 3 Zrotation Yrotation Xrotation\nEnd Site\n{\nOFFSET 0 -42 0\n}\n}\n}\nMOTION\nFrames: 2\nFrame Time: 0.0333333\n0 90 0 0 0 0 0 0 0 0 0 0\n1 90 0 10 0 0 0 5 0 0 0 7\n";

fuzz_target!(|data: &[u8]| {
    static CLIP: OnceLock<surfmotion::mocap::Clip> = OnceLock::new();
    let clip = CLIP.get_or_init(|| {
        surfmotion::mocap::bvh::parse_bvh(BVH, Path::new("f.bvh"), &Default::default())
            .expect("fixed BVH parses")
    });
    let t = surfmotion::util::fsutil::decode_text(data.to_vec());
    if let Ok(map) = serde_json::from_str::<surfmotion::rig::RigMap>(&t) {
        let _ = map.poses(clip);
    }
});
