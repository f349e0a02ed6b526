//! Fuzz target: the amc reader must never panic and never allocate beyond its input.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    // A fixed one-bone skeleton; the AMC text is fuzzed.
    const ASF: &str = ":units\n length 0.45\n:root\n order TX TY TZ RX RY RZ\n axis XYZ\n:bonedata\n begin\n name a\n direction 0 1 0\n length 1\n axis 0 0 0 XYZ\n dof rx rz\n end\n:hierarchy\n begin\n root a\n end\n";
    let skel =
        surfmotion::mocap::asfamc::parse_asf(ASF, Path::new("f.asf")).expect("fixed ASF parses");
    let t = surfmotion::util::fsutil::decode_text(data.to_vec());
    let _ =
        surfmotion::mocap::asfamc::parse_amc(&t, Path::new("fuzz.amc"), &skel, &Default::default());
});
