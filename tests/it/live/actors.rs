//! Rokoko Studio Live with several actors: `--actor NAME|INDEX` picks the
//! one that drives the character (default the first), the others are
//! listed as seen, and a datagram without the chosen actor is skipped.

use surfmotion::live::humanoid::{BodyState, Bone, world_bones};
use surfmotion::live::rokoko::{ActorChoice, Rokoko, encode_actors};
use surfmotion::live::stream::{Protocol, Read};

/// A standing figure, `dx` metres along x.
fn figure(dx: f64) -> surfmotion::pose::Pose {
    std::array::from_fn(|c| glam::DVec3::new(dx + 0.03 * c as f64, 1.7 - 0.09 * c as f64, 0.1))
}

/// The hip bone read by a reader following `choice` from a datagram of
/// actors "ana" (at x = 0) and "ben" (at x = 1 m), with the actors seen.
fn hip(choice: ActorChoice, datagram: &[u8]) -> (Result<Read, String>, Option<Bone>, Vec<String>) {
    let mut r = Rokoko::new(choice);
    let seen = r.seen();
    let mut st = BodyState::default();
    let read = r.read(datagram, &mut st).map_err(|e| format!("{e:?}"));
    let hip = st.bones.get("hip").copied();
    let seen = seen.lock().unwrap().clone();
    (read, hip, seen)
}

#[test]
fn the_chosen_actor_drives_and_every_actor_is_listed() {
    let (a, b) = (
        world_bones(&figure(0.0), None),
        world_bones(&figure(1.0), None),
    );
    let d = encode_actors(&[("ana", &a), ("ben", &b)], 0.5, 60.0, None).unwrap();
    let (read, first, seen) = hip(ActorChoice::default(), &d);
    assert_eq!(read, Ok(Read::Frame(Some(0.5))));
    assert_eq!(seen, ["ana", "ben"]);
    let first = first.expect("the first actor's hip");
    for choice in [
        ActorChoice::Index(1),
        "ben".parse().unwrap(),
        "1".parse().unwrap(),
    ] {
        let (read, second, seen) = hip(choice.clone(), &d);
        assert_eq!(read, Ok(Read::Frame(Some(0.5))), "{choice:?}");
        assert_eq!(seen, ["ana", "ben"]);
        let moved = second.expect("the second actor's hip").pos - first.pos;
        // 1 m apart along one horizontal axis (Unity's x is mirrored).
        assert!((moved.length() - 1.0).abs() < 1e-9, "{choice:?}: {moved}");
        assert!(moved.y.abs() < 1e-9 && moved.z.abs() < 1e-9, "{moved}");
    }
    // An actor that is not in the datagram: nothing read, nothing malformed.
    for choice in [ActorChoice::Index(2), ActorChoice::Name("cy".into())] {
        let (read, hip, _) = hip(choice, &d);
        assert_eq!(read, Ok(Read::Partial));
        assert!(hip.is_none());
    }
}
