//! Canonical mapping: any humanoid clip's joints onto the canonical skeleton.

mod families;
mod fbx_character;
mod mapping;
