//! The command line's mirrors of the library's option enums. The library
//! does not depend on clap; each mirror has the same variants, value names
//! and help (the variants' doc comments) as the library type, and converts
//! into it with `From`.

use surfmotion::batch::Format;
use surfmotion::deform::DeformMode;
use surfmotion::embed::frames::SkeletonKind;
use surfmotion::live::Overlap;
use surfmotion::similarity::Measure;
use surfmotion::synth::Gait;

use super::mirror::mirror;

/// A frame dissimilarity measure ([`Measure`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MeasureArg {
    /// 3D volumetric shape histogram, minimised over rotation about the
    /// vertical (Eq. 1).
    Shape,
    /// Vertex positions and velocities after floor alignment (Casas 2013).
    Vertex,
    /// Canonical joint positions after floor alignment (Eq. 28); needs a rig.
    Skeleton,
    /// 6D shape-colour histogram with a pyramid EMD (Sec. 4.1); needs
    /// vertex colours.
    Colour,
}

/// How joints are read off a frame ([`SkeletonKind`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SkeletonKindArg {
    /// The character's rigid skeleton (bone lengths calibrated over the
    /// database) posed per frame nearest the regressor joints.
    Rigid,
    /// Affine regressors: exact on the rest frame, rigid-motion equivariant.
    Regressor,
    /// Plain centres of each joint's vertex set (Huang et al. 2015, Sec. 3).
    Centroid,
}

/// Which procedural motion ([`Gait`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum GaitArg {
    /// Walk straight ahead at 1.4 m/s.
    Walk,
    /// Run straight ahead at 3.2 m/s.
    Run,
    /// Walk along a circle of 2 m radius.
    Turn,
}

/// Output format of a batch ([`Format`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FormatArg {
    /// Binary glTF with one morph target per frame.
    Glb,
    /// PC2 point cache with its topology OBJ beside it.
    Pc2,
    /// A folder of OBJ frames.
    Obj,
    /// USD text layer (time-sampled points), one `.usda` per clip.
    Usda,
}

/// How retrieved frames are made to follow the query skeleton
/// ([`DeformMode`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum DeformModeArg {
    /// Part-based PCA Laplacian deformation (the paper's method).
    Part,
    /// One PCA Laplacian deformation space for the whole body.
    Global,
    /// Plain linear blend skinning of the retrieved frame.
    Lbs,
    /// No deformation: the interpolated retrieval.
    None,
}

/// When `live` deforms two frames at once ([`Overlap`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum OverlapArg {
    /// One frame at a time.
    Off,
    /// Two at once while frames queue.
    Queued,
    /// Every frame held for the next.
    Always,
}

mirror!(MeasureArg, Measure, Shape, Vertex, Skeleton, Colour);
mirror!(SkeletonKindArg, SkeletonKind, Rigid, Regressor, Centroid);
mirror!(GaitArg, Gait, Walk, Run, Turn);
mirror!(FormatArg, Format, Glb, Pc2, Obj, Usda);
mirror!(DeformModeArg, DeformMode, Part, Global, Lbs, None);
mirror!(OverlapArg, Overlap, Off, Queued, Always);

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum;

    /// Every mirror accepts exactly the names the library type had, and
    /// each converts to the library variant of the same name.
    #[test]
    fn cli_value_enums_mirror_the_library_enums() {
        for m in MeasureArg::value_variants() {
            let name = m.to_possible_value().unwrap().get_name().to_string();
            assert_eq!(Measure::from(*m).name(), name);
        }
        assert_eq!(MeasureArg::value_variants().len(), 4);
        for g in GaitArg::value_variants() {
            let name = g.to_possible_value().unwrap().get_name().to_string();
            assert_eq!(Gait::from(*g).name(), name);
        }
        assert_eq!(GaitArg::value_variants().len(), Gait::ALL.len());
        for k in SkeletonKindArg::value_variants() {
            let name = k.to_possible_value().unwrap().get_name().to_string();
            let lib = serde_json::to_value(SkeletonKind::from(*k)).unwrap();
            assert_eq!(lib, serde_json::json!(name));
        }
        for d in DeformModeArg::value_variants() {
            let name = d.to_possible_value().unwrap().get_name().to_string();
            let lib = serde_json::to_value(DeformMode::from(*d)).unwrap();
            assert_eq!(lib, serde_json::json!(name));
        }
        for f in FormatArg::value_variants() {
            let name = f.to_possible_value().unwrap().get_name().to_string();
            let lib = serde_json::to_value(Format::from(*f)).unwrap();
            // Format serialises with its variant name (`Glb`).
            assert_eq!(lib.as_str().map(str::to_lowercase), Some(name));
        }
        for o in OverlapArg::value_variants() {
            let name = o.to_possible_value().unwrap().get_name().to_string();
            assert_eq!(format!("{:?}", Overlap::from(*o)).to_lowercase(), name);
        }
        assert_eq!(OverlapArg::value_variants().len(), 3);
    }
}
