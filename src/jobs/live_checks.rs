//! `live`'s checks before the session starts: the addresses other
//! machines can reach, said; a recording that would replace an input,
//! refused.

use super::outputs::{OutputError, check_mesh_output, database_inputs, refuse_colliding};
use std::net::SocketAddr;
use std::path::Path;

/// A warning for each of `addrs` that is not a loopback address (the
/// stream and page ports listen there for any machine).
pub fn exposed(addrs: impl IntoIterator<Item = SocketAddr>) -> Vec<String> {
    addrs
        .into_iter()
        .filter(|addr| !addr.ip().is_loopback())
        .map(|addr| {
            format!(
                "warning: listening on {addr}, which other machines can reach (127.0.0.1 keeps it on this one)"
            )
        })
        .collect()
}

/// Refuses a recording `out` that is not a mesh output, or that would
/// replace a file of the database `db`, the replayed clip or the rig map.
pub fn check_record(
    out: &Path,
    db: &Path,
    replay: Option<&Path>,
    rig_map: Option<&Path>,
) -> Result<(), OutputError> {
    check_mesh_output(out)?;
    let mut inputs = database_inputs(db);
    inputs.extend(replay.map(Path::to_path_buf));
    inputs.extend(rig_map.map(Path::to_path_buf));
    let outputs: Vec<_> = crate::mesh::io::output_files(out)
        .into_iter()
        .map(|p| ("-o", p))
        .collect();
    refuse_colliding(&inputs, &outputs)
}
