//! Fuzz target: the parametric model cache (`DIR/cache/parametric.bin`,
//! read by `play` and `web export`) must never panic or allocate from its
//! header counts; a bad file is a reason, and the model is rebuilt.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;

fuzz_target!(|data: &[u8]| {
    static MESH: OnceLock<surfmotion::mesh::Mesh> = OnceLock::new();
    let mesh = MESH.get_or_init(|| {
        surfmotion::mesh::Mesh::new(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            vec![[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]],
        )
        .expect("a tetrahedron")
    });
    // The file's own key (after the 8-byte magic), so parsing goes on.
    let key = data
        .get(8..16)
        .map_or(0, |k| u64::from_le_bytes(k.try_into().unwrap()));
    let _ = surfmotion::parametric::store::parse(data, key, mesh, &Default::default());
});
