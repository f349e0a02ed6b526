//! `surfmotion live send`: sends a clip as a live stream (BVH over TCP, VMC
//! or Rokoko over UDP), so every input path of `live` can be tested
//! without a suit (issue 45).

use std::path::PathBuf;

/// Arguments of `live send`.
#[derive(clap::Args)]
pub struct SendArgs {
    /// The clip (any format `retarget` reads).
    pub clip: PathBuf,
    /// The receiver.
    #[arg(long, value_name = "ADDR:PORT")]
    pub to: std::net::SocketAddr,
    /// The protocol: bvh (BVH over TCP: the clip's own skeleton), vmc (OSC
    /// over UDP: the canonical joints as Unity humanoid bones, local
    /// transforms) or rokoko (Rokoko Studio Live JSON over UDP: the
    /// canonical joints as its body joints, world transforms). Over UDP the
    /// clip's neutral pose goes along (an extension other receivers ignore),
    /// so `live` takes the same reference as `--replay`.
    #[arg(long, default_value = "bvh", value_parser = ["bvh", "vmc", "rokoko"])]
    pub protocol: String,
    /// Resample the clip to this rate before sending (default: its own).
    #[arg(long, value_name = "FPS", value_parser = super::frame_rate)]
    pub fps: Option<f64>,
    /// Speed: 1 sends at the clip's real rate, 0 as fast as the socket takes.
    #[arg(long, default_value_t = 1.0, value_name = "FACTOR", value_parser = super::non_negative)]
    pub speed: f64,
    #[command(flatten)]
    pub clip_opts: super::opts::ClipOpts,
}

/// Runs `live send`.
pub fn run(a: SendArgs) -> anyhow::Result<()> {
    use surfmotion::live::send::{UdpProtocol, send_bvh, send_udp};
    let load = a.clip_opts.load_options()?;
    let r = match a.protocol.as_str() {
        "vmc" => send_udp(&a.clip, a.to, UdpProtocol::Vmc, &load, a.fps, a.speed)?,
        "rokoko" => send_udp(&a.clip, a.to, UdpProtocol::Rokoko, &load, a.fps, a.speed)?,
        _ => send_bvh(&a.clip, a.to, &load, a.fps, a.speed)?,
    };
    println!(
        "{}",
        surfmotion::jobs::short_text::sent(&r, &a.to, &a.protocol)
    );
    Ok(())
}
