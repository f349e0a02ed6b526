//! Reader warnings are `tracing` events where they are raised (issue 19),
//! target `surfmotion::util::fsutil::WARNING`, and are still collected in the
//! struct the reader returns.
#![cfg(feature = "cli")]

use std::sync::{Arc, Mutex};
use surfmotion::util::fsutil::WARNING;
use tracing::field::{Field, Visit};
use tracing_subscriber::layer::{Context, Layer, SubscriberExt};

/// One captured event: target, level, message and `file` field.
#[derive(Debug, Clone, PartialEq)]
struct Captured {
    target: String,
    level: tracing::Level,
    message: String,
    file: String,
}

#[derive(Clone, Default)]
struct Capture(Arc<Mutex<Vec<Captured>>>);

#[derive(Default)]
struct Fields {
    message: String,
    file: String,
}

impl Visit for Fields {
    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        match field.name() {
            "message" => self.message = format!("{value:?}"),
            "file" => self.file = format!("{value:?}"),
            _ => {}
        }
    }
}

impl<S: tracing::Subscriber> Layer<S> for Capture {
    fn on_event(&self, event: &tracing::Event<'_>, _: Context<'_, S>) {
        let mut f = Fields::default();
        event.record(&mut f);
        self.0.lock().unwrap().push(Captured {
            target: event.metadata().target().to_string(),
            level: *event.metadata().level(),
            message: f.message,
            file: f.file,
        });
    }
}

/// Runs `f` with a subscriber that records every event; returns the
/// reader-warning events.
fn capture<T>(f: impl FnOnce() -> T) -> (T, Vec<Captured>) {
    let cap = Capture::default();
    let sub = tracing_subscriber::registry().with(cap.clone());
    let out = tracing::subscriber::with_default(sub, f);
    let events = cap.0.lock().unwrap().clone();
    (
        out,
        events.into_iter().filter(|e| e.target == WARNING).collect(),
    )
}

const BVH: &str = "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n JOINT L\n {\n  OFFSET 1 0 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  End Site\n  {\n   OFFSET 0 1 0\n  }\n }\n}\nMOTION\nFrames: 2\nFrame Time: 0.0333\n0 1 2 3 4 5 6 7 8\n1 2 3 4 5 6 7 8 9\n";

#[test]
fn clip_warning_is_a_tracing_event_and_kept_in_the_clip() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("three_claimed.bvh");
    // The header claims 3 frames; the data has 2: a warning, not an error.
    std::fs::write(&path, BVH.replace("Frames: 2", "Frames: 3")).unwrap();
    let (clip, events) =
        capture(|| surfmotion::rig::load_clip(&path, &surfmotion::rig::LoadOptions::default()));
    let clip = clip.unwrap();
    let want = "header says 3 frames, the data has 2; using the data";
    assert_eq!(clip.warnings(), vec![want.to_string()]);
    assert_eq!(events.len(), 1, "{events:?}");
    assert_eq!(events[0].level, tracing::Level::WARN);
    assert_eq!(events[0].message, want);
    assert!(events[0].file.ends_with("three_claimed.bvh"), "{events:?}");
}

#[test]
fn clean_clip_raises_no_warning_event() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("clean.bvh");
    std::fs::write(&path, BVH).unwrap();
    let (clip, events) =
        capture(|| surfmotion::rig::load_clip(&path, &surfmotion::rig::LoadOptions::default()));
    assert!(clip.unwrap().warnings().is_empty());
    assert!(events.is_empty(), "{events:?}");
}

#[test]
fn point_cache_warning_is_a_tracing_event_and_kept_in_the_cache() {
    let positions = vec![[0.0, 1.0, 2.0]; 4];
    let mut bytes = surfmotion::mesh::io::pc2::encode_pc2(2, &positions);
    bytes.extend_from_slice(&[0u8; 5]);
    let path = std::path::Path::new("trailing.pc2");
    let (cache, events) = capture(|| surfmotion::mesh::io::pc2::parse_pc2(&bytes, path));
    let cache = cache.unwrap();
    let want = "5 bytes after the last frame ignored";
    assert_eq!(cache.warnings, vec![want.to_string()]);
    assert_eq!(events.len(), 1, "{events:?}");
    assert_eq!(events[0].message, want);
    assert_eq!(events[0].file, "trailing.pc2");
}
