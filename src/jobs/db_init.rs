//! `db init` as a job: a character's manifest (`character.toml`) written
//! from its files, every file read and checked first
//! ([`crate::db::init::assemble`]), nothing written on a refusal; with
//! landmarks, the rig embedded once and a setup report written beside the
//! manifest (`setup.json`): the rest frame chosen and why, the contacts
//! found, the parts' rigidity over the sequences, the rig's notes and
//! self-check.
//!
//! Without landmarks (and without a glTF skin) the character is rigged
//! from its capture ([`crate::embed::auto`]): the automatic landmarks are
//! written beside the manifest as `auto.landmarks.json` and the manifest
//! names them, so that `db build` embeds the rig as from any landmarks
//! (on a rest frame clear of contact, as above) and the user can edit the
//! file (and pass it back with `landmarks` as an override).

use super::JobError;
use super::outputs::check_output_folder;
use crate::db::init::{InitError, InitOptions, RestFrame, assemble_setup, assemble_setup_with};
use crate::db::{MANIFEST, Manifest};
use crate::embed::auto::options::{AutoOptions, automatic_setup};
use crate::embed::auto::report::AutoRig;
use crate::embed::auto::rig::auto_rig;
use crate::embed::contact::{Contact, FrameContacts};
use crate::embed::parts::Part;
use crate::embed::rest::{RestOptions, choose_rest_frame};
use crate::embed::rigidity::{PartRigidity, RigidityOptions, part_rigidity};
use crate::embed::{EmbedCheck, Embedding};
use crate::mesh::io::{LoadOptions, load_sequence};
use crate::util::fsutil::write_atomic;
use std::path::{Path, PathBuf};

/// The setup report's file name in the database folder.
pub(crate) const SETUP: &str = "setup.json";

/// The file the automatic landmarks are written to, in the database folder.
pub(crate) const AUTO_LANDMARKS: &str = "auto.landmarks.json";

/// What [`init_database`] wrote.
#[derive(Clone, Debug, serde::Serialize)]
pub struct InitReport {
    /// The manifest written (paths inside the folder relative to it).
    pub manifest: Manifest,
    /// Where it was written (`DIR/character.toml`).
    pub path: PathBuf,
    /// What the `auto` guesses decided, one line each (the up axis read
    /// as Z, the unit read as cm or mm), and the rest frame chosen.
    pub notes: Vec<String>,
    /// The setup report (with landmarks), also written as `DIR/setup.json`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub setup: Option<Setup>,
    /// The automatic rig, when the character was rigged from its capture.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub auto_rig: Option<AutoRig>,
}

/// The rig's setup: what a user checks before trusting the database.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Setup {
    /// The rest frame the rig is embedded on: `SEQUENCE:FRAME`, or
    /// `topology` for the topology's own positions.
    pub rest_frame: String,
    /// Why it was chosen (one line).
    pub why: String,
    /// Frames examined for contact (the topology's and every sequence's).
    pub frames_examined: usize,
    /// Frames with a contact.
    pub frames_in_contact: usize,
    /// Which: `topology`, `SEQUENCE:A-B` (a run) or `SEQUENCE:F`.
    pub contact_frames: Vec<String>,
    /// Contacts on the topology's frame (the parts named by the rig).
    pub topology_contacts: Vec<ContactReport>,
    /// Contacts on the rest frame chosen (empty when it is clear).
    pub rest_contacts: Vec<ContactReport>,
    /// Each part's rigidity over the sequences' frames, with the regions
    /// that follow another part.
    pub rigidity: Vec<PartRigidity>,
    /// The rig's notes (what was assumed while embedding).
    pub rig_notes: Vec<String>,
    /// The automatic rig's summary line and its warnings (`db info` shows
    /// them); empty when the landmarks were given.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub automatic: Vec<String>,
    /// The rig's self-check.
    pub check: EmbedCheck,
    /// Where the report was written.
    pub path: PathBuf,
    /// The missing head was said already (the automatic rig's note says
    /// why): [`Setup::text`] does not say it again.
    #[serde(skip)]
    pub head_said: bool,
    /// The picture written (front and side; `InitSetup::png`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub png: Option<PathBuf>,
}

/// One contact as reported.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ContactReport {
    /// Touching vertices (all sides).
    pub vertices: usize,
    /// The part of each side (its vertices' most frequent label).
    pub parts: Vec<&'static str>,
    /// Smallest distance between the sides, in the files' units.
    pub gap: f64,
    /// Centre of the touching vertices.
    pub centre: [f64; 3],
}

/// What `db init` does beyond the manifest. The defaults are `db init`'s.
#[derive(Clone, Debug, Default)]
pub struct InitSetup {
    /// A picture of the rig, front and side (the topology's frame, and
    /// below it the rest frame when another was chosen). Default none.
    pub png: Option<PathBuf>,
    /// The automatic rig's options, used without landmarks and glTF skin.
    /// Default [`AutoOptions::default`].
    pub auto: AutoOptions,
    /// Without landmarks and glTF skin, write the manifest without a rig
    /// instead of rigging the character from its capture (the graph,
    /// key-frame search and web export need none). Default false.
    pub no_rig: bool,
}

/// Writes the manifest of `opts` into the database folder `dir` (created
/// if missing). Refused before anything is written: a `dir` that is a file,
/// an existing manifest without `force`, a file that does not read, a
/// sequence of another mesh, a rest frame not a person's size in its unit.
pub fn init_database(dir: &Path, opts: &InitOptions) -> Result<InitReport, JobError> {
    init_database_with(dir, opts, &InitSetup::default())
}

/// [`init_database`], then, with landmarks, the rig embedded on the rest
/// frame and the setup report written (`DIR/setup.json`, and the picture
/// of `setup.png`).
pub fn init_database_with(
    dir: &Path,
    opts: &InitOptions,
    setup: &InitSetup,
) -> Result<InitReport, JobError> {
    check_output_folder(
        "",
        dir,
        "db init writes the database's character.toml into a folder",
    )?;
    // Nothing left behind on a refusal: every file this call wrote is put
    // back as it was (a failed automatic setup left `character.toml` and
    // `auto.landmarks.json`).
    let mut written = Written::new(dir);
    init_in(dir, opts, setup, &mut written).inspect_err(|_| written.undo())
}

/// [`init_database_with`]'s steps, each file recorded in `written` before
/// it is written.
fn init_in(
    dir: &Path,
    opts: &InitOptions,
    setup: &InitSetup,
    written: &mut Written,
) -> Result<InitReport, JobError> {
    let mut notes = Vec::new();
    let wants_auto = !setup.no_rig
        && opts.landmarks.is_none()
        && opts.gltf_skin.is_none()
        && !opts.sequences.is_empty();
    let mut o = opts.clone();
    let mut auto = None;
    let mut file = None;
    // The rest frame's rule and the automatic rig's options: without
    // landmarks `automatic_setup`'s (main's rule unless
    // `SURFMOTION_AUTORIG` asks the rules by pose), else main's rule.
    let (rule, auto_opts) = if wants_auto {
        automatic_setup(&setup.auto).map_err(JobError::Usage)?
    } else {
        (RestOptions::default(), setup.auto)
    };
    if wants_auto {
        // Every file read and checked first, refused with the words of a
        // database without a rig; then the rig is found from the capture.
        assemble_setup(dir, opts, &mut Vec::new())?;
        let (rig, f) = write_auto_landmarks(dir, &mut o, &auto_opts, &rule, written, &mut notes)?;
        auto = Some(rig);
        file = Some(f);
    }
    let (manifest, rest) = assemble_setup_with(dir, &o, &rule, &mut notes).map_err(|e| {
        if wants_auto {
            automatic_refused(e)
        } else {
            e.into()
        }
    })?;
    written.before(&dir.join(MANIFEST));
    manifest.save(dir)?;
    if let (Some(rig), Some(file)) = (&auto, &file) {
        notes.push(rig.summary());
        notes.extend(rig.notes.iter().map(|n| format!("automatic rig: {n}")));
        notes.push(format!(
            "automatic rig: landmarks written to {}; edit them and pass them with `InitOptions::landmarks` to override",
            file.display()
        ));
    }
    let setup = if manifest.rig.landmarks.is_some() {
        let mut s = write_setup(dir, &manifest, rest.as_ref(), auto.as_ref(), setup, written)?;
        s.head_said = auto.as_ref().is_some_and(|r| r.headless);
        Some(s)
    } else {
        if setup.png.is_some() {
            notes.push(
                "no picture written: the character has no landmarks to draw its rig from (`RigEmbedOptions::png` draws a glTF skin's)"
                    .into(),
            );
        }
        None
    };
    Ok(InitReport {
        manifest,
        path: dir.join(MANIFEST),
        notes,
        setup,
        auto_rig: auto,
    })
}

/// The files a `db init` wrote, each with what was there before, and
/// whether it made the folder: [`Written::undo`] puts them back (a file
/// that was there gets its old bytes, a new one goes, a new folder goes
/// when empty again), so that a refusal leaves the folder as it was.
struct Written {
    /// The folder, when this call made it.
    made: Option<PathBuf>,
    /// Each file written and its bytes before (`None`: it was not there).
    files: Vec<(PathBuf, Option<Vec<u8>>)>,
}

impl Written {
    fn new(dir: &Path) -> Written {
        Written {
            made: (!dir.exists()).then(|| dir.to_path_buf()),
            files: Vec::new(),
        }
    }

    /// Records `path` before it is written (a file there that does not
    /// read is not recorded: it is never removed).
    fn before(&mut self, path: &Path) {
        if self.files.iter().any(|(p, _)| p == path) {
            return;
        }
        match std::fs::read(path) {
            Ok(bytes) => self.files.push((path.to_path_buf(), Some(bytes))),
            Err(_) if !path.exists() => self.files.push((path.to_path_buf(), None)),
            Err(_) => {}
        }
    }

    /// Every recorded file put back, the folder removed when this call
    /// made it and it is empty again.
    fn undo(&self) {
        for (p, old) in self.files.iter().rev() {
            match old {
                Some(bytes) => {
                    let _ = crate::util::fsutil::write_bytes_atomic(p, bytes);
                }
                None => {
                    let _ = std::fs::remove_file(p);
                }
            }
        }
        if let Some(d) = &self.made {
            let _ = std::fs::remove_dir(d);
        }
    }
}

/// The automatic rig of `o`'s capture, its landmarks written as
/// [`AUTO_LANDMARKS`] in `dir` and named in `o`; `o.up` set from the rig
/// when `auto`. The rest frame is chosen by `rule`; the file is recorded
/// in `written`.
fn write_auto_landmarks(
    dir: &Path,
    o: &mut InitOptions,
    auto: &AutoOptions,
    rule: &RestOptions,
    written: &mut Written,
    notes: &mut Vec<String>,
) -> Result<(AutoRig, PathBuf), JobError> {
    let file = dir.join(AUTO_LANDMARKS);
    if file.exists() && !o.force {
        return Err(JobError::Input {
            path: file,
            msg: "automatic landmarks from an earlier `db init` are there: pass them as `InitOptions::landmarks` to keep them, or set `force` to find them again".into(),
        });
    }
    let (rig, vertex_count) = rig_capture(o, auto, rule)?;
    let axis = crate::embed::axes::nearest_axis(glam::DVec3::from_array(rig.up));
    let up = if axis == glam::DVec3::Y {
        "y"
    } else if axis == glam::DVec3::Z {
        "z"
    } else {
        return Err(JobError::Input {
            path: o.mesh.clone(),
            msg: format!(
                "automatic rigging: the body stands along ({:.0}, {:.0}, {:.0}); the database reads Y-up or Z-up files: turn the mesh and its sequences",
                axis.x, axis.y, axis.z
            ),
        });
    };
    if o.up.eq_ignore_ascii_case("auto") {
        o.up = up.into();
    } else if !o.up.eq_ignore_ascii_case(up) {
        notes.push(format!(
            "`InitOptions::up` {}, but the automatic rig finds the feet on a floor along +{}: is the capture {}-up?",
            o.up,
            up.to_ascii_uppercase(),
            up.to_ascii_uppercase()
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| JobError::Input {
        path: dir.to_path_buf(),
        msg: e.to_string(),
    })?;
    let json = rig.landmarks_json(vertex_count);
    written.before(&file);
    crate::util::fsutil::write_bytes_atomic(&file, json.as_bytes())?;
    o.landmarks = Some(file.clone());
    Ok((rig, file))
}

/// The rig embedded as the database will embed it, its report written.
fn write_setup(
    dir: &Path,
    m: &Manifest,
    rest: Option<&RestFrame>,
    auto: Option<&AutoRig>,
    o: &InitSetup,
    written: &mut Written,
) -> Result<Setup, JobError> {
    let topo = m.load_topology(dir)?;
    let rig = crate::db::skeletons::embed_rig(dir, m, &topo)?;
    let chosen = crate::db::skeletons::rest_frame(dir, m, &topo)?;
    let rest_positions = chosen.clone().unwrap_or_else(|| topo.positions().to_vec());
    // The self-check on the frame the rig was embedded on.
    let check = match chosen {
        Some(_) => {
            let at_rest = rig.carried(topo.positions(), &rest_positions);
            let mesh = topo
                .with_positions(&rest_positions)
                .map_err(|e| JobError::Usage(format!("the rest frame: {e}")))?;
            crate::embed::check(&at_rest, &mesh)
        }
        None => crate::embed::check(&rig, &topo),
    };
    // Rigidity over every sequence's frames (evenly sampled).
    let mut seqs = Vec::with_capacity(m.sequences.len());
    for s in &m.sequences {
        seqs.push(m.load_sequence(dir, s)?);
    }
    let frames: Vec<&[[f64; 3]]> = seqs
        .iter()
        .flat_map(|q| (0..q.frame_count()).map(move |f| q.frame(f)))
        .collect();
    let rigidity = part_rigidity(
        &rig.labels,
        &rest_positions,
        &frames,
        rig.height,
        &RigidityOptions::default(),
    );
    let describe = |c: &FrameContacts| c.contacts.iter().map(|k| contact(k, &rig)).collect();
    let (rest_frame, why, examined, in_contact, topology_contacts, rest_contacts) = match rest {
        Some(r) => (
            r.sequence
                .as_ref()
                .map_or_else(|| "topology".to_string(), |s| format!("{s}:{}", r.frame)),
            r.choice.why.clone(),
            r.choice.frames,
            r.choice.frames_in_contact,
            describe(&r.choice.first),
            describe(&r.choice.contacts),
        ),
        None => (
            "topology".to_string(),
            "not chosen (no sequences, or `InitOptions::choose_rest` off)".to_string(),
            0,
            0,
            Vec::new(),
            Vec::new(),
        ),
    };
    let png = match &o.png {
        Some(p) => {
            let facing = glam::DVec3::from_array(rig.facing);
            let mut img =
                super::render::draw(topo.positions(), topo.triangles(), Some(&rig), facing, 500);
            if rest.is_some_and(|r| r.sequence.is_some()) {
                img = img.above(&super::render::draw(
                    &rest_positions,
                    topo.triangles(),
                    Some(&rig),
                    facing,
                    500,
                ));
            }
            written.before(p);
            img.save_png(p)?;
            Some(p.clone())
        }
        None => None,
    };
    let report = Setup {
        rest_frame,
        why,
        frames_examined: examined,
        frames_in_contact: in_contact,
        contact_frames: rest.map_or_else(Vec::new, |r| r.contact_frames.clone()),
        topology_contacts,
        rest_contacts,
        rigidity,
        rig_notes: rig.notes.clone(),
        automatic: auto.map_or_else(Vec::new, |a| {
            let warnings = a.notes.iter().filter(|n| n.starts_with("WARNING"));
            std::iter::once(a.summary())
                .chain(warnings.cloned())
                .collect()
        }),
        check,
        path: dir.join(SETUP),
        png,
        head_said: false,
    };
    let text = serde_json::to_string_pretty(&report).map_err(|e| JobError::Usage(e.to_string()))?;
    written.before(&report.path);
    write_atomic(&report.path, |w| w.write_all(text.as_bytes()))?;
    Ok(report)
}

/// A contact with its sides' parts named by the rig's labels.
fn contact(c: &Contact, rig: &Embedding) -> ContactReport {
    let parts = c
        .sides
        .iter()
        .map(|side| {
            let mut votes = [0usize; Part::COUNT];
            for &v in side {
                if let Some(&l) = rig.labels.get(v as usize) {
                    votes[(l as usize).min(Part::COUNT - 1)] += 1;
                }
            }
            let best = (0..Part::COUNT).max_by_key(|&k| votes[k]).unwrap_or(0);
            Part::ALL[best].name()
        })
        .collect();
    ContactReport {
        vertices: c.vertex_count(),
        parts,
        gap: c.gap,
        centre: c.centre,
    }
}

/// The automatic rig of `opts`' mesh from all its sequences' frames, and
/// the mesh's vertex count.
fn rig_capture(
    opts: &InitOptions,
    auto: &AutoOptions,
    rule: &RestOptions,
) -> Result<(AutoRig, usize), JobError> {
    let spec = |p: &Path| p.to_string_lossy().into_owned();
    let topo = load_sequence(&spec(&opts.mesh), &LoadOptions::default())?;
    let mesh = topo.mesh();
    let load = LoadOptions {
        topology: Some(opts.mesh.clone()),
        fps: None,
    };
    let mut seqs = Vec::new();
    for (_, path) in &opts.sequences {
        seqs.push(load_sequence(&spec(path), &load)?);
    }
    let frames: Vec<&[[f64; 3]]> = seqs
        .iter()
        .flat_map(|s| (0..s.frame_count()).map(|f| s.frame(f)))
        .collect();
    let mut auto = *auto;
    let mut why = None;
    if auto.rest_frame.is_none() && opts.choose_rest {
        // The parts found on the frame clearest of contact: the choice
        // `assemble_setup` makes for the embedding (the topology's
        // positions first, then every sequence's frames), so that a
        // hand on the hip in frame 0 is not one rigid part with the hip.
        let mut all: Vec<&[[f64; 3]]> = vec![mesh.positions()];
        all.extend_from_slice(&frames);
        if let Some(c) = choose_rest_frame(mesh, &all, rule)
            && c.frame > 0
        {
            auto.rest_frame = Some(c.frame - 1);
            why = Some(c.why);
        }
    }
    let mut rig = auto_rig(mesh, &frames, &auto)?;
    if let (Some(f), Some(why)) = (auto.rest_frame, why) {
        rig.notes
            .push(format!("parts found on frame {f} of the sequences ({why})"));
    }
    Ok((rig, mesh.vertex_count()))
}

/// A refusal of the automatic rig's own landmarks. They are not the
/// user's, and their file goes with everything else this call wrote, so
/// the message says that the automatic rig failed its check and what to
/// do instead, not "`InitOptions::landmarks` FILE: ..., landmarks of
/// another mesh?" (a crane draw named the removed `auto.landmarks.json`).
fn automatic_refused(e: InitError) -> JobError {
    match e {
        InitError::Read { option, source } if option.starts_with("`InitOptions::landmarks`") => {
            let why = source.to_string();
            let why = why
                .split("; landmarks of another mesh")
                .next()
                .unwrap_or(&why);
            JobError::Usage(format!(
                "the automatic rig failed its own check ({why}); nothing was written: give the landmarks by hand (`InitOptions::landmarks`), or draw the automatic rig again (`SURFMOTION_AUTORIG=salt=N`, N = 1, 2, ...)"
            ))
        }
        e => e.into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A topology with a vertex in no triangle is written with a note
    /// naming it (the deformation carries it), at any place in the file.
    #[test]
    fn a_vertex_in_no_triangle_is_noted_at_init() {
        let cap = crate::synth::shapes::capsule_mesh(0.15, 1.4, 12, 6);
        for stray in [0usize, cap.vertex_count()] {
            let tmp = tempfile::tempdir().unwrap();
            let mut p = cap.positions().to_vec();
            p.insert(stray, [0.0, 0.2, 0.0]);
            let tris = cap
                .triangles()
                .iter()
                .map(|t| t.map(|v| v + u32::from(v as usize >= stray)))
                .collect();
            let mesh = crate::mesh::Mesh::new(p, tris).unwrap();
            let obj = tmp.path().join("body.obj");
            crate::mesh::io::obj::write_obj(&mesh, None, &obj).unwrap();
            let opts = InitOptions {
                mesh: obj,
                ..InitOptions::default()
            };
            let setup = InitSetup {
                no_rig: true,
                ..InitSetup::default()
            };
            let r = init_database_with(&tmp.path().join("db"), &opts, &setup).unwrap();
            let want =
                format!("1 vertices of the topology are in no triangle (first: vertex {stray})");
            assert!(r.notes.iter().any(|n| n.contains(&want)), "{:?}", r.notes);
            // Without the stray vertex, no such warning.
            crate::mesh::io::obj::write_obj(&cap, None, &tmp.path().join("whole.obj")).unwrap();
            let opts = InitOptions {
                mesh: tmp.path().join("whole.obj"),
                ..InitOptions::default()
            };
            let r = init_database_with(&tmp.path().join("db2"), &opts, &setup).unwrap();
            assert!(
                !r.notes.iter().any(|n| n.contains("no triangle")),
                "{:?}",
                r.notes
            );
        }
    }

    #[test]
    fn a_refused_automatic_rig_names_no_landmark_file() {
        let inner: Box<dyn std::error::Error + Send + Sync> = "landmark l_knee: 23% of the groin-chin distance on the right side of the body's mid-plane; landmarks of another mesh or character? (a file made for this mesh may record its \"vertex_count\")".into();
        let e = InitError::Read {
            option: "`InitOptions::landmarks` /db/auto.landmarks.json".into(),
            source: inner,
        };
        let m = automatic_refused(e).to_string();
        assert!(
            m.starts_with("the automatic rig failed its own check (landmark l_knee: 23%"),
            "{m}"
        );
        assert!(
            !m.contains("auto.landmarks.json") && !m.contains("another mesh"),
            "{m}"
        );
        assert!(
            m.contains("`InitOptions::landmarks`") && m.contains("salt=N"),
            "{m}"
        );
        // Any other refusal passes through as it was.
        let other = automatic_refused(InitError::Option(
            "`InitOptions::up` q: expected y, z or auto".into(),
        ));
        assert_eq!(
            other.to_string(),
            "`InitOptions::up` q: expected y, z or auto"
        );
    }
}
