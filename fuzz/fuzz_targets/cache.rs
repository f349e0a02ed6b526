//! Fuzz target: the similarity cache file and the manifest must never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if data.len() >= 16 {
        // Use the file's own key so the parser goes past the header.
        let key = u64::from_le_bytes(data[8..16].try_into().unwrap());
        let _ = surfmotion::db::cache::parse_matrix(data, key);
    }
    let t = String::from_utf8_lossy(data);
    if let Ok(m) = toml::from_str::<surfmotion::db::Manifest>(&t) {
        let _ = m.validate();
    }
});
