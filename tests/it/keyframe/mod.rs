//! Key-frame animation (Huang 5.1): the search, the memory budget, the smoothness floor and optimum, synthesis on the prepared blender.

mod budget;
mod floor;
mod prepared;
mod search;
mod smoothest;
