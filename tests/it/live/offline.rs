//! The offline-vs-online comparison set-up shared by `live::online` and
//! `live::carried`: a clip's first frames analysed and synthesised
//! offline, the session options whose lag and history cover them, a
//! session pushed a clip raw, and the largest coordinate difference
//! between two mesh sequences.

use crate::common;

use std::path::Path;
use surfmotion::db::Character;
use surfmotion::deform::DeformMode;
use surfmotion::drive::query::{ClipQuery, load_mocap};
use surfmotion::drive::trellis::DatabaseLinks;
use surfmotion::drive::{Analysed, DriveError, DriveOptions, Prepared};
use surfmotion::live::ground::OfflineGround;
use surfmotion::live::{LiveFrame, OnlineOptions, Session, SessionOptions};
use surfmotion::pose::Pose;
use surfmotion::pose::retarget::ClipNeutral;

/// The synthetic samba database's character (`common::synthetic_db`).
pub(super) fn character(d: &Path) -> Character {
    Character::load(&common::synthetic_db(d), &surfmotion::db::Quiet).unwrap()
}

/// Retarget options without deformation (the queries do not depend on
/// it: quick) and `ch` prepared for them.
pub(super) fn undeformed(ch: &Character) -> (DriveOptions, Prepared) {
    let opts = DriveOptions {
        deform: DeformMode::None,
        ..DriveOptions::default()
    };
    (opts, Prepared::new(ch, &opts).unwrap())
}

/// A clip's first frames (at most 150: a third of a CMU walk keeps the
/// tests quick, still several jumps) and their offline result.
pub(super) struct Offline {
    /// The clip as loaded (all its frames).
    pub m: ClipQuery,
    /// Its first frames.
    pub poses: Vec<Pose>,
    /// Those frames analysed on the character with the given reference.
    pub analysed: Analysed,
    /// The offline synthesis of `analysed` (every frame's vertices).
    pub meshes: Vec<[f64; 3]>,
    /// Session options whose lag and history cover the frames.
    pub covering: SessionOptions,
}

/// [`Offline`] for `clip` (under `../shared/data/mocap`) on `ch`, analysed
/// with `reference(&m)` (the clip's reference, with or without its file
/// rotations).
pub(super) fn offline(
    d: &Path,
    ch: &Character,
    prepared: &Prepared,
    opts: &DriveOptions,
    clip: &str,
    reference: impl Fn(&ClipQuery) -> ClipNeutral,
) -> Offline {
    let fps = ch.manifest().fps;
    let m = load_mocap(&d.join("mocap").join(clip), &Default::default(), fps).unwrap();
    let poses = m.poses[..m.poses.len().min(150)].to_vec();
    let n = poses.len();
    let analysed = prepared.analyse(ch, &reference(&m), &poses);
    let mut meshes = Vec::new();
    prepared
        .synthesise::<_, DriveError>(ch, &analysed, m.reference.source, fps, opts, &mut meshes)
        .unwrap();
    let covering = SessionOptions {
        retarget: *opts,
        online: OnlineOptions {
            lag: n,
            ..OnlineOptions::default()
        },
        history: n,
        ..SessionOptions::default()
    };
    Offline {
        m,
        poses,
        analysed,
        meshes,
        covering,
    }
}

/// The largest coordinate difference between two mesh sequences (metres).
pub(super) fn worst_difference(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(a, b)| (0..3).map(|i| (a[i] - b[i]).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max)
}

/// Every output frame of a session pushed `poses` raw (with their file
/// rotations when `rotations`; with the ground decisions `swap` takes from
/// the offline analysis), in order: (index, query, positions).
#[allow(clippy::type_complexity)]
pub(super) fn run_raw(
    ch: &Character,
    prepared: &Prepared,
    m: &surfmotion::drive::query::ClipQuery,
    poses: &[Pose],
    rotations: bool,
    sopts: SessionOptions,
    swap: Option<OfflineGround>,
) -> (Vec<usize>, Vec<Pose>, Vec<[f64; 3]>) {
    let links = DatabaseLinks::of(ch);
    let input = links.input();
    let mut s = Session::new(ch, prepared, &input, m.reference.without_rotations(), sopts);
    if let Some(g) = swap {
        s.swap_in(g);
    }
    let (mut order, mut queries, mut positions) = (Vec::new(), Vec::new(), Vec::new());
    let mut keep = |f: LiveFrame<'_>| {
        order.push(f.index);
        queries.push(*f.query);
        positions.extend_from_slice(f.positions);
    };
    for (i, p) in poses.iter().enumerate() {
        let r = if rotations {
            m.reference.rotations.get(i)
        } else {
            None
        };
        s.push(p, r, &mut keep);
    }
    s.finish(&mut keep);
    (order, queries, positions)
}
