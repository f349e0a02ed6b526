//! The rest frame a rig is embedded on, chosen rather than assumed
//! (issue 41): over every frame of a character's sequences, the frame
//! whose limbs are clearest of the body — the fewest vertices in a contact
//! ([`super::contact`]: a hand on the hip, forearms on the belly), then
//! the fewest barely clear of one — and, among frames as clear, the one
//! nearest frame 0 in the order given (the capture's own start, usually its
//! most neutral pose). Frame 0 is kept whenever it has no contact, so a
//! clear capture rigs exactly as before.
//! With [`RestOptions::by_pose`] (the automatic rig's rule,
//! [`RestOptions::automatic`]) the order given plays no part: among the
//! clearest frames, one chosen by its pose alone ([`PoseRule`]; by
//! default the most standing with the limbs in,
//! [`super::pose_order::spread`]; [`PoseRule::Held`], the pose the
//! capture holds longest: samba's still start, crane's A-pose), ties
//! broken by pose. The mean pose was tried first: it chose
//! samba's frame 119, mid-step, and the rig embedded there warned of
//! wrists, ankles and toes 10-20 % apart; the most standing within the
//! near slack (session 25) chose samba's frame 87; the most standing
//! (session 26, [`PoseRule::Standing`]) chose samba's still start but a
//! step of crane's walk (frame 86).

use super::contact::{ContactFinder, ContactOptions, FrameContacts};

use crate::mesh::Mesh;
use serde::Serialize;

/// How [`choose_rest_frame`] chooses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RestOptions {
    /// The contact thresholds. Default [`ContactOptions::default`].
    pub contact: ContactOptions,
    /// Frames whose near count (vertices within
    /// [`ContactOptions::near`] of a surface-far vertex) exceeds the
    /// clearest frame's by at most this fraction of the vertices count as
    /// clear as it. Default 0.01 (1 %).
    pub near_slack: f64,
    /// The most frames among the clearest whose near count is measured
    /// (evenly spread; the first always among them; with `by_pose`, the
    /// most standing). Default 24.
    pub candidates: usize,
    /// Choose by pose alone, never by index: among the clearest frames,
    /// the one most standing with the limbs in
    /// ([`super::pose_order::standing_first`]) whose near count is
    /// within the slack, frame 0 not kept for being first. The automatic
    /// rig's rule (its parts and joints then do not depend on the frame a
    /// capture starts with); landmarks marked on the topology keep the
    /// topology when it is clear. Default false.
    pub by_pose: bool,
    /// With `by_pose`, which of the clearest frames. Default
    /// [`PoseRule::Standing`].
    pub pose_rule: PoseRule,
}

/// [`RestOptions::by_pose`]'s choice among the frames with the fewest
/// touching vertices (the contact-clear ones when there are any).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PoseRule {
    /// The pose the capture holds longest
    /// ([`super::pose_order::held_first`]: the nearest frames in pose
    /// closest), of the more standing half: a capture's still start or
    /// end (samba's frames 4-10, arms hanging; crane's A-pose, frames
    /// 2-9). An option (`SURFMOTION_AUTORIG=rest=held`):
    /// [`PoseRule::Standing`] chose a step of crane's walk (frame 86, the
    /// right knee bent), and the automatic rig on it put crane's right
    /// knee 4.4 % of the height off the landmark rig's (0.1 / 2.2 % on
    /// this rule's frame 5); see `AutoOptions::frames` for why it is not
    /// the default.
    Held,
    /// The most standing with the limbs in
    /// ([`super::pose_order::standing_first`]). The near count is not
    /// asked: samba's still start has its hands hanging beside the skirt
    /// (many vertices near, none touching), and asking it moved the
    /// choice to a dance frame (87).
    Standing,
    /// The most standing whose near count is within
    /// [`RestOptions::near_slack`] of the least among the
    /// [`RestOptions::candidates`] most standing (session 25's rule: samba's
    /// frame 87).
    StandingNear,
    /// The nearest the per-coordinate median of all frames' pose
    /// descriptors ([`super::pose_order::median`]).
    NearestMedian,
}

impl PoseRule {
    /// The rule named `name` (`held`, `standing`, `standing-near`,
    /// `median`).
    pub fn parse(name: &str) -> Option<PoseRule> {
        match name {
            "held" => Some(PoseRule::Held),
            "standing" => Some(PoseRule::Standing),
            "standing-near" => Some(PoseRule::StandingNear),
            "median" => Some(PoseRule::NearestMedian),
            _ => None,
        }
    }
}

impl RestOptions {
    /// The rule by pose for the automatic rig: [`PoseRule::Standing`]. Not
    /// `db init`'s default (`embed::auto::options::automatic_setup`; with
    /// `SURFMOTION_AUTORIG=rest=standing`, or `rest=held`).
    pub fn automatic() -> RestOptions {
        RestOptions {
            by_pose: true,
            ..RestOptions::default()
        }
    }
}

impl Default for RestOptions {
    fn default() -> Self {
        RestOptions {
            contact: ContactOptions::default(),
            near_slack: 0.01,
            candidates: 24,
            by_pose: false,
            pose_rule: PoseRule::Standing,
        }
    }
}

/// The rest frame chosen and why.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RestChoice {
    /// The frame chosen (index into the frames given).
    pub frame: usize,
    /// Its contacts.
    pub contacts: FrameContacts,
    /// Frame 0's contacts.
    pub first: FrameContacts,
    /// Frames examined.
    pub frames: usize,
    /// Frames with a contact.
    pub frames_in_contact: usize,
    /// Which: their indices into the frames given, in order.
    pub contact_frames: Vec<usize>,
    /// One line: why this frame.
    pub why: String,
}

/// The rest frame among `frames` (each one position per vertex of
/// `mesh`, in the order of the sequences; `frames[0]` is the current rest
/// frame), with the contacts of the chosen frame and of frame 0 and a
/// one-line reason. Surface distances are measured on `mesh`'s own
/// positions (with [`RestOptions::by_pose`], on the most standing frame).
/// `None` when `frames` is empty.
///
/// Cost: [`ContactFinder::new`] once, [`ContactFinder::find`] per frame,
/// and [`ContactFinder::near`] on frame 0 and, when frame 0 has a contact,
/// on at most [`RestOptions::candidates`] of the clearest frames.
pub fn choose_rest_frame(
    mesh: &Mesh,
    frames: &[&[[f64; 3]]],
    opts: &RestOptions,
) -> Option<RestChoice> {
    if opts.by_pose
        && let Some(m) = reference_by_pose(mesh, frames)
    {
        return choose_with(&ContactFinder::new(&m, opts.contact), frames, opts);
    }
    let finder = ContactFinder::new(mesh, opts.contact);
    choose_with(&finder, frames, opts)
}

/// `mesh` on the most standing frame ([`super::pose_order::spread`]):
/// [`RestOptions::by_pose`]'s
/// reference for surface distances and heights, so that the counts do not
/// depend on which frame the mesh's own positions are (the contact frame a
/// capture starts with). `None` without frames or on a frame that does not
/// fit the mesh.
fn reference_by_pose(mesh: &Mesh, frames: &[&[[f64; 3]]]) -> Option<Mesh> {
    use super::pose_order::standing_first;
    let descs = descriptors(frames);
    let all: Vec<usize> = (0..frames.len()).collect();
    let f = *standing_first(frames, &descs, &all).first()?;
    mesh.with_positions(frames[f]).ok()
}

/// Every frame's pose descriptor on vertices chosen by the motion
/// ([`super::pose_order::descriptor_vertices`]): the held rule's hold
/// radii and every tie by pose then follow the body, not the vertex
/// numbering (on every `n / K`-th id they did: session 29).
fn descriptors(frames: &[&[[f64; 3]]]) -> Vec<Vec<f64>> {
    use super::pose_order::{descriptor_at, descriptor_vertices};
    let picks = descriptor_vertices(frames);
    frames.iter().map(|f| descriptor_at(f, &picks)).collect()
}

/// [`choose_rest_frame`] with a prepared finder.
pub(crate) fn choose_with(
    finder: &ContactFinder,
    frames: &[&[[f64; 3]]],
    opts: &RestOptions,
) -> Option<RestChoice> {
    if frames.is_empty() {
        return None;
    }
    let mut found: Vec<FrameContacts> = frames.iter().map(|f| finder.find(f)).collect();
    let n = frames[0].len().max(1);
    let least = found.iter().map(|c| c.touching).min().unwrap_or(0);
    let slack = (opts.near_slack * n as f64).ceil() as usize;
    let mut nearest = 0;
    // A clear frame 0 is kept: a clear capture rigs exactly as before.
    let frame = if opts.by_pose {
        let (f, least_near) = by_pose(finder, frames, &mut found, least, slack, opts);
        nearest = least_near;
        f
    } else if found[0].contacts.is_empty() {
        0
    } else {
        // The near count of at most `opts.candidates` of the clearest
        // frames, evenly spread in order.
        let clearest: Vec<usize> = (0..found.len())
            .filter(|&f| found[f].touching == least)
            .collect();
        let step = clearest.len().div_ceil(opts.candidates.max(1)).max(1);
        let examined: Vec<usize> = clearest.iter().copied().step_by(step).collect();
        for &f in &examined {
            found[f].near = finder.near(frames[f]);
        }
        nearest = examined.iter().map(|&f| found[f].near).min().unwrap_or(0);
        examined
            .iter()
            .copied()
            .find(|&f| found[f].near <= nearest + slack)
            .unwrap_or(0)
    };
    found[0].near = finder.near(frames[0]);
    let in_contact = found.iter().filter(|c| !c.contacts.is_empty()).count();
    let first = found[0].clone();
    let contacts = found[frame].clone();
    let describe = |c: &FrameContacts| {
        if c.contacts.is_empty() {
            "no contact".to_string()
        } else {
            format!(
                "{} contact(s), {} vertices touching",
                c.contacts.len(),
                c.touching
            )
        }
    };
    let why = if opts.by_pose {
        format!(
            "{} among those with {}: {} vertices near a surface-far one; frame 0 has {} ({} of {} frames have a contact)",
            match opts.pose_rule {
                PoseRule::Held =>
                    "the pose the capture holds longest, of the more standing half (`pose_order::held_first`)".to_string(),
                PoseRule::Standing =>
                    "the frame most standing with the limbs in (`pose_order::spread`)".to_string(),
                PoseRule::StandingNear => format!(
                    "the frame most standing with the limbs in (`pose_order::spread`) with at most {} vertices near (the clearest {nearest}, slack {slack})",
                    nearest + slack
                ),
                PoseRule::NearestMedian =>
                    "the frame nearest the median pose (`pose_order::median`)".to_string(),
            },
            describe(&contacts),
            contacts.near,
            describe(&first),
            in_contact,
            frames.len()
        )
    } else if frame == 0 {
        if first.contacts.is_empty() {
            format!(
                "frame 0 is clear of contact ({} of {} frames have one)",
                in_contact,
                frames.len()
            )
        } else {
            format!(
                "frame 0 kept: {}, no frame is clearer ({} of {} frames have a contact)",
                describe(&first),
                in_contact,
                frames.len()
            )
        }
    } else {
        format!(
            "frame 0 has {}; the first frame with {} and {} vertices near a surface-far one (the clearest {nearest}, slack {slack}) is chosen",
            describe(&first),
            describe(&contacts),
            contacts.near
        )
    };
    Some(RestChoice {
        frame,
        contacts,
        first,
        frames: frames.len(),
        frames_in_contact: in_contact,
        contact_frames: (0..found.len())
            .filter(|&f| !found[f].contacts.is_empty())
            .collect(),
        why,
    })
}

/// [`RestOptions::by_pose`]'s choice among the clearest frames (`least`
/// touching vertices), by [`RestOptions::pose_rule`]; ties broken by pose.
/// Returns the frame and the least near count measured (of the frames
/// examined; the frame's own when only it is).
fn by_pose(
    finder: &ContactFinder,
    frames: &[&[[f64; 3]]],
    found: &mut [FrameContacts],
    least: usize,
    slack: usize,
    opts: &RestOptions,
) -> (usize, usize) {
    use super::pose_order::{held_first, median, nearest, standing_first};
    let descs = descriptors(frames);
    let clearest: Vec<usize> = (0..found.len())
        .filter(|&f| found[f].touching == least)
        .collect();
    let mut examined = match opts.pose_rule {
        PoseRule::Held => held_first(frames, &descs, &clearest),
        PoseRule::NearestMedian => nearest(&descs, &median(&descs), &clearest),
        PoseRule::Standing | PoseRule::StandingNear => standing_first(frames, &descs, &clearest),
    };
    let keep = match opts.pose_rule {
        PoseRule::StandingNear => opts.candidates.max(1),
        PoseRule::Held | PoseRule::Standing | PoseRule::NearestMedian => 1,
    };
    examined.truncate(keep);
    for &f in &examined {
        found[f].near = finder.near(frames[f]);
    }
    let nearest_count = examined.iter().map(|&f| found[f].near).min().unwrap_or(0);
    let frame = examined
        .iter()
        .copied()
        .find(|&f| found[f].near <= nearest_count + slack)
        .unwrap_or(0);
    (frame, nearest_count)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two boxes side by side joined by a thin bridge far away: in
    /// "touching" frames the boxes' facing sides are 1 cm apart.
    fn two_boxes() -> (Mesh, Vec<[f64; 3]>, Vec<[f64; 3]>) {
        // A strip of quads: box A's side at x = 0, box B's at x = gap,
        // joined by a long U (see contact.rs's folded strip).
        let ladder = |gap: f64| -> Vec<[f64; 3]> {
            let mut p = Vec::new();
            for i in 0..=40 {
                let t = i as f64 / 40.0 * 4.0;
                // 0..1.8 up on x = 0, 0.4 across the top, 1.8 down on x = gap
                let (x, y) = if t <= 1.8 {
                    (0.0, t)
                } else if t <= 2.2 {
                    (gap * (t - 1.8) / 0.4, 1.8)
                } else {
                    (gap, 1.8 - (t - 2.2))
                };
                p.push([x, y, 0.0]);
                p.push([x, y, 0.1]);
            }
            p
        };
        let mut t = Vec::new();
        for i in 0..40u32 {
            let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
            t.push([a, c, b]);
            t.push([b, c, d]);
        }
        let touching = ladder(0.01);
        let clear = ladder(0.5);
        (Mesh::new(touching.clone(), t).unwrap(), touching, clear)
    }

    #[test]
    fn a_contact_in_frame_0_moves_the_rest_to_the_first_clear_frame() {
        let (mesh, touching, clear) = two_boxes();
        let frames: Vec<&[[f64; 3]]> = vec![&touching, &touching, &clear, &clear];
        let c = choose_rest_frame(&mesh, &frames, &RestOptions::default()).unwrap();
        assert_eq!(c.frame, 2, "{}", c.why);
        assert!(!c.first.contacts.is_empty());
        assert!(c.contacts.contacts.is_empty());
        assert_eq!(c.frames_in_contact, 2);
        // A clear frame 0 is kept.
        let frames: Vec<&[[f64; 3]]> = vec![&clear, &touching, &clear];
        let c = choose_rest_frame(&mesh, &frames, &RestOptions::default()).unwrap();
        assert_eq!(c.frame, 0, "{}", c.why);
        // Every frame touching: frame 0 stays, said so.
        let frames: Vec<&[[f64; 3]]> = vec![&touching, &touching];
        let c = choose_rest_frame(&mesh, &frames, &RestOptions::default()).unwrap();
        assert_eq!(c.frame, 0);
        assert!(c.why.contains("no frame is clearer"), "{}", c.why);
        assert!(choose_rest_frame(&mesh, &[], &RestOptions::default()).is_none());
    }

    #[test]
    fn the_automatic_rule_chooses_the_same_pose_in_any_order() {
        let (mesh, touching, clear) = two_boxes();
        // A third pose: clear, the boxes farther apart (more spread).
        let wide: Vec<[f64; 3]> = clear
            .iter()
            .map(|p| {
                if p[0] > 0.25 {
                    [p[0] + 0.4, p[1], p[2]]
                } else {
                    *p
                }
            })
            .collect();
        let poses = [&touching, &wide, &clear];
        let mut chosen = Vec::new();
        for order in [[0, 1, 2], [2, 0, 1], [1, 2, 0], [0, 2, 1]] {
            let frames: Vec<&[[f64; 3]]> = order.iter().map(|&k| poses[k].as_slice()).collect();
            let topo = Mesh::new(frames[0].to_vec(), mesh.triangles().to_vec()).unwrap();
            for rule in [PoseRule::Held, PoseRule::Standing, PoseRule::NearestMedian] {
                let opts = RestOptions {
                    pose_rule: rule,
                    ..RestOptions::automatic()
                };
                let c = choose_rest_frame(&topo, &frames, &opts).unwrap();
                assert!(c.contacts.contacts.is_empty(), "{}", c.why);
                chosen.push((rule, frames[c.frame].to_vec()));
            }
        }
        for rule in [PoseRule::Held, PoseRule::Standing, PoseRule::NearestMedian] {
            let mine: Vec<&Vec<[f64; 3]>> = chosen
                .iter()
                .filter(|(r, _)| *r == rule)
                .map(|(_, p)| p)
                .collect();
            assert!(mine.iter().all(|p| *p == mine[0]), "{rule:?}");
        }
    }
}
