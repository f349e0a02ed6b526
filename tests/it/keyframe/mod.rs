//! Key-frame animation (Huang 5.1): the search, the memory budget, the smoothness floor and optimum.

mod budget;
mod floor;
mod search;
mod smoothest;
