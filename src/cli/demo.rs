//! `surfmotion demo`.

/// Arguments of `demo`.
#[derive(clap::Args)]
pub struct Args {}

/// Runs the demo. The end-to-end job (a procedural character driven by a
/// procedural clip through the surface motion graph) needs the synthesis
/// pipeline, which does not exist yet; until then this says so plainly.
pub fn run(_: Args) -> anyhow::Result<()> {
    crate::outln!(
        "surfmotion demo: not available yet.\n\
         \n\
         The demo will drive an embedded procedural character with a procedural clip\n\
         once the mocap-driven synthesis pipeline exists. What works today:\n\
         \n\
         \x20 surfmotion inspect FILE [--json]                 any mocap or mesh file\n\
         \x20 surfmotion mocap positions CLIP --frames 0,10    forward kinematics\n\
         \x20 surfmotion mocap convert IN.amc OUT.bvh --fps 30 convert and resample clips\n\
         \x20 surfmotion mocap rigmap CLIP -o map.json         detected rig convention\n\
         \x20 surfmotion mocap procedural -o clips             procedural walk/run/turn BVH\n\
         \x20 surfmotion mesh convert samba.pc2 samba.glb      mesh sequence formats\n\
         \x20 surfmotion blend A.pc2:0 A.pc2:60 -o mid.obj     non-linear mesh blending\n\
         \x20 surfmotion repair scan.obj -o clean.obj          weld, drop degenerate, components\n\
         \x20 surfmotion db init DIR --mesh M --sequence N=P   character database manifest\n\
         \x20 surfmotion rig embed MESH --landmarks L -o R     joints, skin weights, parts, regressors\n\
         \x20 surfmotion db skeleton DIR                       per-frame skeletons (JSON + BVH)\n\
         \x20 surfmotion synth --mesh M --landmarks L --mocap CLIP... -o DIR\n\
         \x20                                                  synthetic multi-motion database\n\
         \x20 surfmotion render MESH --rig R -o view.png       a mesh and its rig as PNG"
    )?;
    Ok(())
}
