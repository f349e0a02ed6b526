//! Rig embedding on a mesh: landmarks, parts, joints, regressors.

mod bodies;
mod captures;
mod placement;
mod scan_auto;
