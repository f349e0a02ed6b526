//! Rokoko Studio Live: JSON over UDP (default port 14043), one datagram a
//! frame: `{"version": 3, "fps": F, "scene": {"timestamp": T, "actors":
//! [{"name": N, "body": {"hip": {"position": {"x","y","z"}, "rotation":
//! {"x","y","z","w"}}, …}}]}}`. Positions (metres) and rotations are world
//! transforms in Unity's axes (Y up, left-handed); the body joints are
//! named as [`ROKOKO_BONES`]. One actor drives the character (the first,
//! or the one [`Actor`] names: `--actor NAME|INDEX`); a datagram without
//! it is skipped. The actors' names seen are kept ([`Rokoko::seen`]) for
//! the report. Props, faces, fingers and unknown joints are ignored.
//!
//! The sender may add `"surfmotion": {"reference": {"hip": {"x","y","z"},
//! …}}`, its neutral reference (which other receivers ignore).

use super::humanoid::{BodyState, Bone, ROKOKO_BONES, ROKOKO_CANONICAL, from_unity, mirror};
use super::stream::{Malformed, Protocol, Read};
use crate::pose::Pose;
use crate::rig::Canonical;
use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The Rokoko Studio Live default port.
pub const DEFAULT_PORT: u16 = 14043;

/// The actor that drives the character.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ActorChoice {
    /// The actor at this position in each datagram (from 0).
    Index(usize),
    /// The actor of this name.
    Name(String),
}

impl Default for ActorChoice {
    fn default() -> Self {
        ActorChoice::Index(0)
    }
}

impl std::str::FromStr for ActorChoice {
    type Err = std::convert::Infallible;
    /// A number is an index, anything else a name.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(match s.parse::<usize>() {
            Ok(i) => ActorChoice::Index(i),
            Err(_) => ActorChoice::Name(s.to_string()),
        })
    }
}

/// The most actor names kept for the report.
const MAX_SEEN: usize = 32;

/// Rokoko Studio Live's reader.
#[derive(Debug, Default)]
pub struct Rokoko {
    /// The actor that drives the character.
    pub actor: ActorChoice,
    seen: std::sync::Arc<std::sync::Mutex<Vec<String>>>,
}

impl Rokoko {
    /// A reader that follows `actor`.
    pub fn new(actor: ActorChoice) -> Rokoko {
        Rokoko {
            actor,
            ..Rokoko::default()
        }
    }

    /// The actors' names seen so far (in order of first appearance, at
    /// most 32), shared with the reader once it is moved to its thread.
    pub fn seen(&self) -> std::sync::Arc<std::sync::Mutex<Vec<String>>> {
        self.seen.clone()
    }

    fn note(&self, actors: &[Actor]) {
        let mut seen = self.seen.lock().unwrap_or_else(|e| e.into_inner());
        for a in actors {
            if seen.len() < MAX_SEEN && !seen.contains(&a.name) {
                seen.push(a.name.clone());
            }
        }
    }

    fn pick<'p>(&self, actors: &'p [Actor]) -> Option<&'p Actor> {
        match &self.actor {
            ActorChoice::Index(i) => actors.get(*i),
            ActorChoice::Name(n) => actors.iter().find(|a| &a.name == n),
        }
    }
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
struct V3 {
    x: f64,
    y: f64,
    z: f64,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
struct Q {
    x: f64,
    y: f64,
    z: f64,
    w: f64,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
struct JointJson {
    position: V3,
    rotation: Q,
}

#[derive(Debug, Serialize, Deserialize)]
struct Actor {
    #[serde(default)]
    name: String,
    #[serde(default)]
    body: BTreeMap<String, serde_json::Value>,
}

#[derive(Debug, Serialize, Deserialize)]
struct Scene {
    #[serde(default)]
    timestamp: Option<f64>,
    actors: Vec<Actor>,
}

#[derive(Debug, Serialize, Deserialize)]
struct Ext {
    reference: BTreeMap<String, V3>,
}

#[derive(Debug, Serialize, Deserialize)]
struct Packet {
    #[serde(default)]
    version: serde_json::Value,
    #[serde(default)]
    fps: Option<f64>,
    scene: Scene,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    surfmotion: Option<Ext>,
}

fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// A joint's transform in the project's axes.
fn joint(name: &str, v: &serde_json::Value) -> Result<Bone, Malformed> {
    let j: JointJson =
        serde_json::from_value(v.clone()).map_err(|e| Malformed(format!("body.{name}: {e}")))?;
    let (p, r) = (j.position, j.rotation);
    let q = DQuat::from_xyzw(r.x, r.y, r.z, r.w);
    if !(finite(&[p.x, p.y, p.z, r.x, r.y, r.z, r.w]) && q.length() > 1e-6) {
        return Err(Malformed(format!("body.{name}: not a transform")));
    }
    Ok(mirror(Bone {
        pos: DVec3::new(p.x, p.y, p.z),
        rot: q.normalize(),
    }))
}

impl Protocol for Rokoko {
    const NAME: &'static str = "Rokoko Studio Live (JSON over UDP)";
    const TABLE: super::humanoid::BoneTable = ROKOKO_BONES;
    const CANONICAL: [&'static str; Canonical::COUNT] = ROKOKO_CANONICAL;
    const LOCAL: bool = false;

    fn read(&mut self, datagram: &[u8], state: &mut BodyState) -> Result<Read, Malformed> {
        let p: Packet =
            serde_json::from_slice(datagram).map_err(|e| Malformed(format!("JSON: {e}")))?;
        self.note(&p.scene.actors);
        let Some(actor) = self.pick(&p.scene.actors) else {
            return Ok(Read::Partial);
        };
        let mut bones = Vec::new();
        for (name, v) in &actor.body {
            if ROKOKO_BONES.iter().any(|(n, _)| n == name) {
                bones.push((name.clone(), joint(name, v)?));
            }
        }
        let reference = match &p.surfmotion {
            Some(ext) => Some(reference(ext)?),
            None => None,
        };
        let t = p.scene.timestamp;
        if t.is_some_and(|t| !t.is_finite()) {
            return Err(Malformed("scene.timestamp is not a number".into()));
        }
        state.bones.extend(bones);
        if state.reference.is_none() {
            state.reference = reference.flatten();
        }
        Ok(Read::Frame(t))
    }
}

/// The sender's reference, when it names every canonical joint.
fn reference(ext: &Ext) -> Result<Option<Pose>, Malformed> {
    let mut out = [DVec3::ZERO; Canonical::COUNT];
    for (c, n) in ROKOKO_CANONICAL.iter().enumerate() {
        let Some(v) = ext.reference.get(*n) else {
            return Ok(None);
        };
        if !finite(&[v.x, v.y, v.z]) {
            return Err(Malformed(format!("surfmotion.reference.{n}: not a number")));
        }
        out[c] = from_unity(DVec3::new(v.x, v.y, v.z));
    }
    Ok(Some(out))
}

/// One frame as a Rokoko Studio Live datagram: the canonical joints' world
/// transforms (project axes) as the actor's body at time `t`, sent at
/// `fps`; the reference (project axes) added when given.
pub fn encode_frame(
    world: &[Bone; Canonical::COUNT],
    t: f64,
    fps: f64,
    reference: Option<&Pose>,
) -> Result<Vec<u8>, serde_json::Error> {
    encode_actors(&[("surfmotion", world)], t, fps, reference)
}

/// One frame of several actors (name, the canonical joints' world
/// transforms in project axes), in order, as [`encode_frame`] does one.
pub fn encode_actors(
    actors: &[(&str, &[Bone; Canonical::COUNT])],
    t: f64,
    fps: f64,
    reference: Option<&Pose>,
) -> Result<Vec<u8>, serde_json::Error> {
    let actors = actors
        .iter()
        .map(|(name, world)| {
            Ok(Actor {
                name: name.to_string(),
                body: body(world)?,
            })
        })
        .collect::<Result<Vec<_>, serde_json::Error>>()?;
    let v3 = |p: DVec3| V3 {
        x: p.x,
        y: p.y,
        z: p.z,
    };
    let surfmotion = reference.map(|r| Ext {
        reference: r
            .iter()
            .enumerate()
            .map(|(c, p)| (ROKOKO_CANONICAL[c].to_string(), v3(from_unity(*p))))
            .collect(),
    });
    serde_json::to_vec(&Packet {
        version: serde_json::json!(3),
        fps: Some(fps),
        scene: Scene {
            timestamp: Some(t),
            actors,
        },
        surfmotion,
    })
}

/// An actor's body joints as JSON values.
fn body(
    world: &[Bone; Canonical::COUNT],
) -> Result<BTreeMap<String, serde_json::Value>, serde_json::Error> {
    let v3 = |p: DVec3| V3 {
        x: p.x,
        y: p.y,
        z: p.z,
    };
    world
        .iter()
        .enumerate()
        .map(|(c, b)| {
            let u = mirror(*b);
            let j = JointJson {
                position: v3(u.pos),
                rotation: Q {
                    x: u.rot.x,
                    y: u.rot.y,
                    z: u.rot.z,
                    w: u.rot.w,
                },
            };
            Ok((ROKOKO_CANONICAL[c].to_string(), serde_json::to_value(j)?))
        })
        .collect()
}
