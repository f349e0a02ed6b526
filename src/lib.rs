//! # surfmotion
//!
//! Drives 4D performance-capture characters from skeletal motion capture
//! (Huang et al. 2015) and transfers mocap onto static scanned meshes
//! (de Aguiar et al. 2007). Modules follow the pipeline: [`mocap`] (clips),
//! [`rig`] (canonical skeleton), [`mesh`] (meshes, sequences and their file
//! formats), [`inspect`] (what a file holds).

pub mod batch;
pub mod budget;
pub mod db;
pub mod deform;
pub mod eval;
pub mod fsutil;
pub mod graph;
pub mod inspect;
pub mod keyframe;
pub mod mesh;
pub mod mocap;
pub mod render;
pub mod retarget;
pub mod rig;
pub mod similarity;
pub mod skeleton;
pub mod synth;
pub mod transfer;
pub mod web;
