//! The pose kernel: a clip's poses on a character's skeleton (feet, toes, chest, ground, placement, neutral frame).

mod anchor;
mod character_neutral;
mod chest;
mod data_floor;
mod feet;
mod footfall;
mod footfall_query;
mod ground;
mod level;
mod level_variants;
mod placement;
mod stride;
mod toes;
mod travel;
mod two_files;
