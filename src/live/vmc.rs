//! The VMC protocol (Virtual Motion Capture: OSC over UDP, default port
//! 39539), as VTuber tools, Blender add-ons and many suits' bridges send
//! it. A frame is a bundle (or several) of:
//!
//! - `/VMC/Ext/Root/Pos` name, position, rotation (the avatar's root);
//! - `/VMC/Ext/Bone/Pos` name, position, rotation: a bone's local
//!   transform, named as Unity's `HumanBodyBones` ([`UNITY_BONES`]);
//! - `/VMC/Ext/OK` (the avatar is loaded) and `/VMC/Ext/T` time (seconds),
//!   which end the frame (the time when given, else `OK`).
//!
//! Positions are metres and both in Unity's axes (Y up, left-handed).
//! Other addresses (blend shapes, cameras, trackers) are ignored. The
//! sender may add `/SurfMotion/Ref/Pos` name, position (world) for each
//! canonical joint: its neutral reference, which other receivers ignore and
//! which makes the stream's reference the file's.
//!
//! OSC is read and written with the `rosc` crate.

use super::humanoid::{BodyState, Bone, UNITY_BONES, UNITY_CANONICAL, from_unity, mirror};
use super::stream::{Malformed, Protocol, Read};
use crate::pose::Pose;
use crate::rig::Canonical;
use glam::{DQuat, DVec3};
use rosc::{OscBundle, OscMessage, OscPacket, OscTime, OscType};

/// The VMC default port.
pub const DEFAULT_PORT: u16 = 39539;

/// The address of the reference extension.
pub(crate) const REF_ADDR: &str = "/SurfMotion/Ref/Pos";

/// The VMC protocol's reader.
#[derive(Debug, Default)]
pub struct Vmc {
    /// ClipNeutral joints received so far (complete when all are).
    reference: [Option<DVec3>; Canonical::COUNT],
}

/// What one message says.
enum Said {
    Root(Bone),
    Bone(String, Bone),
    Ref(usize, DVec3),
    Time(f64),
    Ok,
    Other,
}

impl Protocol for Vmc {
    const NAME: &'static str = "VMC (OSC over UDP)";
    const TABLE: super::humanoid::BoneTable = UNITY_BONES;
    const CANONICAL: [&'static str; Canonical::COUNT] = UNITY_CANONICAL;
    const LOCAL: bool = true;

    fn read(&mut self, datagram: &[u8], state: &mut BodyState) -> Result<Read, Malformed> {
        let (_, packet) =
            rosc::decoder::decode_udp(datagram).map_err(|e| Malformed(format!("OSC: {e}")))?;
        let mut said = Vec::new();
        flatten(&packet, &mut |m| {
            said.push(message(m));
        });
        // Every message read before anything is applied.
        let said: Vec<Said> = said.into_iter().collect::<Result<_, _>>()?;
        let (mut time, mut ok) = (None, false);
        for s in said {
            match s {
                Said::Root(b) => state.root = Some(b),
                Said::Bone(n, b) => {
                    state.bones.insert(n, b);
                }
                Said::Ref(c, p) => self.reference[c] = Some(p),
                Said::Time(t) => time = Some(t),
                Said::Ok => ok = true,
                Said::Other => {}
            }
        }
        if state.reference.is_none() && self.reference.iter().all(Option::is_some) {
            state.reference = Some(std::array::from_fn(|c| {
                self.reference[c].unwrap_or_default()
            }));
        }
        Ok(match (time, ok) {
            (Some(t), _) => Read::Frame(Some(t)),
            (None, true) => Read::Frame(None),
            _ => Read::Partial,
        })
    }
}

/// Every message of a packet, bundles opened, in order.
fn flatten(p: &OscPacket, f: &mut dyn FnMut(&OscMessage)) {
    match p {
        OscPacket::Message(m) => f(m),
        OscPacket::Bundle(b) => {
            for c in &b.content {
                flatten(c, f);
            }
        }
    }
}

fn number(a: &OscType) -> Option<f64> {
    let v = match a {
        OscType::Float(x) => f64::from(*x),
        OscType::Double(x) => *x,
        OscType::Int(x) => f64::from(*x),
        _ => return None,
    };
    v.is_finite().then_some(v)
}

/// `name, px, py, pz[, qx, qy, qz, qw]` (Unity axes) as a name and a bone
/// in the project's axes.
fn transform(m: &OscMessage, with_rotation: bool) -> Result<(String, Bone), Malformed> {
    let bad = || Malformed(format!("{}: bad arguments {:?}", m.addr, m.args));
    let Some(OscType::String(name)) = m.args.first() else {
        return Err(bad());
    };
    let n = if with_rotation { 7 } else { 3 };
    let v: Vec<f64> = m
        .args
        .iter()
        .skip(1)
        .take(n)
        .map(number)
        .collect::<Option<_>>()
        .ok_or_else(bad)?;
    if v.len() != n {
        return Err(bad());
    }
    let rot = if with_rotation {
        let q = DQuat::from_xyzw(v[3], v[4], v[5], v[6]);
        let len = q.length();
        if len.is_nan() || len <= 1e-6 {
            return Err(bad());
        }
        q.normalize()
    } else {
        DQuat::IDENTITY
    };
    let b = mirror(Bone {
        pos: DVec3::new(v[0], v[1], v[2]),
        rot,
    });
    Ok((name.clone(), b))
}

/// What one message says.
fn message(m: &OscMessage) -> Result<Said, Malformed> {
    Ok(match m.addr.as_str() {
        "/VMC/Ext/Root/Pos" => Said::Root(transform(m, true)?.1),
        "/VMC/Ext/Bone/Pos" => {
            let (name, b) = transform(m, true)?;
            if UNITY_BONES.iter().any(|(n, _)| *n == name) {
                Said::Bone(name, b)
            } else {
                Said::Other
            }
        }
        REF_ADDR => {
            let (name, b) = transform(m, false)?;
            match UNITY_CANONICAL.iter().position(|n| *n == name) {
                Some(c) => Said::Ref(c, b.pos),
                None => Said::Other,
            }
        }
        "/VMC/Ext/T" => Said::Time(
            m.args
                .first()
                .and_then(number)
                .ok_or_else(|| Malformed(format!("/VMC/Ext/T: bad arguments {:?}", m.args)))?,
        ),
        "/VMC/Ext/OK" => Said::Ok,
        _ => Said::Other,
    })
}

fn transform_message(addr: &str, name: &str, b: Bone) -> OscPacket {
    let u = mirror(b);
    let mut args = vec![OscType::String(name.into())];
    args.extend(
        [
            u.pos.x, u.pos.y, u.pos.z, u.rot.x, u.rot.y, u.rot.z, u.rot.w,
        ]
        .map(|x| OscType::Float(x as f32)),
    );
    OscPacket::Message(OscMessage {
        addr: addr.into(),
        args,
    })
}

/// One frame as a VMC bundle: the root at the origin, the canonical
/// joints' local transforms (project axes; see
/// [`super::humanoid::local_bones`]) as Unity bones, `OK` and the time `t`;
/// the reference (world, project axes) first when given.
pub fn encode_frame(
    local: &[Bone; Canonical::COUNT],
    t: f64,
    reference: Option<&Pose>,
) -> Result<Vec<u8>, rosc::OscError> {
    let mut content = Vec::with_capacity(2 * Canonical::COUNT + 3);
    if let Some(r) = reference {
        for (c, p) in r.iter().enumerate() {
            let u = from_unity(*p);
            content.push(OscPacket::Message(OscMessage {
                addr: REF_ADDR.into(),
                args: vec![
                    OscType::String(UNITY_CANONICAL[c].into()),
                    OscType::Float(u.x as f32),
                    OscType::Float(u.y as f32),
                    OscType::Float(u.z as f32),
                ],
            }));
        }
    }
    let origin = Bone {
        pos: DVec3::ZERO,
        rot: DQuat::IDENTITY,
    };
    content.push(transform_message("/VMC/Ext/Root/Pos", "root", origin));
    for (c, b) in local.iter().enumerate() {
        content.push(transform_message(
            "/VMC/Ext/Bone/Pos",
            UNITY_CANONICAL[c],
            *b,
        ));
    }
    content.push(OscPacket::Message(OscMessage {
        addr: "/VMC/Ext/OK".into(),
        args: vec![OscType::Int(1)],
    }));
    content.push(OscPacket::Message(OscMessage {
        addr: "/VMC/Ext/T".into(),
        args: vec![OscType::Float(t as f32)],
    }));
    rosc::encoder::encode(&OscPacket::Bundle(OscBundle {
        timetag: OscTime {
            seconds: 0,
            fractional: 1,
        },
        content,
    }))
}
