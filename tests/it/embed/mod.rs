//! Rig embedding on a mesh: landmarks, parts, joints, regressors.

mod auto;
mod bodies;
mod captures;
mod contact;
mod contradict;
mod partial;
mod placement;
mod scan_auto;
