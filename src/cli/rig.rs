//! `surfmotion rig embed`: landmarks on a rest mesh → joints, skin weights,
//! body parts and joint regressors.

use std::path::PathBuf;
use std::time::Instant;
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::embed::parts::{Part, neighbours, piece_counts};
use surfmotion::embed::{Embedding, parse_parts};
use surfmotion::rig::Canonical;
use surfmotion::util::fsutil::read_text;

/// `rig` subcommands.
#[derive(clap::Subcommand)]
pub enum Cmd {
    /// Embed a rig in a rest mesh from landmarks (chin, groin, wrists,
    /// elbows, knees; optionally shoulders, ankles, toes, head_top) given as
    /// JSON points or vertex indices. Writes joints, bone-heat skin weights,
    /// contiguous body parts with overlapping regions and joint regressors.
    #[command(
        after_help = "Example:\n  surfmotion rig embed samba.obj --landmarks samba.landmarks.json -o samba.rig.json --png samba_rig.png"
    )]
    Embed(EmbedArgs),
}

/// Arguments of `rig embed`.
#[derive(clap::Args)]
pub struct EmbedArgs {
    /// Rest mesh (a file, or SEQ.pc2:FRAME).
    #[arg(value_parser = super::mesh_spec)]
    pub mesh: String,
    /// Only these OBJ groups of the mesh (repeatable), e.g. `body`; the
    /// embedding is for the groups' vertices alone (renumbered in order).
    #[arg(long, value_name = "NAME")]
    pub group: Vec<String>,
    /// Landmark JSON.
    #[arg(long, required_unless_present = "skin", conflicts_with = "skin")]
    pub landmarks: Option<PathBuf>,
    /// Or take the rig from a rigged glTF (.glb/.gltf) or FBX (.fbx) of
    /// this character: its skin's joints and weights, matched to the mesh
    /// by vertex position (an FBX in metres by its UnitScaleFactor, Y up).
    #[arg(long)]
    pub skin: Option<PathBuf>,
    /// A rig map (canonical joint → skin joint name) for a skin whose
    /// joint names are not detected (e.g. unnamed `joint_N` nodes).
    #[arg(long = "rig-map", requires = "skin")]
    pub rig_map: Option<PathBuf>,
    /// Explicit part labels, JSON {part: [vertex ids]}, overriding the computed ones.
    #[arg(long)]
    pub parts: Option<PathBuf>,
    /// Output embedding (JSON).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also draw the mesh coloured by part with the skeleton (PNG).
    #[arg(long, value_parser = super::png_path)]
    pub png: Option<PathBuf>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs a `rig` subcommand.
pub fn run(c: Cmd) -> anyhow::Result<()> {
    match c {
        Cmd::Embed(a) => embed(a),
    }
}

fn embed(a: EmbedArgs) -> anyhow::Result<()> {
    // No output over an input, checked before any work (`-o LANDMARKS.json`
    // replaced the landmarks with the embedding, exit 0).
    let mut inputs = surfmotion::mesh::io::input_files(&a.mesh, None);
    inputs.extend(
        [&a.landmarks, &a.skin, &a.rig_map, &a.parts]
            .into_iter()
            .flatten()
            .cloned(),
    );
    let mut outputs = vec![("-o", a.output.clone())];
    outputs.extend(a.png.clone().map(|p| ("--png", p)));
    surfmotion::jobs::outputs::refuse_colliding(&inputs, &outputs)?;
    let mut mesh = super::load_mesh_groups(&a.mesh, &a.group)?;
    let parts = match &a.parts {
        Some(p) => Some(parse_parts(&read_text(p)?, p, mesh.triangles(), mesh.vertex_count())?.0),
        None => None,
    };
    let t = Instant::now();
    let e = match (&a.landmarks, &a.skin) {
        (Some(l), _) => {
            let mut lm = Landmarks::load(l, mesh.vertex_count())?;
            if !a.group.is_empty() {
                // Only the groups' vertices: landmarks given as vertex ids
                // of the file become points first.
                anyhow::ensure!(
                    parts.is_none(),
                    "--parts with --group: part labels name the file's vertices"
                );
                let points: Vec<_> = lm
                    .marks
                    .keys()
                    .filter_map(|&l| lm.point(l, mesh.positions()).map(|p| (l, p)))
                    .collect();
                for (l, p) in points {
                    lm.marks
                        .insert(l, surfmotion::embed::landmarks::Mark::Point(p));
                }
                mesh = surfmotion::mesh::repair::repair(&mesh, &Default::default()).0;
            }
            // A degenerate landmark set is the landmark file's fault: name it.
            Embedding::new(&mesh, &lm, parts).map_err(|e| match e {
                surfmotion::embed::EmbedError::Landmarks(le) => {
                    anyhow::anyhow!("{}: {le}", l.display())
                }
                e @ surfmotion::embed::EmbedError::Mesh(_) => {
                    anyhow::anyhow!("{}: {e}", a.mesh)
                }
                other => other.into(),
            })?
        }
        (None, Some(g)) => {
            anyhow::ensure!(
                parts.is_none(),
                "--parts goes with --landmarks; a skin gives its own parts"
            );
            let asset = surfmotion::mesh::io::read_rigged(g)?;
            // The glTF itself as the mesh: its bind pose, not its animation.
            if std::path::Path::new(&a.mesh) == g.as_path() {
                mesh = asset.mesh.clone();
            }
            let map = match &a.rig_map {
                Some(m) => Some(surfmotion::rig::RigMap::load(m)?),
                None => None,
            };
            surfmotion::embed::skin::from_skin(&mesh, &asset, map.as_ref(), g)?
        }
        (None, None) => anyhow::bail!("give --landmarks or --skin"),
    };
    let secs = t.elapsed().as_secs_f64();
    e.save(&a.output)?;
    let verdict = surfmotion::embed::check(&e, &mesh);
    if let Some(p) = &a.png {
        let img = super::render::draw(
            mesh.positions(),
            mesh.triangles(),
            Some(&e),
            glam::DVec3::from_array(e.facing),
            600,
        );
        img.save_png(p)?;
    }
    let nb = neighbours(mesh.vertex_count(), mesh.triangles());
    let pieces = piece_counts(&e.labels, &nb);
    let mut sizes = [0usize; Part::COUNT];
    for &l in &e.labels {
        sizes[l as usize] += 1;
    }
    if a.json {
        let v = serde_json::json!({
            "output": a.output,
            "seconds": secs,
            "joints": Canonical::ALL.iter().map(|c| (c.name(), e.joints[c.index()])).collect::<std::collections::BTreeMap<_, _>>(),
            "parts": Part::ALL.iter().map(|p| (p.name(), serde_json::json!({"vertices": sizes[p.index()], "region": e.regions[p.index()].len(), "pieces": pieces[p.index()]}))).collect::<std::collections::BTreeMap<_, _>>(),
            "facing": e.facing,
            "height": e.height,
            "notes": e.notes,
            "check": verdict,
        });
        crate::outln!("{}", serde_json::to_string_pretty(&v)?)?;
        return Ok(());
    }
    crate::outln!(
        "embedded a rig in {} ({} vertices) in {:.2} s → {}",
        a.mesh,
        mesh.vertex_count(),
        secs,
        a.output.display()
    )?;
    let f = e.facing;
    crate::outln!(
        "  height {:.3}, facing ({:.2}, {:.2}, {:.2})",
        e.height,
        f[0],
        f[1],
        f[2]
    )?;
    crate::outln!("  joints:")?;
    for c in Canonical::ALL {
        let p = e.joints[c.index()];
        crate::outln!(
            "    {:<11} ({:>7.3}, {:>7.3}, {:>7.3})",
            c.name(),
            p[0],
            p[1],
            p[2]
        )?;
    }
    crate::outln!("  parts (labelled vertices / overlapping region / pieces):")?;
    for p in Part::ALL {
        crate::outln!(
            "    {:<12} {:>6} {:>6} {:>3}",
            p.name(),
            sizes[p.index()],
            e.regions[p.index()].len(),
            pieces[p.index()]
        )?;
    }
    for n in &e.notes {
        crate::outln!("  note: {n}")?;
    }
    crate::outln!(
        "  self-check: pelvis {:.2}% of the height off the mid-plane, hips {:.2}% asymmetric: {}",
        verdict.pelvis_offset_percent,
        verdict.hip_asymmetry_percent,
        if verdict.passed() {
            "passed".to_string()
        } else {
            format!("{} warning(s)", verdict.warnings.len())
        }
    )?;
    for w in &verdict.warnings {
        crate::outln!("  warning: {}", w.message)?;
    }
    if let Some(p) = &a.png {
        crate::outln!("  drew {}", p.display())?;
    }
    Ok(())
}
