//! The two-frame overlap (`SessionOptions::overlap`): a frame held until
//! the next is ready, the two deformed at once, output in order. Every
//! output frame must be the one-frame path's bit for bit, in the same
//! order, none lost or repeated, none held past the next push; a lone last
//! frame comes out of `finish`. The arrival patterns are generated and go
//! through the newest-wins mailbox the network sources use: bursts (frames
//! replaced before the session took them: dropped), gaps in the sender's
//! numbers, duplicates, a single frame, streams ending mid-pair; at lag 0
//! and 3 (where `finish` decides three frames at once) on the synthetic
//! samba database with the part-based deformation and its fold repair.

use super::offline::character;
use crate::common;

use std::time::{Duration, Instant};
use surfmotion::db::Character;
use surfmotion::drive::query::load_mocap;
use surfmotion::drive::trellis::DatabaseLinks;
use surfmotion::drive::{DriveOptions, Prepared};
use surfmotion::live::mailbox::Mailbox;
use surfmotion::live::source::{Event, Incoming};
use surfmotion::live::{LiveFrame, OnlineOptions, Overlap, Session, SessionOptions};
use surfmotion::pose::Pose;
use surfmotion::pose::retarget::ClipNeutral;

/// A small generator (xorshift), seeded per pattern.
struct Rng(u64);

impl Rng {
    fn below(&mut self, n: usize) -> usize {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 % n.max(1) as u64) as usize
    }
}

/// The poses a session is pushed when the stream's frames `0..n` of
/// `poses` arrive in generated bursts through a newest-wins mailbox: each
/// step puts 1-`burst` frames (skipping some sender numbers: gaps, and
/// repeating some: duplicates) and the session takes what is there.
fn through_mailbox(poses: &[Pose], n: usize, burst: usize, seed: u64) -> Vec<Pose> {
    let mb = Mailbox::default();
    let mut rng = Rng(seed);
    let (mut seq, mut taken) = (0u64, Vec::new());
    while (seq as usize) < n {
        for _ in 0..1 + rng.below(burst) {
            if seq as usize >= n {
                break;
            }
            let dup = rng.below(5) == 0;
            let f = Incoming {
                seq,
                pose: poses[seq as usize],
                rotations: None,
                arrived: Instant::now(),
            };
            mb.put(f);
            if dup {
                mb.put(f);
            }
            seq += 1 + (rng.below(6) == 0) as u64;
        }
        if let Ok(Event::Frame(f)) = mb.next(Duration::ZERO) {
            taken.push(f.pose);
        }
    }
    if let Ok(Event::Frame(f)) = mb.next(Duration::ZERO) {
        taken.push(f.pose);
    }
    taken
}

/// One output frame: its index, database frame, the push it came out on
/// (0 for `finish`), `held`, and its query's and vertices' bits.
type Out = (usize, u32, usize, usize, Vec<u64>, Vec<u64>);

fn run(
    ch: &Character,
    prepared: &Prepared,
    reference: &ClipNeutral,
    pushed: &[Pose],
    waiting: &[bool],
    sopts: SessionOptions,
) -> Vec<Out> {
    let links = DatabaseLinks::of(ch);
    let input = links.input();
    let mut s = Session::new(ch, prepared, &input, reference.clone(), sopts);
    let mut outs = Vec::new();
    let mut keep = |f: LiveFrame<'_>, on: usize| {
        outs.push((
            f.index,
            f.id.get(),
            on,
            f.held,
            f.query
                .iter()
                .flat_map(|j| j.to_array())
                .map(f64::to_bits)
                .collect(),
            f.positions.iter().flatten().map(|x| x.to_bits()).collect(),
        ));
    };
    for (i, p) in pushed.iter().enumerate() {
        if let Some(&w) = waiting.get(i) {
            s.set_waiting(w);
        }
        s.push(p, None, &mut |f| keep(f, i + 1));
    }
    s.finish(&mut |f| keep(f, 0));
    outs
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_overlap_outputs_the_one_frame_paths_frames_in_order() {
    let Some(d) = common::data_dir() else { return };
    let ch = character(&d);
    let opts = DriveOptions::default();
    let prepared = Prepared::new(&ch, &opts).unwrap();
    assert!(prepared.deformer().is_some(), "the deformation must run");
    let fps = ch.manifest().fps;
    let clip = d.join("mocap/cmu-amc/02/02_02.amc");
    let m = load_mocap(&clip, &Default::default(), fps).unwrap();
    let reference = m.reference.without_rotations();
    let poses = &m.poses[..m.poses.len().min(40)];
    // (name, frames pushed): a single frame, a pair, an odd count (the
    // stream ends mid-pair), every frame, and generated bursts and gaps.
    let mut patterns: Vec<(String, Vec<Pose>)> = vec![
        ("single".into(), poses[..1].to_vec()),
        ("pair".into(), poses[..2].to_vec()),
        ("five".into(), poses[..5].to_vec()),
        ("every frame".into(), poses[..24].to_vec()),
    ];
    for seed in 1..=3u64 {
        let n = 20 + 7 * seed as usize;
        let taken = through_mailbox(poses, n.min(poses.len()), 1 + seed as usize, seed);
        patterns.push((format!("bursts seed {seed}"), taken));
    }
    let (mut moving, mut queued_holds) = (0, 0);
    for (name, pushed) in &patterns {
        for lag in [0, 3] {
            let base = SessionOptions {
                retarget: opts,
                online: OnlineOptions {
                    lag,
                    ..OnlineOptions::default()
                },
                overlap: Overlap::Off,
                ..SessionOptions::default()
            };
            let one = run(&ch, &prepared, &reference, pushed, &[], base);
            let two = run(
                &ch,
                &prepared,
                &reference,
                pushed,
                &[],
                SessionOptions {
                    overlap: Overlap::Always,
                    ..base
                },
            );
            let what = format!("{name} ({} pushed), lag {lag}", pushed.len());
            assert_eq!(one.len(), pushed.len(), "{what}: one frame out per push");
            assert_eq!(two.len(), one.len(), "{what}: frames out");
            for (k, (a, b)) in one.iter().zip(&two).enumerate() {
                assert_eq!((a.0, b.0), (k, k), "{what}: output {k} out of order");
                assert_eq!(a.1, b.1, "{what}: frame {k}'s database frame");
                assert_eq!(a.3, 0, "{what}: the one-frame path holds nothing");
                assert!(a.4 == b.4, "{what}: frame {k}'s query differs");
                assert!(a.5 == b.5, "{what}: frame {k}'s vertices differ");
                // A held frame comes out on the next push (or at the end),
                // never later; an unheld one where the one-frame path has it.
                // A frame decided on the last push may be held into
                // `finish`.
                let last = pushed.len();
                match (b.3, a.2, b.2) {
                    (0, x, y) => assert!(
                        x == y || (y == 0 && x == last),
                        "{what}: frame {k} came out on {y}, not {x}"
                    ),
                    (1, x, y) => assert!(x > 0 && y == x + 1, "{what}: frame {k} held {x} → {y}"),
                    (h, ..) => panic!("{what}: frame {k} held {h} pushes"),
                }
            }
            // The pairs: with the overlap a push outputs no frame or two
            // (the held one first); `finish` outputs the rest.
            let held = two.iter().filter(|o| o.3 == 1).count();
            let on_pushes = two.iter().filter(|o| o.2 > 0).count();
            assert_eq!(on_pushes, 2 * held, "{what}: pairs on the pushes");
            moving += one.iter().filter(|o| o.5 != one[0].5).count();
            queued_holds +=
                only_while_waiting(&ch, &prepared, &reference, pushed, &one, base, &what);
        }
    }
    // The frames differ from each other (the test compares real meshes),
    // and the queued overlap held frames where the next one waited.
    assert!(moving > 0);
    assert!(queued_holds > 0, "the queued overlap never held a frame");
}

/// [`Overlap::Queued`] on `pushed` with generated waiting flags (and with
/// none waiting): the one-frame path's frames `one` bit for bit, in order,
/// and a frame held only when it was decided on a push told the next frame
/// was waiting or that decided another frame after it. Returns the frames
/// held.
fn only_while_waiting(
    ch: &Character,
    prepared: &Prepared,
    reference: &ClipNeutral,
    pushed: &[Pose],
    one: &[Out],
    base: SessionOptions,
    what: &str,
) -> usize {
    let opts = SessionOptions {
        overlap: Overlap::Queued,
        ..base
    };
    let mut rng = Rng(pushed.len() as u64 * 7919 + 17);
    let generated: Vec<bool> = (0..pushed.len()).map(|_| rng.below(2) == 0).collect();
    let never = vec![false; pushed.len()];
    let mut held = 0;
    for waiting in [&generated, &never] {
        let q = run(ch, prepared, reference, pushed, waiting, opts);
        assert_eq!(q.len(), one.len(), "{what}, queued: frames out");
        for (k, (a, b)) in one.iter().zip(&q).enumerate() {
            assert_eq!(b.0, k, "{what}, queued: output {k} out of order");
            assert!(
                a.1 == b.1 && a.4 == b.4 && a.5 == b.5,
                "{what}, queued: frame {k} differs"
            );
        }
        // The push each frame was decided on (the held ones one earlier).
        let decided: Vec<usize> = q
            .iter()
            .map(|o| if o.3 == 1 { o.2 - 1 } else { o.2 })
            .collect();
        for (k, o) in q.iter().enumerate().filter(|(_, o)| o.3 == 1) {
            let x = decided[k];
            let others = decided.iter().filter(|&&d| d == x).count();
            assert!(
                waiting[x - 1] || others > 1,
                "{what}, queued: frame {k} held on push {x}, nothing waiting"
            );
            held += 1;
            assert!(o.3 <= 1);
        }
    }
    held
}
