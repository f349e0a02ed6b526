//! `rig embed`: landmarks on a rest mesh (or a rigged glTF's skin) → the
//! canonical joints, skin weights, body parts and joint regressors, saved
//! as JSON, with the embedding's self-check.

use crate::embed::landmarks::{Landmarks, Mark};
use crate::embed::parts::{Part, neighbours, piece_counts};
use crate::embed::scan_landmarks::{AutoLandmarks, Disagreement, ScanOptions, estimate, find};
use crate::embed::{EmbedCheck, EmbedError, Embedding, parse_parts};
use crate::mesh::Mesh;
use crate::rig::Canonical;
use crate::util::fsutil::read_text;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use super::JobError;

/// Where the rig comes from and where it goes.
#[derive(Clone, Debug, Default)]
pub struct RigEmbedOptions {
    /// The rest mesh's name (a file, or `SEQ.pc2:FRAME`), for messages and
    /// to tell a glTF given as both mesh and skin.
    pub mesh: String,
    /// Only some OBJ groups of the file were kept (landmarks given as
    /// vertex ids become points; part labels are refused).
    pub groups: bool,
    /// Landmark JSON.
    pub landmarks: Option<PathBuf>,
    /// Or a rigged glTF whose skin gives the rig.
    pub skin: Option<PathBuf>,
    /// A rig map for the skin's joint names.
    pub rig_map: Option<PathBuf>,
    /// Explicit part labels, JSON `{part: [vertex ids]}`.
    pub parts: Option<PathBuf>,
    /// The embedding written (JSON).
    pub output: PathBuf,
    /// A picture of the mesh coloured by part with the skeleton (PNG).
    pub png: Option<PathBuf>,
    /// Without `landmarks` and `skin`: the automatic landmarks are
    /// refused below this confidence (0..1; the CLI's default 0.5).
    pub min_confidence: f64,
    /// Write the landmarks used (automatic ones) as a landmark file a user
    /// can edit and give back as `landmarks`.
    pub write_landmarks: Option<PathBuf>,
}

/// One body part of an embedding.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PartCount {
    /// Vertices labelled with it.
    pub vertices: usize,
    /// Vertices of its overlapping region.
    pub region: usize,
    /// Its connected pieces.
    pub pieces: usize,
}

/// What `rig embed` made.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RigEmbedReport {
    /// The embedding written.
    pub output: PathBuf,
    /// Embedding time.
    pub seconds: f64,
    /// Each canonical joint's position.
    pub joints: BTreeMap<&'static str, [f64; 3]>,
    /// Each body part.
    pub parts: BTreeMap<&'static str, PartCount>,
    /// The direction the body faces.
    pub facing: [f64; 3],
    /// Its height.
    pub height: f64,
    /// Notes of the embedding.
    pub notes: Vec<String>,
    /// The self-check.
    pub check: EmbedCheck,
    /// The automatic landmarks, when no landmarks or skin were given.
    pub automatic: Option<AutoLandmarks>,
    /// Given landmarks far (over 10 % of the height) from the automatic
    /// ones, when the automatic ones are confident (a left/right swap is
    /// named).
    pub disagreements: Vec<Disagreement>,
    /// The mesh's name.
    #[serde(skip)]
    pub mesh: String,
    /// Vertices of the mesh embedded in.
    #[serde(skip)]
    pub vertices: usize,
    /// The picture drawn.
    #[serde(skip)]
    pub png: Option<PathBuf>,
}

/// Embeds a rig in `mesh` as `o` says, saves it to `o.output` (and the
/// picture to `o.png`), and reports joints, parts and the self-check.
/// Steps: the part labels, the embedding (from landmarks, a skin or the
/// geometry), the files written, the report.
pub fn embed_rig(mut mesh: Mesh, o: &RigEmbedOptions) -> Result<RigEmbedReport, JobError> {
    let parts = match &o.parts {
        Some(p) => Some(parse_parts(&read_text(p)?, p, mesh.triangles(), mesh.vertex_count())?.0),
        None => None,
    };
    let t = Instant::now();
    let mut automatic = None;
    let mut disagreements = Vec::new();
    let e = match (&o.landmarks, &o.skin) {
        (Some(l), _) => {
            let (e, d) = from_landmarks(&mut mesh, l, parts, o)?;
            disagreements = d;
            e
        }
        (None, Some(g)) => from_skin(&mut mesh, g, parts, o)?,
        (None, None) => {
            let (e, a) = from_geometry(&mut mesh, parts, o)?;
            automatic = Some(a);
            e
        }
    };
    if let (Some(a), Some(p)) = (&automatic, &o.write_landmarks) {
        let text = a.to_json();
        crate::util::fsutil::write_atomic(p, |w| std::io::Write::write_all(w, text.as_bytes()))?;
    }
    let seconds = t.elapsed().as_secs_f64();
    e.save(&o.output)?;
    let check = crate::embed::check(&e, &mesh);
    if let Some(p) = &o.png {
        let img = super::render::draw(
            mesh.positions(),
            mesh.triangles(),
            Some(&e),
            glam::DVec3::from_array(e.facing),
            600,
        );
        img.save_png(p)?;
    }
    Ok(RigEmbedReport {
        output: o.output.clone(),
        seconds,
        joints: Canonical::ALL
            .iter()
            .map(|c| (c.name(), e.joints[c.index()]))
            .collect(),
        parts: part_counts(&mesh, &e),
        facing: e.facing,
        height: e.height,
        notes: e.notes.clone(),
        check,
        automatic,
        disagreements,
        mesh: o.mesh.clone(),
        vertices: mesh.vertex_count(),
        png: o.png.clone(),
    })
}

/// The embedding from the landmark file `l` (with `o.groups`: landmarks
/// as points, the kept groups repaired), and the landmarks that contradict
/// confident automatic ones.
fn from_landmarks(
    mesh: &mut Mesh,
    l: &std::path::Path,
    parts: Option<Vec<u8>>,
    o: &RigEmbedOptions,
) -> Result<(Embedding, Vec<Disagreement>), JobError> {
    let mut disagreements = Vec::new();
    let mut lm = Landmarks::load(l, mesh.vertex_count())?;
    if o.groups {
        // Only the groups' vertices: landmarks given as vertex ids
        // of the file become points first.
        if parts.is_some() {
            return Err(JobError::Usage(
                "`RigEmbedOptions::parts` with `RigEmbedOptions::groups`: part labels name the file's vertices".into(),
            ));
        }
        let points: Vec<_> = lm
            .marks
            .keys()
            .filter_map(|&l| lm.point(l, mesh.positions()).map(|p| (l, p)))
            .collect();
        for (l, p) in points {
            lm.marks.insert(l, Mark::Point(p));
        }
        *mesh = crate::mesh::repair::repair(mesh, &Default::default()).0;
    }
    // A file that contradicts confident automatic landmarks (a
    // left/right swap) is reported, not silently obeyed.
    if let Ok((Some(a), None)) = estimate(mesh.positions(), mesh.triangles())
        && a.confidence >= o.min_confidence
    {
        disagreements = crate::embed::scan_landmarks::compare(&a, &lm, mesh.positions(), 10.0);
    }
    // A degenerate landmark set is the landmark file's fault: name it.
    let e = Embedding::new(mesh, &lm, parts).map_err(|e| match e {
        EmbedError::Landmarks(le) => JobError::Input {
            path: l.to_path_buf(),
            msg: le.to_string(),
        },
        e @ EmbedError::Mesh(_) => JobError::Usage(format!("{}: {e}", o.mesh)),
        other => other.into(),
    })?;
    Ok((e, disagreements))
}

/// The embedding from the rigged glTF `g`'s skin (the glTF itself as the
/// mesh when it is also `o.mesh`: its bind pose).
fn from_skin(
    mesh: &mut Mesh,
    g: &std::path::Path,
    parts: Option<Vec<u8>>,
    o: &RigEmbedOptions,
) -> Result<Embedding, JobError> {
    if parts.is_some() {
        return Err(JobError::Usage(
            "`RigEmbedOptions::parts` goes with `RigEmbedOptions::landmarks`; a skin gives its own parts".into(),
        ));
    }
    let asset = crate::rig::read_rigged_character(g)?;
    // The glTF itself as the mesh: its bind pose, not its animation (an
    // FBX's skin may read at another unit than the file as a mesh).
    if same_file(std::path::Path::new(&o.mesh), g) {
        *mesh = asset.mesh.clone();
    }
    let map = match &o.rig_map {
        Some(m) => Some(crate::rig::RigMap::load(m)?),
        None => None,
    };
    Ok(crate::embed::skin::from_skin(
        mesh,
        &asset,
        map.as_ref(),
        g,
    )?)
}

/// Whether two paths name one file (`./a.fbx` and `a.fbx` do).
fn same_file(a: &std::path::Path, b: &std::path::Path) -> bool {
    a == b
        || matches!(
            (std::fs::canonicalize(a), std::fs::canonicalize(b)),
            (Ok(x), Ok(y)) if x == y
        )
}

/// The embedding from automatic landmarks found on the geometry (issue 41),
/// with those landmarks.
fn from_geometry(
    mesh: &mut Mesh,
    parts: Option<Vec<u8>>,
    o: &RigEmbedOptions,
) -> Result<(Embedding, AutoLandmarks), JobError> {
    if o.groups {
        *mesh = crate::mesh::repair::repair(mesh, &Default::default()).0;
    }
    let opts = ScanOptions {
        min_confidence: o.min_confidence,
    };
    let a = find(mesh.positions(), mesh.triangles(), &opts).map_err(|e| JobError::Input {
        path: PathBuf::from(&o.mesh),
        msg: e.to_string(),
    })?;
    let lm = a.landmarks();
    let e = Embedding::new(mesh, &lm, parts).map_err(|e| match e {
        EmbedError::Landmarks(le) => JobError::Input {
            path: PathBuf::from(&o.mesh),
            msg: format!("the automatic landmarks: {le}"),
        },
        e @ EmbedError::Mesh(_) => JobError::Usage(format!("{}: {e}", o.mesh)),
        other => other.into(),
    })?;
    Ok((e, a))
}

/// Each body part's vertices, region and connected pieces.
fn part_counts(mesh: &Mesh, e: &Embedding) -> BTreeMap<&'static str, PartCount> {
    let nb = neighbours(mesh.vertex_count(), mesh.triangles());
    let pieces = piece_counts(&e.labels, &nb);
    let mut sizes = [0usize; Part::COUNT];
    for &l in &e.labels {
        sizes[l as usize] += 1;
    }
    Part::ALL
        .iter()
        .map(|p| {
            let c = PartCount {
                vertices: sizes[p.index()],
                region: e.regions[p.index()].len(),
                pieces: pieces[p.index()],
            };
            (p.name(), c)
        })
        .collect()
}
