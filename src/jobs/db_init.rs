//! `db init` as a job: a character's manifest (`character.toml`) written
//! from its files, every file read and checked first
//! ([`crate::db::init::assemble`]), nothing written on a refusal; with
//! landmarks, the rig embedded once and a setup report written beside the
//! manifest (`setup.json`): the rest frame chosen and why, the contacts
//! found, the parts' rigidity over the sequences, the rig's notes and
//! self-check.

use super::JobError;
use super::outputs::check_output_folder;
use crate::db::init::{InitOptions, RestFrame, assemble_setup};
use crate::db::{MANIFEST, Manifest};
use crate::embed::contact::{Contact, FrameContacts};
use crate::embed::parts::Part;
use crate::embed::rigidity::{PartRigidity, RigidityOptions, part_rigidity};
use crate::embed::{EmbedCheck, Embedding};
use crate::util::fsutil::write_atomic;
use std::path::{Path, PathBuf};

/// The setup report's file name in the database folder.
pub const SETUP: &str = "setup.json";

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
    /// Contacts on the topology's frame (the parts named by the rig).
    pub topology_contacts: Vec<ContactReport>,
    /// Contacts on the rest frame chosen (empty when it is clear).
    pub rest_contacts: Vec<ContactReport>,
    /// Each part's rigidity over the sequences' frames, with the regions
    /// that follow another part.
    pub rigidity: Vec<PartRigidity>,
    /// The rig's notes (what was assumed while embedding).
    pub rig_notes: Vec<String>,
    /// The rig's self-check.
    pub check: EmbedCheck,
    /// Where the report was written.
    pub path: PathBuf,
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
    let mut notes = Vec::new();
    let (manifest, rest) = assemble_setup(dir, opts, &mut notes)?;
    manifest.save(dir)?;
    let setup = if manifest.rig.landmarks.is_some() {
        Some(write_setup(dir, &manifest, rest.as_ref(), setup)?)
    } else {
        None
    };
    Ok(InitReport {
        manifest,
        path: dir.join(MANIFEST),
        notes,
        setup,
    })
}

/// The rig embedded as the database will embed it, its report written.
fn write_setup(
    dir: &Path,
    m: &Manifest,
    rest: Option<&RestFrame>,
    o: &InitSetup,
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
        topology_contacts,
        rest_contacts,
        rigidity,
        rig_notes: rig.notes.clone(),
        check,
        path: dir.join(SETUP),
        png,
    };
    let text = serde_json::to_string_pretty(&report).map_err(|e| JobError::Usage(e.to_string()))?;
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
