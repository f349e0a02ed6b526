//! Rig embedding on a mesh: landmarks, parts, joints, regressors.

mod auto;
mod auto_arms;
mod auto_branches;
mod auto_contact;
mod auto_facing;
mod auto_hands;
mod auto_headless;
mod auto_held;
mod auto_kit;
mod auto_knees;
mod auto_order;
mod auto_settle;
mod auto_sides;
mod auto_straddle;
mod auto_vertex_order;
mod bodies;
mod captures;
mod contact;
mod contradict;
mod motion_rest;
mod motion_skin;
mod motion_tears;
mod partial;
mod placement;
mod renumber;
mod scan_auto;
