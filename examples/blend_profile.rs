use glam::DMat3;
use std::time::Instant;
use surfmotion::mesh::blend::{Blender, slerp};
use surfmotion::mesh::io::{LoadOptions, load_sequence};
fn main() {
    let s = load_sequence("../shared/data/4d/samba/samba.pc2", &LoadOptions::default()).unwrap();
    let m = s.frame_mesh(0);
    let b = Blender::new(&m).unwrap();
    let mut ws = b.workspace();
    let ga = b.decompose(s.frame(0), &mut ws);
    let gb = b.decompose(s.frame(60), &mut ws);
    let n = ga.rotation.len();
    let mut tr = vec![DMat3::IDENTITY; n];
    let mut small = 0;
    for i in 0..n { if ga.rotation[i].dot(gb.rotation[i]).abs() > 0.9995 { small += 1; } }
    println!("{small} of {n} pairs under the nlerp threshold");
    for _ in 0..3 {
        let t = Instant::now();
        for _ in 0..100 { for i in 0..n { tr[i] = DMat3::from_quat(slerp(ga.rotation[i], gb.rotation[i], 0.4)); } }
        println!("slerp+from_quat {:.3} ms", t.elapsed().as_secs_f64() * 10.0);
        let t = Instant::now();
        for _ in 0..100 { for i in 0..n { tr[i] = DMat3::from_quat(ga.rotation[i]) * (ga.stretch[i] * 0.6 + gb.stretch[i] * 0.4); } }
        println!("mat {:.3} ms", t.elapsed().as_secs_f64() * 10.0);
        let mut out = vec![[0.0; 3]; m.vertex_count()];
        let t = Instant::now();
        for _ in 0..100 { b.blend(&ga, &gb, 0.4, &mut out, &mut ws); }
        println!("blend {:.3} ms", t.elapsed().as_secs_f64() * 10.0);
    }
}
