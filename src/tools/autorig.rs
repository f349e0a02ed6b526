//! The evaluation of the automatic rig ([`crate::embed::auto`], issue 41)
//! that `cargo run --release --example autorig_eval -- [DATA]
//! [real|synth|bodies|headless|all|held-parts|facing|orders|contact|joints|spread]` runs
//! (DATA defaults to `../shared/data`; the fixtures are read from
//! `tests/fixtures`, relative to the working folder): [`evaluate_autorig`]
//! returns its tables ([`AutorigReport`]'s `Display`, the example's
//! standard output) and the details (`AutorigReport::details`, its
//! standard error); a setting that cannot run is an [`AutorigEvalError`].
//!
//! - real captures (samba, crane): the embedding from the automatic
//!   landmarks (the parts found on the rest frame `db init` chooses)
//!   against the embedding from the hand-made fixtures'
//!   landmarks (`tests/fixtures/*.landmarks.json`): mean joint distance over
//!   the 19 joints in % of the height, part labels agreeing, time; and
//!   samba re-ordered to start with both hands on the hips (frame 130)
//!   against the clear order; `contact [FRAMES]`: samba re-ordered to
//!   start at each of FRAMES (default 130 and 155, forearms on the belly),
//!   plain and mirrored, against the clear order (the rest frame chosen
//!   and the rig embedded on it as `db init` does);
//! - synthetic databases (the procedural humanoid in two shapes, driven by
//!   two motion sets with `synth::database::drive`): the automatic rig's
//!   joints read off every frame (its regressors) against the skeleton that
//!   drove the frame, mean over joints and frames in % of the height, and
//!   its part labels against the generating rig's;
//! - `headless` ([`crate::tools::autorig_headless`], run by the example
//!   itself): the bodies whole and cut at the neck, the trunk's depth
//!   below the top and whether the rig has a head;
//! - `facing`: the real captures turned about the vertical and mirrored,
//!   the automatic facing, chin and head joint against the landmark rig's
//!   moved alike;
//! - `joints`: per joint against the landmark rig, as numbered and with
//!   the vertices renumbered, and samba on rest frames 2 and 4;
//! - `spread [SALTS] [renumbered]`: the same against the decomposition's
//!   pseudo-random draws (`DecomposeOptions::salt` 0..SALTS, default 5;
//!   with `renumbered` each salt also on the vertices renumbered by a
//!   fixed shuffle, another draw of the vertex order): how far the
//!   joints move from draw to draw.

use crate::embed::EmbedError;
use crate::embed::Embedding;
use crate::embed::auto::options::AutoOptions;
use crate::embed::auto::rig::auto_rig;
use crate::embed::landmarks::{LandmarkError, Landmarks};
use crate::mesh::io::{LoadOptions, load_sequence};
use crate::mesh::{Mesh, TopologyError};
use crate::pose::retarget::ClipPoses;
use crate::rig::Canonical;
use glam::DVec3;
use std::fmt::{self, Write as _};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Why the evaluation could not run.
#[derive(Debug, thiserror::Error)]
pub enum AutorigEvalError {
    /// The arguments name no evaluation.
    #[error(
        "{0}: expected [DATA] [real|synth|bodies|headless|all|held-parts|facing|orders|contact [FRAMES]|joints|spread [SALTS] [renumbered]]"
    )]
    Usage(String),
    /// `SURFMOTION_AUTORIG` cannot be read.
    #[error("SURFMOTION_AUTORIG: {0}")]
    Options(String),
    /// A fixture's landmark file could not be read.
    #[error(transparent)]
    Landmarks(#[from] LandmarkError),
    /// A reference rig (the fixture's, the synthetic body's) could not be
    /// embedded.
    #[error("the reference rig: {0}")]
    Embed(#[from] EmbedError),
    /// A re-numbered mesh could not be made.
    #[error(transparent)]
    Topology(#[from] TopologyError),
}

/// Which tables to make ([`AutorigMode::parse`] reads the example's
/// arguments).
#[derive(Debug, Clone, PartialEq)]
pub enum AutorigMode {
    /// The real captures against their landmark rigs.
    Real,
    /// The synthetic databases against the skeletons that drove them.
    Synth,
    /// The same on samba's frame 0, the SMPL template and MakeHuman's body.
    Bodies,
    /// [`AutorigMode::Real`], then [`AutorigMode::Synth`].
    All,
    /// Samba's rest frames 2 and 4 and their pose samples.
    HeldParts,
    /// The facing on the captures turned and mirrored.
    Facing,
    /// Per joint, as numbered and renumbered.
    Joints,
    /// The decomposition's draws: `salts` salts, each also renumbered.
    Spread {
        /// Salts 0..salts.
        salts: u32,
        /// Each salt also on the vertices renumbered.
        renumbered: bool,
    },
    /// Samba's frames reversed and shuffled.
    Orders,
    /// Samba started at each of these frames.
    Contact(Vec<usize>),
}

impl AutorigMode {
    /// The data folder and the mode from the example's arguments (without
    /// the program's name): `[DATA] [MODE [ARGS]]`; as before this module
    /// took them, `spread`'s salts default to 5 and `contact`'s frames to
    /// 130 and 155, and arguments that do not parse are skipped.
    pub fn parse(args: &[String]) -> Result<(PathBuf, AutorigMode), AutorigEvalError> {
        let data = PathBuf::from(args.first().map_or("../shared/data", String::as_str));
        let rest = args.get(2..).unwrap_or(&[]);
        let mode = match args.get(1).map_or("all", String::as_str) {
            "real" => AutorigMode::Real,
            "synth" => AutorigMode::Synth,
            "bodies" => AutorigMode::Bodies,
            "all" => AutorigMode::All,
            "held-parts" => AutorigMode::HeldParts,
            "facing" => AutorigMode::Facing,
            "joints" => AutorigMode::Joints,
            "orders" => AutorigMode::Orders,
            "spread" => AutorigMode::Spread {
                salts: rest.first().and_then(|a| a.parse().ok()).unwrap_or(5),
                renumbered: rest.get(1).is_some_and(|a| a == "renumbered"),
            },
            "contact" => {
                let starts: Vec<usize> = rest.iter().filter_map(|a| a.parse().ok()).collect();
                AutorigMode::Contact(if starts.is_empty() {
                    vec![130, 155]
                } else {
                    starts
                })
            }
            other => {
                return Err(AutorigEvalError::Usage(format!(
                    "unknown evaluation {other:?}"
                )));
            }
        };
        Ok((data, mode))
    }
}

/// The evaluation's output: the tables (Markdown rows; its `Display`)
/// and the details (per-joint distances, notes, rest frames).
#[derive(Debug, Clone, Default)]
pub struct AutorigReport {
    /// The tables, as the example prints them on standard output.
    pub tables: String,
    /// The details, as the example prints them on standard error.
    pub details: String,
}

impl fmt::Display for AutorigReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.tables)
    }
}

/// A line of the tables.
macro_rules! say {
    ($w:expr, $($t:tt)*) => {{
        let _ = writeln!($w.tables, $($t)*);
    }};
}

/// A line of the details (`note!(w)`: an empty one).
macro_rules! note {
    ($w:expr) => {{
        $w.details.push('\n');
    }};
    ($w:expr, $($t:tt)*) => {{
        let _ = writeln!($w.details, $($t)*);
    }};
}

/// Part of a line of the details.
macro_rules! note_part {
    ($w:expr, $($t:tt)*) => {{
        let _ = write!($w.details, $($t)*);
    }};
}

/// Runs the evaluation `mode` on the data folder `data` (the captures
/// under `4d/`, the CMU clips under `mocap/`) with `db init`'s rules for
/// the automatic rig (`SURFMOTION_AUTORIG` applied).
pub fn evaluate_autorig(
    data: &Path,
    mode: &AutorigMode,
) -> Result<AutorigReport, AutorigEvalError> {
    crate::embed::auto::options::automatic_setup(&AutoOptions::default())
        .map_err(AutorigEvalError::Options)?;
    let mut w = AutorigReport::default();
    match mode {
        AutorigMode::Real => real(data, &mut w)?,
        AutorigMode::Synth => synth(data, &mut w)?,
        AutorigMode::Bodies => bodies(data, &mut w)?,
        AutorigMode::All => {
            real(data, &mut w)?;
            synth(data, &mut w)?;
        }
        AutorigMode::HeldParts => held_parts(data, &mut w)?,
        AutorigMode::Facing => facing(data, &mut w)?,
        AutorigMode::Joints => joints(data, &mut w)?,
        AutorigMode::Spread { salts, renumbered } => spread(data, *salts, *renumbered, &mut w)?,
        AutorigMode::Orders => orders(data, &mut w)?,
        AutorigMode::Contact(starts) => contact(data, starts, &mut w),
    }
    Ok(w)
}

/// The process's user + system CPU seconds so far (every thread), from
/// `/proc/self/stat` (0 where it cannot be read).
fn cpu_secs() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let after = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<f64> = after
        .split_whitespace()
        .map(|x| x.parse().unwrap_or(0.0))
        .collect();
    // Fields 14 and 15 of the line (utime, stime), in clock ticks of 100 Hz.
    f.get(11)
        .zip(f.get(12))
        .map_or(0.0, |(u, s)| (u + s) / 100.0)
}

fn height(rig: &Embedding) -> f64 {
    rig.height()
}

fn joint_error(a: &[[f64; 3]; 19], b: &[[f64; 3]; 19]) -> (f64, usize, f64) {
    let mut worst = (0, 0.0);
    let mut s = 0.0;
    for j in 0..19 {
        let d = DVec3::from_array(a[j]).distance(DVec3::from_array(b[j]));
        s += d;
        if d > worst.1 {
            worst = (j, d);
        }
    }
    (s / 19.0, worst.0, worst.1)
}

pub(crate) fn agree(a: &[u8], b: &[u8]) -> f64 {
    a.iter().zip(b).filter(|(x, y)| x == y).count() as f64 / a.len() as f64
}

/// A real capture (samba, crane) with its hand-made landmarks and their
/// rig: what every per-capture table of this evaluation compares against.
struct Capture<'a> {
    name: &'a str,
    mesh: &'a Mesh,
    frames: &'a [&'a [[f64; 3]]],
    landmarks: &'a Landmarks,
    truth: &'a Embedding,
}

/// Calls `row` on each real capture, loaded with its fixture's landmarks
/// and their rig; a capture that does not load prints `| NAME | not run:
/// why |` (the table's first column) and is skipped.
fn for_each_capture(
    data: &Path,
    w: &mut AutorigReport,
    mut row: impl FnMut(&mut AutorigReport, &Capture),
) -> Result<(), AutorigEvalError> {
    for name in ["samba", "crane"] {
        let pc2 = data.join(format!("4d/{name}/{name}.pc2"));
        let seq = match load_sequence(&pc2.to_string_lossy(), &LoadOptions::default()) {
            Ok(s) => s,
            Err(e) => {
                say!(w, "| {name} | not run: {e} |");
                continue;
            }
        };
        let frames: Vec<&[[f64; 3]]> = (0..seq.frame_count()).map(|f| seq.frame(f)).collect();
        let fixture = PathBuf::from(format!("tests/fixtures/{name}.landmarks.json"));
        let landmarks = Landmarks::load(&fixture, seq.mesh().vertex_count())?;
        let truth = Embedding::new(seq.mesh(), &landmarks, None)?;
        row(
            w,
            &Capture {
                name,
                mesh: seq.mesh(),
                frames: &frames,
                landmarks: &landmarks,
                truth: &truth,
            },
        );
    }
    Ok(())
}

fn real(data: &Path, w: &mut AutorigReport) -> Result<(), AutorigEvalError> {
    say!(
        w,
        "| capture | joints vs landmark rig (% height) | worst joint | parts agree | confidence | time (s) |"
    );
    say!(w, "|---|---|---|---|---|---|");
    for_each_capture(data, w, |w, c| {
        let (name, mesh, frames, truth) = (c.name, c.mesh, c.frames, c.truth);
        let t = Instant::now();
        let (rest, why) = rest_as_db_init(mesh, frames);
        note!(w, "  {name}: rest frame {rest:?}: {why}");
        let auto = match rig_as_db_init(mesh, frames) {
            Ok(a) => a,
            Err(e) => {
                say!(w, "| {name} | refused: {e} |");
                return;
            }
        };
        let secs = t.elapsed().as_secs_f64();
        match embed_as_db_init(mesh, frames, auto.rest_frame, &auto.landmarks) {
            Some(mine) => {
                let (e, wj, wd) = joint_error(mine.joints(), truth.joints());
                let h = height(truth);
                say!(
                    w,
                    "| {name} | {:.2} | {} {:.1} | {:.1}% | {:.2} | {secs:.1} |",
                    100.0 * e / h,
                    Canonical::ALL[wj].name(),
                    100.0 * wd / h,
                    100.0 * agree(mine.labels(), truth.labels()),
                    auto.confidence
                );
                for j in Canonical::ALL {
                    let d = DVec3::from_array(mine.joints()[j.index()])
                        .distance(DVec3::from_array(truth.joints()[j.index()]));
                    note_part!(w, "{} {:.1}  ", j.name(), 100.0 * d / h);
                }
                note!(w);
                knees_per_frame(name, frames, &mine, truth, w);
            }
            None => say!(w, "| {name} | embedding refused |"),
        }
        arm_offsets(name, mesh, c.landmarks, &auto, w);
        for n in &auto.notes {
            note!(w, "  {name}: {n}");
        }
        note!(w, "  {name}: {}", auto.summary());
        note!(
            w,
            "  {name}: facing {:.1}° from the landmark rig's",
            facing_deg(&auto, truth.facing())
        );
        if name == "samba" {
            contact_first(mesh, frames, 130, false, w);
        }
    })
}

/// The angle (degrees) between the automatic rig's facing and `want`.
fn facing_deg(auto: &crate::embed::auto::report::AutoRig, want: [f64; 3]) -> f64 {
    let (a, b) = (DVec3::from_array(auto.facing), DVec3::from_array(want));
    a.normalize_or_zero()
        .dot(b.normalize_or_zero())
        .clamp(-1.0, 1.0)
        .acos()
        .to_degrees()
}

/// The automatic rig's facing on the real captures turned about +Y by
/// 0°, 30°, 90°, 180°, 270°, each also mirrored (x → −x): the angle to
/// the landmark rig's facing turned and mirrored alike, and the chin's
/// and the head joint's distance to the landmark rig's (% of the height;
/// the rig embedded on the topology, the rest `db init` keeps for them).
fn facing(data: &Path, w: &mut AutorigReport) -> Result<(), AutorigEvalError> {
    say!(
        w,
        "| capture | turn | mirrored | facing off (°) | chin off (% h) | head joint off (% h) |"
    );
    say!(w, "|---|---|---|---|---|---|");
    for_each_capture(data, w, |w, c| {
        let (name, lm, truth) = (c.name, c.landmarks, c.truth);
        let h = truth.height();
        for yaw in [0.0_f64, 30.0, 90.0, 180.0, 270.0] {
            for mirror in [false, true] {
                let m = glam::DMat3::from_diagonal(DVec3::new(
                    if mirror { -1.0 } else { 1.0 },
                    1.0,
                    1.0,
                )) * glam::DMat3::from_rotation_y(yaw.to_radians());
                let place = |f: &[[f64; 3]]| -> Vec<[f64; 3]> {
                    f.iter()
                        .map(|q| (m * DVec3::from_array(*q)).to_array())
                        .collect()
                };
                let mut tris = c.mesh.triangles().to_vec();
                if mirror {
                    tris.iter_mut().for_each(|t| t.swap(1, 2));
                }
                let Ok(mesh) = Mesh::new(place(c.mesh.positions()), tris) else {
                    continue;
                };
                let own: Vec<Vec<[f64; 3]>> = c.frames.iter().map(|f| place(f)).collect();
                let frames: Vec<&[[f64; 3]]> = own.iter().map(Vec::as_slice).collect();
                let Ok(auto) = auto_rig(&mesh, &frames, &db_init_options(None)) else {
                    say!(w, "| {name} | {yaw} | {mirror} | refused |");
                    continue;
                };
                let want = (m * DVec3::from_array(truth.facing())).to_array();
                let joint =
                    |e: &Embedding, c: Canonical| m * DVec3::from_array(e.joints()[c.index()]);
                let chin = |l: &Landmarks, p: &[[f64; 3]]| {
                    l.point(crate::embed::landmarks::Landmark::Chin, p)
                        .map(DVec3::from_array)
                };
                let chin_off = match (
                    chin(&auto.landmarks, mesh.positions()),
                    chin(lm, c.mesh.positions()),
                ) {
                    (Some(a), Some(b)) => 100.0 * a.distance(m * b) / h,
                    _ => f64::NAN,
                };
                let head_off = Embedding::new(&mesh, &auto.landmarks, None).map_or(f64::NAN, |e| {
                    100.0
                        * DVec3::from_array(e.joints()[Canonical::Head.index()])
                            .distance(joint(truth, Canonical::Head))
                        / h
                });
                say!(
                    w,
                    "| {name} | {yaw:.0}° | {mirror} | {:.1} | {chin_off:.2} | {head_off:.2} |",
                    facing_deg(&auto, want)
                );
            }
        }
    })
}

/// Issue 41's held-rule question: samba rigged on rest frame `r` with the
/// decomposition fitted to the pose-quantile sample seeded by frame `x`
/// (`r`, `x` in 2 and 4, frames of one still start), the frames given in
/// the sample's order (the rest frame first): the left elbow and right
/// knee against the landmark rig (% of the height), the parts, and the
/// same rest and sample with the vertices re-ordered (the decomposition's
/// k-means seeding follows the vertex order).
fn held_parts(data: &Path, w: &mut AutorigReport) -> Result<(), AutorigEvalError> {
    use crate::embed::auto::options::FrameSample;
    use crate::embed::pose_order::{descriptor, quantiles};
    let pc2 = data.join("4d/samba/samba.pc2");
    let Ok(seq) = load_sequence(&pc2.to_string_lossy(), &LoadOptions::default()) else {
        say!(w, "samba: not run");
        return Ok(());
    };
    let mesh = seq.mesh().clone();
    let frames: Vec<&[[f64; 3]]> = (0..seq.frame_count()).map(|f| seq.frame(f)).collect();
    let lm = Landmarks::load(
        &PathBuf::from("tests/fixtures/samba.landmarks.json"),
        mesh.vertex_count(),
    )?;
    let truth = Embedding::new(&mesh, &lm, None)?;
    let h = truth.height();
    let descs: Vec<Vec<f64>> = frames.iter().map(|f| descriptor(f)).collect();
    let sample = |x: usize| quantiles(&descs, &descs[x], 40);
    say!(
        w,
        "| rest | sample seeded by | vertices | l_elbow % | r_knee % | joints mean % | parts | sample shared |"
    );
    say!(w, "|---|---|---|---|---|---|---|---|");
    let (s2, s4) = (sample(2), sample(4));
    let shared = s2.iter().filter(|f| s4.contains(f)).count();
    for (r, x) in [(2, 2), (4, 4), (4, 2), (2, 4)] {
        for shuffle in [false, true] {
            let s = sample(x);
            let mut f: Vec<&[[f64; 3]]> = vec![frames[r]];
            f.extend(s.iter().skip(1).map(|&k| frames[k]));
            let (m, own) = if shuffle {
                let order = shuffled(mesh.vertex_count());
                let mut new_of = vec![0u32; order.len()];
                for (k, &o) in order.iter().enumerate() {
                    new_of[o] = k as u32;
                }
                let tris: Vec<[u32; 3]> = mesh
                    .triangles()
                    .iter()
                    .map(|t| t.map(|i| new_of[i as usize]))
                    .collect();
                let pos =
                    |q: &[[f64; 3]]| -> Vec<[f64; 3]> { order.iter().map(|&o| q[o]).collect() };
                let own: Vec<Vec<[f64; 3]>> = f.iter().map(|q| pos(q)).collect();
                (Mesh::new(pos(mesh.positions()), tris)?, own)
            } else {
                (mesh.clone(), f.iter().map(|q| q.to_vec()).collect())
            };
            let fr: Vec<&[[f64; 3]]> = own.iter().map(Vec::as_slice).collect();
            let opts = AutoOptions {
                rest_frame: Some(0),
                frames: FrameSample::PoseQuantiles,
                max_frames: fr.len(),
                ..db_init_options(None)
            };
            let Ok(auto) = auto_rig(&m, &fr, &opts) else {
                say!(w, "| {r} | {x} | refused |");
                continue;
            };
            let Ok(e) = Embedding::new_on_frame(&m, fr[0], &auto.landmarks, None) else {
                say!(w, "| {r} | {x} | embedding refused |");
                continue;
            };
            let d = |c: Canonical| {
                100.0
                    * DVec3::from_array(e.joints()[c.index()])
                        .distance(DVec3::from_array(truth.joints()[c.index()]))
                    / h
            };
            let (mean, _, _) = joint_error(e.joints(), truth.joints());
            say!(
                w,
                "| {r} | {x} | {} | {:.1} | {:.1} | {:.2} | {} | {shared} of 40 |",
                if shuffle { "re-ordered" } else { "as captured" },
                d(Canonical::LElbow),
                d(Canonical::RKnee),
                100.0 * mean / h,
                auto.parts
            );
        }
    }
    Ok(())
}

/// The knees of `mine` against `truth`'s in every frame (each rig's
/// joints read off the frame by its regressors), in % of the height:
/// mean, the worst and its frame, and the five worst frames.
fn knees_per_frame(
    name: &str,
    frames: &[&[[f64; 3]]],
    mine: &Embedding,
    truth: &Embedding,
    w: &mut AutorigReport,
) {
    let h = truth.height();
    for knee in [Canonical::LKnee, Canonical::RKnee] {
        let k = knee.index();
        let mut d: Vec<(f64, usize)> = frames
            .iter()
            .enumerate()
            .map(|(f, x)| {
                let (a, b) = (mine.frame_joints(x), truth.frame_joints(x));
                (100.0 * a[k].distance(b[k]) / h, f)
            })
            .collect();
        let mean = d.iter().map(|x| x.0).sum::<f64>() / d.len().max(1) as f64;
        d.sort_by(|a, b| b.0.total_cmp(&a.0));
        let worst: Vec<String> = d
            .iter()
            .take(5)
            .map(|(x, f)| format!("{f}: {x:.1}"))
            .collect();
        note!(
            w,
            "  {name} {} per frame: mean {mean:.2}%, worst {}",
            knee.name(),
            worst.join(", ")
        );
    }
}

/// The arm landmarks (elbows, wrists) of the automatic rig against the
/// fixture's: the distance, and its part along the fixture's forearm
/// (elbow to wrist; positive towards the hand), in % of the height.
fn arm_offsets(
    name: &str,
    mesh: &Mesh,
    lm: &Landmarks,
    auto: &crate::embed::auto::report::AutoRig,
    w: &mut AutorigReport,
) {
    use crate::embed::landmarks::Landmark as L;
    let p = mesh.positions();
    let h = {
        let ys = p.iter().map(|q| q[1]);
        ys.clone().fold(f64::MIN, f64::max) - ys.fold(f64::MAX, f64::min)
    };
    let get = |l: &Landmarks, m: L| l.point(m, p).map(DVec3::from_array);
    for (e, wrist, side) in [(L::LElbow, L::LWrist, "l"), (L::RElbow, L::RWrist, "r")] {
        let (Some(fe), Some(fw), Some(ae), Some(aw)) = (
            get(lm, e),
            get(lm, wrist),
            get(&auto.landmarks, e),
            get(&auto.landmarks, wrist),
        ) else {
            continue;
        };
        let axis = (fw - fe).normalize_or_zero();
        note!(
            w,
            "  {name} {side}: elbow {:.1}% off ({:+.1}% along the forearm), wrist {:.1}% off ({:+.1}%); forearm {:.1}% vs {:.1}%",
            100.0 * ae.distance(fe) / h,
            100.0 * (ae - fe).dot(axis) / h,
            100.0 * aw.distance(fw) / h,
            100.0 * (aw - fw).dot(axis) / h,
            100.0 * fe.distance(fw) / h,
            100.0 * ae.distance(aw) / h,
        );
    }
}

/// The automatic rig as `db init` runs it (its rules, `automatic_setup`,
/// `SURFMOTION_AUTORIG` applied): the parts found on the rest frame chosen
/// over the topology's positions and every frame.
fn rig_as_db_init(
    mesh: &Mesh,
    frames: &[&[[f64; 3]]],
) -> Result<crate::embed::auto::report::AutoRig, crate::embed::auto::options::AutoError> {
    let (rest, _) = rest_as_db_init(mesh, frames);
    auto_rig(mesh, frames, &db_init_options(rest))
}

/// `db init`'s rules for the automatic rig (`automatic_setup`, with
/// `SURFMOTION_AUTORIG` when set).
fn db_init_rules() -> (crate::embed::rest::RestOptions, AutoOptions) {
    use crate::embed::auto::options::automatic_setup;
    // Checked once before any table (`evaluate_autorig`).
    automatic_setup(&AutoOptions::default()).unwrap_or_default()
}

/// `db init`'s automatic rig options with the rest frame `rest`.
pub(crate) fn db_init_options(rest: Option<usize>) -> AutoOptions {
    AutoOptions {
        rest_frame: rest,
        ..db_init_rules().1
    }
}

/// The rest frame `db init` chooses over the topology's positions and
/// `frames` (an index into `frames`; `None`: the topology's), and why.
pub(crate) fn rest_as_db_init(mesh: &Mesh, frames: &[&[[f64; 3]]]) -> (Option<usize>, String) {
    use crate::embed::rest::choose_rest_frame;
    let mut all = vec![mesh.positions()];
    all.extend_from_slice(frames);
    match choose_rest_frame(mesh, &all, &db_init_rules().0) {
        Some(c) => ((c.frame > 0).then(|| c.frame - 1), c.why),
        None => (None, String::new()),
    }
}

/// The embedding `db init` makes from automatic landmarks: on the rest
/// frame it chose (`[rig] rest`), its joints carried to the topology.
pub(crate) fn embed_as_db_init(
    mesh: &Mesh,
    frames: &[&[[f64; 3]]],
    rest: Option<usize>,
    lm: &Landmarks,
) -> Option<Embedding> {
    embed_or_why(mesh, frames, rest, lm).ok()
}

/// [`embed_as_db_init`], `Err` with the embedding's refusal (which
/// landmark, why).
fn embed_or_why(
    mesh: &Mesh,
    frames: &[&[[f64; 3]]],
    rest: Option<usize>,
    lm: &Landmarks,
) -> Result<Embedding, String> {
    match rest {
        None => Embedding::new(mesh, lm, None),
        Some(r) => Embedding::new_on_frame(mesh, frames[r], lm, None),
    }
    .map_err(|e| format!("embedding refused: {e}"))
}

/// Issue 41's contact figure: the capture re-ordered so that frame
/// `first` (samba 130: both hands on the hips; 155: forearms on the belly)
/// comes first, rigged automatically and embedded as `db init` does (on
/// the rest frame it chooses), against the rig from the clear order
/// carried to that frame: mean and worst joint distance (% of the height),
/// parts agreeing, and the rest frame chosen (as a frame of the clear
/// order). `mirror` mirrors both orders' frames (x → −x) first.
fn contact_first(
    mesh: &Mesh,
    frames: &[&[[f64; 3]]],
    first: usize,
    mirror: bool,
    w: &mut AutorigReport,
) {
    let nf = frames.len();
    let order: Vec<usize> = (0..nf).map(|k| (first + k) % nf).collect();
    let what = format!(
        "samba{}, frame {first} first",
        if mirror { " mirrored" } else { "" }
    );
    reordered(mesh, frames, &order, &what, mirror, w);
}

/// [`contact_first`] for any `order` of the frames (`order[k]`: the
/// original frame given k-th; its first the topology), named `what`.
fn reordered(
    mesh: &Mesh,
    frames: &[&[[f64; 3]]],
    order: &[usize],
    what: &str,
    mirror: bool,
    w: &mut AutorigReport,
) {
    let first = order[0];
    let flip = |f: &[[f64; 3]]| -> Vec<[f64; 3]> {
        f.iter()
            .map(|q| if mirror { [-q[0], q[1], q[2]] } else { *q })
            .collect()
    };
    let own: Vec<Vec<[f64; 3]>> = frames.iter().map(|f| flip(f)).collect();
    let frames: Vec<&[[f64; 3]]> = own.iter().map(Vec::as_slice).collect();
    let mut tris = mesh.triangles().to_vec();
    if mirror {
        tris.iter_mut().for_each(|t| t.swap(1, 2));
    }
    let (Ok(mesh), Ok(cmesh)) = (
        Mesh::new(flip(mesh.positions()), tris.clone()),
        Mesh::new(frames[first].to_vec(), tris),
    ) else {
        return;
    };
    let moved: Vec<&[[f64; 3]]> = order.iter().map(|&k| frames[k]).collect();
    let (rest_a, _) = rest_as_db_init(&mesh, &frames);
    let (rest_b, why) = rest_as_db_init(&cmesh, &moved);
    let rig = |m: &Mesh, f: &[&[[f64; 3]]], r: Option<usize>| auto_rig(m, f, &db_init_options(r));
    let (Ok(clear), Ok(contact)) = (rig(&mesh, &frames, rest_a), rig(&cmesh, &moved, rest_b))
    else {
        say!(w, "| {what} | refused |");
        return;
    };
    let (Some(a), Some(b)) = (
        embed_as_db_init(&mesh, &frames, rest_a, &clear.landmarks),
        embed_as_db_init(&cmesh, &moved, rest_b, &contact.landmarks),
    ) else {
        say!(w, "| {what} | embedding refused |");
        return;
    };
    // As frames of the clear order (the topology: its first frame).
    let original = |r: Option<usize>| r.map_or(first, |r| order[r]);
    let clear_rest = rest_a.unwrap_or(0);
    // `a` is a clear-order rig (its joints on frame 0), `b` one whose
    // joints are on frame `first` (`b_first`) or on frame 0.
    let row3 = |w: &mut AutorigReport, case: &str, a: &Embedding, b: &Embedding, b_first: bool| {
        let carried = a.frame_joints(frames[first]);
        let other = if b_first {
            b.joints().map(DVec3::from_array)
        } else {
            b.frame_joints(frames[first])
        };
        let d: Vec<f64> = (0..19)
            .map(|j| carried[j].distance(other[j]) / a.height() * 100.0)
            .collect();
        let (wj, wd) = d
            .iter()
            .enumerate()
            .fold((0, 0.0f64), |w, (j, &x)| if x > w.1 { (j, x) } else { w });
        say!(
            w,
            "| {what}: {case} | {:.2} | {} {:.1} | {:.1}% | {:.2} | rest frame {} (clear order: {}) |",
            d.iter().sum::<f64>() / 19.0,
            Canonical::ALL[wj].name(),
            wd,
            100.0 * agree(a.labels(), b.labels()),
            contact.confidence,
            original(rest_b),
            clear_rest,
        );
    };
    let row =
        |w: &mut AutorigReport, case: &str, a: &Embedding, b: &Embedding| row3(w, case, a, b, true);
    row(w, "vs clear order", &a, &b);
    note!(w, "  {what}: {why}");
    // Where the distance comes from. (1) The landmarks as points on the
    // topology (the contact frame) carried back to the rest frame by its
    // nearest triangles (`Landmarks::moved`), as `db init` wrote them
    // before surface marks.
    let on_topo = Landmarks {
        marks: contact
            .landmarks
            .marks
            .keys()
            .filter_map(|&l| {
                let p = contact.landmarks.point(l, cmesh.positions())?;
                Some((l, crate::embed::landmarks::Mark::Point(p)))
            })
            .collect(),
    };
    match embed_as_db_init(&cmesh, &moved, rest_b, &on_topo) {
        Some(old) => row(w, "points carried through the contact frame", &a, &old),
        None => {
            say!(
                w,
                "| {what}: points carried through the contact frame | embedding refused |"
            )
        }
    }
    // (2) The clear order rigged and embedded on the contact order's rest
    // frame: what the rest frame alone changes.
    let r = original(rest_b);
    if let Ok(same) = rig(&mesh, &frames, Some(r))
        && let Some(s) = embed_as_db_init(&mesh, &frames, Some(r), &same.landmarks)
    {
        row3(
            w,
            "clear order on the same rest frame, vs clear order",
            &a,
            &s,
            false,
        );
        row(w, "vs clear order on the same rest frame", &s, &b);
    }
}

/// The frames of `frames` with a contact (issue 41's contact finder on
/// `mesh`'s surface distances).
fn contact_frames(mesh: &Mesh, frames: &[&[[f64; 3]]]) -> Vec<usize> {
    use crate::embed::contact::{ContactFinder, ContactOptions};
    let finder = ContactFinder::new(mesh, ContactOptions::default());
    (0..frames.len())
        .filter(|&f| !finder.find(frames[f]).contacts.is_empty())
        .collect()
}

/// `contact [FRAMES]`: the contact figure for samba started at each of
/// `FRAMES` (default 130 and 155), plain and mirrored.
fn contact(data: &Path, starts: &[usize], w: &mut AutorigReport) {
    let pc2 = data.join("4d/samba/samba.pc2");
    let Ok(seq) = load_sequence(&pc2.to_string_lossy(), &LoadOptions::default()) else {
        say!(w, "no samba at {}", pc2.display());
        return;
    };
    let mesh = seq.mesh().clone();
    let frames: Vec<&[[f64; 3]]> = (0..seq.frame_count()).map(|f| seq.frame(f)).collect();
    note!(
        w,
        "samba frames with a contact: {:?}",
        contact_frames(&mesh, &frames)
    );
    say!(
        w,
        "| case | joints (% height, mean) | worst joint | parts agree | confidence | rest |"
    );
    say!(w, "|---|---|---|---|---|---|");
    for &f in starts {
        for mirror in [false, true] {
            contact_first(&mesh, &frames, f, mirror, w);
        }
    }
}

/// The seed of the evaluation's renumbered and shuffled orders.
pub const EVAL_SEED: u64 = 0x2545_F491_4F6C_DD1D;

/// A fixed shuffle of `0..n` with [`EVAL_SEED`].
fn shuffled(n: usize) -> Vec<usize> {
    xorshift_order(n, EVAL_SEED)
}

/// A fixed shuffle of `0..n` (xorshift from `seed`; the same every run):
/// the orders the evaluation and the automatic-rig tests draw.
pub fn xorshift_order(n: usize, seed: u64) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    let mut x = seed;
    for i in (1..n).rev() {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        order.swap(i, (x % (i as u64 + 1)) as usize);
    }
    order
}

/// `orders`: samba's frames reversed and shuffled, plain and mirrored,
/// against the clear order (the rig must not depend on the order).
fn orders(data: &Path, w: &mut AutorigReport) -> Result<(), AutorigEvalError> {
    let pc2 = data.join("4d/samba/samba.pc2");
    let Ok(seq) = load_sequence(&pc2.to_string_lossy(), &LoadOptions::default()) else {
        say!(w, "no samba at {}", pc2.display());
        return Ok(());
    };
    let mesh = seq.mesh().clone();
    let frames: Vec<&[[f64; 3]]> = (0..seq.frame_count()).map(|f| seq.frame(f)).collect();
    let nf = frames.len();
    say!(
        w,
        "| case | joints (% height, mean) | worst joint | parts agree | confidence | rest |"
    );
    say!(w, "|---|---|---|---|---|---|");
    let reversed: Vec<usize> = (0..nf).rev().collect();
    for mirror in [false, true] {
        let m = if mirror { " mirrored" } else { "" };
        reordered(
            &mesh,
            &frames,
            &reversed,
            &format!("samba{m} reversed"),
            mirror,
            w,
        );
        reordered(
            &mesh,
            &frames,
            &shuffled(nf),
            &format!("samba{m} shuffled"),
            mirror,
            w,
        );
    }
    Ok(())
}

fn synth(data: &Path, w: &mut AutorigReport) -> Result<(), AutorigEvalError> {
    use crate::synth::humanoid::{HumanoidShape, humanoid_landmarks_with, humanoid_mesh_with};
    say!(
        w,
        "| body | motion | frames | joints vs truth (% height, mean over joints and frames) | parts agree | confidence | time (s) |"
    );
    say!(w, "|---|---|---|---|---|---|---|");
    let bodies = [
        ("humanoid A-pose 1.75 m", HumanoidShape::default()),
        (
            "humanoid T-pose 1.60 m, wide hips",
            HumanoidShape {
                arm_angle: 10.0,
                hip_width: 1.2,
                shoulder_width: 0.9,
                height: 1.6,
                ..Default::default()
            },
        ),
    ];
    let motions = synth_motions(data, w);
    for (bname, shape) in &bodies {
        let rest: Mesh = humanoid_mesh_with(0.02, shape);
        let lm = humanoid_landmarks_with(&rest, shape);
        let rig = Embedding::new(&rest, &lm, None)?;
        synth_rows(bname, &rest, &rig, &motions, w);
    }
    Ok(())
}

/// `bodies`: issue 41's synthetic figure on the bodies it names:
/// samba's frame 0, the SMPL template and MakeHuman's `body` group (its
/// unused vertices dropped), each rigged from its fixture's landmarks
/// (`tests/fixtures/{samba,smpl,makehuman}.landmarks.json`) and driven by
/// [`synth_motions`]; rows as [`synth`]'s.
fn bodies(data: &Path, w: &mut AutorigReport) -> Result<(), AutorigEvalError> {
    say!(
        w,
        "| body | motion | frames | joints vs truth (% height, mean over joints and frames) | parts agree | confidence | time (s) |"
    );
    say!(w, "|---|---|---|---|---|---|---|");
    let motions = synth_motions(data, w);
    for (bname, rest, rig) in body_meshes(data, w)? {
        synth_rows(bname, &rest, &rig, &motions, w);
    }
    Ok(())
}

/// Samba's frame 0, the SMPL template and MakeHuman's `body` group (its
/// unused vertices dropped), each with its rig from its fixture's
/// landmarks; a body that does not load prints `| NAME | not run: why |`.
pub(crate) fn body_meshes(
    data: &Path,
    w: &mut AutorigReport,
) -> Result<Vec<(&'static str, Mesh, Embedding)>, AutorigEvalError> {
    let mut out = Vec::new();
    for (bname, file, group, fixture) in [
        ("samba frame 0", "4d/samba/samba.obj", None, "samba"),
        (
            "SMPL template",
            "scans/smpl-template/human_man.obj",
            None,
            "smpl",
        ),
        (
            "MakeHuman body",
            "scans/makehuman/base.obj",
            Some("body"),
            "makehuman",
        ),
    ] {
        let spec = data.join(file);
        let seq = match load_sequence(&spec.to_string_lossy(), &LoadOptions::default()) {
            Ok(s) => s,
            Err(e) => {
                say!(w, "| {bname} | not run: {e} |");
                continue;
            }
        };
        let whole = match group {
            None => seq.frame_mesh(0),
            Some(g) => match seq.mesh().select_groups(&[g.to_string()]) {
                Some(m) => m,
                None => {
                    say!(w, "| {bname} | not run: no group {g} |");
                    continue;
                }
            },
        };
        let rest = used_vertices_only(&whole)?;
        let fixture = PathBuf::from(format!("tests/fixtures/{fixture}.landmarks.json"));
        let lm = Landmarks::load(&fixture, rest.vertex_count())?;
        let rig = Embedding::new(&rest, &lm, None)?;
        out.push((bname, rest, rig));
    }
    Ok(out)
}

/// `mesh` with only the vertices its triangles use, in their order (a
/// scan's helper meshes and MakeHuman's unused groups dropped).
pub fn used_vertices_only(mesh: &Mesh) -> Result<Mesh, TopologyError> {
    let mut used = vec![false; mesh.vertex_count()];
    mesh.triangles()
        .iter()
        .flatten()
        .for_each(|&v| used[v as usize] = true);
    let mut index = vec![u32::MAX; used.len()];
    let mut kept = Vec::new();
    for (v, _) in used.iter().enumerate().filter(|(_, u)| **u) {
        index[v] = kept.len() as u32;
        kept.push(mesh.positions()[v]);
    }
    let tris = mesh
        .triangles()
        .iter()
        .map(|t| t.map(|v| index[v as usize]))
        .collect();
    Mesh::new(kept, tris)
}

/// The synthetic databases' motions: the procedural gait turn (4 s) and
/// CMU 02_05 and 05_06 (150 frames each), at 30 frames a second.
pub(crate) fn synth_motions(data: &Path, w: &mut AutorigReport) -> Vec<(String, ClipPoses)> {
    use crate::drive::query::load_mocap;
    use crate::jobs::synth_db::SynthClip;
    let fps = 30.0;
    let mut motions: Vec<(String, ClipPoses)> = Vec::new();
    let walk = crate::synth::clips::gait_clip(crate::synth::clips::Gait::Turn, 4.0, fps);
    if let Ok(SynthClip::Poses { poses, .. }) = SynthClip::from_clip("turn", &walk) {
        motions.push(("gait turn (4 s)".into(), *poses));
    }
    for clip in ["02_05", "05_06"] {
        let p = [
            data.join(format!("mocap/cmu-amc/02/{clip}.amc")),
            data.join(format!("mocap/cmu-bvh-altered/{clip}.bvh")),
        ];
        let Some(path) = p.iter().find(|p| p.exists()) else {
            continue;
        };
        match load_mocap(path, &Default::default(), fps) {
            Ok(c) => {
                let mut poses = c.poses;
                let mut reference = c.reference;
                poses.truncate(150);
                reference.rotations = reference.rotations.iter().take(150).copied().collect();
                motions.push((format!("CMU {clip} (5 s)"), ClipPoses { poses, reference }));
            }
            Err(e) => note!(w, "{clip}: {e}"),
        }
    }
    motions
}

/// One row per motion: `rest` driven by each of `motions` through `rig`
/// (`synth::database::drive`, its secondary dynamics), rigged
/// automatically as `db init` rigs it, its joints read off every frame
/// against the skeleton that drove the frame, its parts against `rig`'s.
fn synth_rows(
    bname: &str,
    rest: &Mesh,
    rig: &Embedding,
    motions: &[(String, ClipPoses)],
    w: &mut AutorigReport,
) {
    use crate::synth::database::{Dynamics, drive};
    let h = rig.height();
    let fps = 30.0;
    for (mname, cp) in motions {
        let out = drive(
            rest,
            rig,
            &cp.poses,
            &cp.reference,
            fps,
            Dynamics::default(),
        );
        let n = rest.vertex_count();
        let frames: Vec<&[[f64; 3]]> = out.positions.chunks(n).collect();
        let t = Instant::now();
        let (rest_frame, why) = rest_as_db_init(rest, &frames);
        let auto = match auto_rig(rest, &frames, &db_init_options(rest_frame)) {
            Ok(a) => a,
            Err(e) => {
                say!(w, "| {bname} | {mname} | {} | refused: {e} |", frames.len());
                continue;
            }
        };
        let secs = t.elapsed().as_secs_f64();
        let mine =
            match embed_as_db_init(rest, &frames, rest_frame, &auto.landmarks).ok_or("refused") {
                Ok(m) => m,
                Err(e) => {
                    say!(
                        w,
                        "| {bname} | {mname} | {} | embedding refused: {e} |",
                        frames.len()
                    );
                    continue;
                }
            };
        let mut s = 0.0;
        let mut k = 0usize;
        for (f, pose) in frames.iter().zip(&out.poses) {
            let j = mine.frame_joints(f);
            for c in 0..19 {
                s += j[c].distance(pose[c]);
                k += 1;
            }
        }
        say!(
            w,
            "| {bname} | {mname} | {} | {:.2} | {:.1}% | {:.2} | {secs:.1} |",
            frames.len(),
            100.0 * s / k as f64 / h,
            100.0 * agree(mine.labels(), rig.labels()),
            auto.confidence
        );
        let (e, wj, wd) = joint_error(mine.joints(), rig.joints());
        note!(
            w,
            "  rest frame {rest_frame:?} ({why}); rest joints {:.2}%, worst {} {:.1}%; facing {:.1}° from the rig's; {}",
            100.0 * e / h,
            Canonical::ALL[wj].name(),
            100.0 * wd / h,
            facing_deg(&auto, rig.facing()),
            auto.summary()
        );
    }
}

/// One automatic rig scored against the landmark rig: each joint's
/// distance (% of the height, [`Canonical`] order), their mean, the parts
/// agreeing, the parts found, the joints themselves and the seconds the
/// rig took.
struct Scored {
    off: [f64; 19],
    mean: f64,
    agree: f64,
    parts: usize,
    joints: [[f64; 3]; 19],
    /// The hips' midpoint above the landmark rig's (% of the height,
    /// along the rig's up; negative below).
    hips_up: f64,
    /// The motion's hips above the knees over the knees above the floor
    /// (`embed::auto::hips::bound_hips`'s ratio); `None` when the motion
    /// did not give both hips.
    hip_knee: Option<f64>,
    secs: f64,
    cpu: f64,
}

impl Scored {
    fn of(&self, c: Canonical) -> f64 {
        self.off[c.index()]
    }
    fn worst(&self) -> (Canonical, f64) {
        let j = (0..19)
            .max_by(|&a, &b| self.off[a].total_cmp(&self.off[b]))
            .unwrap_or(0);
        (Canonical::ALL[j], self.off[j])
    }
}

/// Capture `c` rigged as `db init` rigs it with `opts` on rest frame
/// `rest` (its vertices renumbered by a fixed shuffle when `renumber`;
/// the parts compared through it) and embedded on that frame, scored
/// against the landmark rig. `Err`: which step refused.
fn score(
    c: &Capture,
    rest: Option<usize>,
    renumber: bool,
    opts: AutoOptions,
) -> Result<Scored, String> {
    let n = c.mesh.vertex_count();
    let order: Vec<usize> = if renumber {
        shuffled(n)
    } else {
        (0..n).collect()
    };
    let mut new_of = vec![0u32; n];
    for (k, &o) in order.iter().enumerate() {
        new_of[o] = k as u32;
    }
    let tris: Vec<[u32; 3]> = c
        .mesh
        .triangles()
        .iter()
        .map(|t| t.map(|i| new_of[i as usize]))
        .collect();
    let pos = |q: &[[f64; 3]]| -> Vec<[f64; 3]> { order.iter().map(|&o| q[o]).collect() };
    let own: Vec<Vec<[f64; 3]>> = c.frames.iter().map(|q| pos(q)).collect();
    let fr: Vec<&[[f64; 3]]> = own.iter().map(Vec::as_slice).collect();
    let m = Mesh::new(pos(c.mesh.positions()), tris).map_err(|e| e.to_string())?;
    let t = Instant::now();
    let c0 = cpu_secs();
    let auto = auto_rig(
        &m,
        &fr,
        &AutoOptions {
            rest_frame: rest,
            ..opts
        },
    )
    .map_err(|e| format!("refused: {e}"))?;
    let secs = t.elapsed().as_secs_f64();
    let cpu = cpu_secs() - c0;
    let e = embed_or_why(&m, &fr, rest, &auto.landmarks)?;
    let h = c.truth.height();
    let off: [f64; 19] = std::array::from_fn(|j| {
        100.0 * DVec3::from_array(e.joints()[j]).distance(DVec3::from_array(c.truth.joints()[j]))
            / h
    });
    let labels: Vec<u8> = (0..n).map(|o| e.labels()[new_of[o] as usize]).collect();
    let up = DVec3::from_array(auto.up);
    let mid = |j: &[[f64; 3]; 19]| {
        let (l, r) = (Canonical::LHip.index(), Canonical::RHip.index());
        0.5 * (DVec3::from_array(j[l]) + DVec3::from_array(j[r])).dot(up)
    };
    let hips_up = 100.0 * (mid(e.joints()) - mid(c.truth.joints())) / h;
    Ok(Scored {
        mean: off.iter().sum::<f64>() / 19.0,
        hips_up,
        hip_knee: hip_over_knee(&auto, &fr, up),
        off,
        agree: 100.0 * agree(&labels, c.truth.labels()),
        parts: auto.parts,
        joints: *e.joints(),
        secs,
        cpu,
    })
}

/// The motion's hips above the knees over the knees above the floor (the
/// rest frame's lowest vertex along `up`), as `bound_hips` reads them.
fn hip_over_knee(
    auto: &crate::embed::auto::report::AutoRig,
    frames: &[&[[f64; 3]]],
    up: DVec3,
) -> Option<f64> {
    let rest = frames.get(auto.rest_frame.unwrap_or(0))?;
    let lo = rest
        .iter()
        .map(|p| DVec3::from_array(*p).dot(up))
        .fold(f64::INFINITY, f64::min);
    let at = |name: &str| {
        let j = auto.joints.iter().find(|j| j.name == name)?;
        Some((DVec3::from_array(j.position).dot(up) - lo, j.by_motion))
    };
    let [(lh, a), (rh, b), (lk, _), (rk, _)] =
        [at("l_hip")?, at("r_hip")?, at("l_knee")?, at("r_knee")?];
    let knees = 0.5 * (lk + rk);
    (a && b && knees > 0.0).then(|| (0.5 * (lh + rh) - knees) / knees)
}

/// Per joint, the automatic rig against the landmark rig (% of the
/// height) as `db init` makes it (`SURFMOTION_AUTORIG` applied), with the
/// vertices renumbered (a fixed shuffle; the joints compared through it),
/// and on samba with the rest frame forced to 2 and to 4 (both of its
/// still start: session 28's held rule chose either): l_elbow, r_knee,
/// the mean and worst joint, parts agreeing, parts found.
fn joints(data: &Path, w: &mut AutorigReport) -> Result<(), AutorigEvalError> {
    say!(
        w,
        "| capture | variant | rest | l_elbow % | r_knee % | joints mean % | worst | parts agree | parts |"
    );
    say!(w, "|---|---|---|---|---|---|---|---|---|");
    for_each_capture(data, w, |w, c| {
        let name = c.name;
        let (chosen, _) = rest_as_db_init(c.mesh, c.frames);
        let mut variants: Vec<(&str, Option<usize>, bool)> = vec![
            ("db init", chosen, false),
            ("db init, renumbered", chosen, true),
        ];
        if name == "samba" {
            for r in [2, 4] {
                variants.push(("rest forced", Some(r), false));
                variants.push(("rest forced, renumbered", Some(r), true));
            }
        }
        for (what, rest, renumber) in variants {
            let s = match score(c, rest, renumber, db_init_options(None)) {
                Ok(s) => s,
                Err(e) => {
                    say!(w, "| {name} | {what} | {rest:?} | {e} |");
                    continue;
                }
            };
            let (wj, wd) = s.worst();
            say!(
                w,
                "| {name} | {what} | {rest:?} | {:.2} | {:.2} | {:.2} | {} {wd:.1} | {:.1}% | {} |",
                s.of(Canonical::LElbow),
                s.of(Canonical::RKnee),
                s.mean,
                wj.name(),
                s.agree,
                s.parts
            );
            note_part!(w, "  {name} {what} {rest:?} ({:.1} s):", s.secs);
            for j in Canonical::ALL {
                note_part!(w, " {} {:.2}", j.name(), s.of(j));
            }
            note!(w);
        }
    })
}

/// `spread [SALTS]`: the rig's spread from draw to draw. Each capture
/// rigged as `db init` rigs it (`SURFMOTION_AUTORIG` applied) with the
/// decomposition's salt 0..SALTS (default 5; other pseudo-random draws
/// of the same seeding): per salt the mean joint, l_elbow, r_knee, worst
/// joint, parts agreeing with the landmark rig, parts; then the spread:
/// per joint the greatest distance between two salts' positions (% of the
/// height), its mean over the joints and its worst, and the range of the
/// mean joint error and of the parts agreeing; per salt also the hips'
/// midpoint above the landmark rig's (% of the height) and the motion's
/// hips above the knees over the knees' height (`hips::bound_hips`'s
/// ratio; "by proportion" when the motion did not give both hips). With
/// `renumber` each salt
/// is rigged twice, as numbered and with the vertices renumbered
/// (`score`'s fixed shuffle; the joints and parts compared through it).
fn spread(
    data: &Path,
    salts: u32,
    renumber: bool,
    w: &mut AutorigReport,
) -> Result<(), AutorigEvalError> {
    say!(
        w,
        "| capture | salt | joints mean % | l_elbow % | r_knee % | worst | parts agree | parts | wall s | CPU s | hips up % | hip/knee |"
    );
    say!(w, "|---|---|---|---|---|---|---|---|---|---|---|---|");
    for_each_capture(data, w, |w, c| {
        let name = c.name;
        let (rest, _) = rest_as_db_init(c.mesh, c.frames);
        let mut all: Vec<Scored> = Vec::new();
        let orders: &[bool] = if renumber { &[false, true] } else { &[false] };
        for salt in 0..salts {
            for &shuffle in orders {
                let mut o = db_init_options(None);
                o.decompose.salt = salt;
                let salt = if shuffle {
                    format!("{salt} renumbered")
                } else {
                    salt.to_string()
                };
                match score(c, rest, shuffle, o) {
                    Ok(s) => {
                        let (wj, wd) = s.worst();
                        say!(
                            w,
                            "| {name} | {salt} | {:.2} | {:.2} | {:.2} | {} {wd:.1} | {:.1}% | {} | {:.1} | {:.1} | {:+.2} | {} |",
                            s.mean,
                            s.of(Canonical::LElbow),
                            s.of(Canonical::RKnee),
                            wj.name(),
                            s.agree,
                            s.parts,
                            s.secs,
                            s.cpu,
                            s.hips_up,
                            s.hip_knee
                                .map_or("by proportion".into(), |r| format!("{r:.2}"))
                        );
                        all.push(s);
                    }
                    Err(e) => say!(w, "| {name} | {salt} | {e} |"),
                }
            }
        }
        let h = c.truth.height();
        let per_joint: Vec<f64> = (0..19)
            .map(|j| {
                let mut w = 0.0f64;
                for a in &all {
                    for b in &all {
                        let d =
                            DVec3::from_array(a.joints[j]).distance(DVec3::from_array(b.joints[j]));
                        w = w.max(100.0 * d / h);
                    }
                }
                w
            })
            .collect();
        let (wj, wd) = per_joint
            .iter()
            .enumerate()
            .fold((0, 0.0f64), |w, (j, &x)| if x > w.1 { (j, x) } else { w });
        let range = |f: &dyn Fn(&Scored) -> f64| {
            let v = all.iter().map(f);
            (
                v.clone().fold(f64::INFINITY, f64::min),
                v.fold(f64::NEG_INFINITY, f64::max),
            )
        };
        let (m0, m1) = range(&|s| s.mean);
        let (p0, p1) = range(&|s| s.agree);
        let (k0, k1) = range(&|s| s.of(Canonical::RKnee));
        let (e0, e1) = range(&|s| s.of(Canonical::LElbow));
        let k = all.len().max(1) as f64;
        let avg = |f: &dyn Fn(&Scored) -> f64| all.iter().map(f).sum::<f64>() / k;
        let worst = all
            .iter()
            .map(|s| s.worst())
            .fold(
                (Canonical::Pelvis, 0.0f64),
                |w, x| if x.1 > w.1 { x } else { w },
            );
        say!(
            w,
            "| {name} | spread over {} | mean {m0:.2}-{m1:.2} (avg {:.2}) | {e0:.2}-{e1:.2} | {k0:.2}-{k1:.2} | joint spread mean {:.2}, worst {} {wd:.2}; worst error {} {:.2} | {p0:.1}-{p1:.1}% (avg {:.1}) | | {:.1} | {:.1} |",
            all.len(),
            avg(&|s| s.mean),
            per_joint.iter().sum::<f64>() / 19.0,
            Canonical::ALL[wj].name(),
            worst.0.name(),
            worst.1,
            avg(&|s| s.agree),
            avg(&|s| s.secs),
            avg(&|s| s.cpu)
        );
    })
}
