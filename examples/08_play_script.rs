//! Tutorial 8: parametric motion (Casas et al. 2013, Sec. 3): a database's
//! `[[space]]` motion spaces (declared in its `character.toml`, README
//! "Parametric motion") steered by a script of timed requests, e.g.
//! `[{"t": 0, "space": "locomotion", "speed": 1.4}, {"t": 2, "speed": 2.5}]`;
//! the model is built and cached on first use, frames are written as made.
//!
//! cargo run --release --example 08_play_script -- gaits control.json session.pc2

use surfmotion::jobs::play::{PlayOptions, play_session};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let [db, script, out] = &a[..] else {
        return Err("usage: 08_play_script DB_DIR SCRIPT.json OUT".into());
    };
    let opts = PlayOptions::default(); // the session: the last request + 2 s
    let (db, script, out) = (db.as_ref(), script.as_ref(), out.as_ref());
    let r = play_session(db, script, out, &opts, &mut |_| {})?.report;
    println!("{} frames, {} transitions", r.frames, r.transitions.len());
    Ok(())
}
