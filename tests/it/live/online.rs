//! The online (fixed-lag) retrieval and the live session on the synthetic
//! samba database: with a lag and history covering the whole clip they give
//! the offline path and meshes exactly; at lag 3 and 0 every step is one the
//! offline path could take.

use super::offline::{character, offline, worst_difference};
use crate::common;

use surfmotion::drive::query::load_mocap;
use surfmotion::drive::timeline::plays_on;
use surfmotion::drive::trellis::{DatabaseLinks, TrellisInput, retrieve};
use surfmotion::drive::{DriveOptions, Prepared};
use surfmotion::live::{OnlineOptions, OnlineTrellis, Session};

/// The database frame path the online decoder commits for `on_floor`.
fn online_path(
    input: &TrellisInput,
    on_floor: &[surfmotion::pose::Pose],
    lag: usize,
) -> Vec<surfmotion::graph::FlatFrame> {
    decided(input, on_floor, lag).iter().map(|c| c.id).collect()
}

/// Every frame the online decoder commits for `on_floor`, in order.
fn decided(
    input: &TrellisInput,
    on_floor: &[surfmotion::pose::Pose],
    lag: usize,
) -> Vec<surfmotion::live::Committed> {
    let opts = DriveOptions::default();
    let mut t = OnlineTrellis::new(
        input,
        opts.trellis,
        OnlineOptions {
            lag,
            ..OnlineOptions::default()
        },
    );
    let mut path = Vec::new();
    for (k, q) in on_floor.iter().enumerate() {
        let a = t.push(q);
        assert!(a.committed.len() <= 1, "frame {k}: {a:?}");
        if k < lag {
            assert!(a.committed.is_empty(), "frame {k} decided before its lag");
        }
        path.extend(a.committed);
    }
    path.extend(t.finish().committed);
    path
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_lag_covering_the_clip_gives_the_offline_path_and_meshes_exactly() {
    let Some(d) = common::data_dir() else { return };
    let ch = character(&d);
    let opts = DriveOptions::default();
    let prepared = Prepared::new(&ch, &opts).unwrap();
    let links = DatabaseLinks::of(&ch);
    let input = links.input();
    for clip in ["cmu-amc/02/02_02.amc", "cmu-bvh/131_01.bvh"] {
        let o = offline(&d, &ch, &prepared, &opts, clip, |m| m.reference.clone());
        let (m, poses, a) = (&o.m, &o.poses, &o.analysed);
        let retrieved = retrieve(&a.on_floor, &input, &opts.trellis);
        let online = online_path(&input, &a.on_floor, poses.len());
        assert_eq!(online, retrieved.path, "{clip}: lag = length");
        // A lag longer than the clip, too.
        assert_eq!(
            online_path(&input, &a.on_floor, 10 * poses.len()),
            retrieved.path
        );
        // The meshes: the session fed the analysed clip equals the offline
        // synthesis bit for bit.
        let mut s = Session::new(&ch, &prepared, &input, m.reference.clone(), o.covering);
        let mut live = Vec::new();
        let mut order = Vec::new();
        let mut keep = |f: surfmotion::live::LiveFrame<'_>| {
            order.push(f.index);
            live.extend_from_slice(f.positions);
        };
        for (q, f) in a.query.iter().zip(&a.on_floor) {
            s.push_analysed(q, f, &mut keep);
        }
        s.finish(&mut keep);
        assert_eq!(order, (0..poses.len()).collect::<Vec<_>>(), "{clip}");
        assert_eq!(live.len(), o.meshes.len(), "{clip}");
        let worst = worst_difference(&live, &o.meshes);
        assert_eq!(
            worst, 0.0,
            "{clip}: online meshes differ from offline by {worst} m"
        );
        eprintln!(
            "{clip}: {} frames, offline path = online path, meshes identical",
            poses.len()
        );
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn short_lags_commit_every_frame_in_order_along_the_graph() {
    let Some(d) = common::data_dir() else { return };
    let ch = character(&d);
    let fps = ch.manifest().fps;
    let opts = DriveOptions::default();
    let prepared = Prepared::new(&ch, &opts).unwrap();
    let links = DatabaseLinks::of(&ch);
    let input = links.input();
    let m = load_mocap(
        &d.join("mocap/cmu-amc/02/02_02.amc"),
        &Default::default(),
        fps,
    )
    .unwrap();
    let a = prepared.analyse(&ch, &m.reference, &m.poses);
    let offline = retrieve(&a.on_floor, &input, &opts.trellis);
    for lag in [0, 3] {
        let steps = decided(&input, &a.on_floor, lag);
        let path: Vec<surfmotion::graph::FlatFrame> = steps.iter().map(|c| c.id).collect();
        assert_eq!(path.len(), a.on_floor.len(), "lag {lag}");
        for (k, c) in steps.iter().enumerate() {
            assert_eq!(c.index, k, "lag {lag}: decided out of order");
        }
        let jumps = (1..path.len())
            .filter(|&k| !plays_on(&ch, path[k - 1], path[k]))
            .count();
        for k in 1..path.len() {
            let edge = ch
                .adjacency()
                .successors(path[k - 1])
                .any(|(j, _)| j == path[k]);
            // Every step plays on, follows a graph edge or is a reported cut.
            assert!(
                plays_on(&ch, path[k - 1], path[k]) || edge || steps[k].cut,
                "lag {lag}: step {k} {} -> {} is none of them",
                path[k - 1],
                path[k]
            );
        }
        // The online path follows the query nearly as closely as the
        // offline one (mean c_skel of the nodes, metres summed over joints).
        let mean = |v: &mut dyn Iterator<Item = f64>| {
            let (s, n) = v.fold((0.0, 0usize), |(s, n), c| (s + c, n + 1));
            s / n.max(1) as f64
        };
        let on = mean(&mut steps.iter().map(|c| c.skeleton_cost));
        let off = mean(&mut offline.skeleton_cost.iter().copied());
        let offline_jumps = (1..offline.path.len())
            .filter(|&k| !plays_on(&ch, offline.path[k - 1], offline.path[k]))
            .count();
        eprintln!(
            "lag {lag}: {jumps} jumps ({offline_jumps} offline), mean c_skel {on:.4} m vs offline {off:.4} m ({:.2}x)",
            on / off
        );
        let bound = if lag == 0 { 2.0 } else { 1.5 };
        assert!(on <= bound * off, "lag {lag}: c_skel {on} vs offline {off}");
    }
}
