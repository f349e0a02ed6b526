//! Which seed's extremities to keep ([`super::centre::TipSeed::Guarded`],
//! session 37): those sought from the vertex nearest the centroid
//! (sessions 20-36's) unless a measured sign says that seed is wrong,
//! then those sought from the geodesic centre ([`super::centre`]).
//!
//! The centroid's vertex is a wrong seed in two ways measured so far
//! (`autorig_eval … tips`: every frame of samba, crane and samba without
//! hands as the rest; `embed::auto_branches`):
//! - **it lies on a limb's end**: with a hand held at the body's centre
//!   (samba's frames 127-173) the vertex nearest the centroid is on the
//!   hand, which is then no extremity. Read as the least geodesic
//!   distance from the centroid's vertex to one of the five tips found
//!   from the centre, over the fifth of those tips' reach
//!   ([`Guard::seed_to_tip`]): 0.05-0.06 on samba's 47 frames whose tips
//!   from the centroid's vertex are wrong, 0.85-1.07 on the 478 frames of
//!   samba, crane and samba without hands whose tips are right (session
//!   37). The line, [`SEED_ON_TIP`], is a quarter: the seed lies on the
//!   last quarter of a branch;
//! - **it hides a sixth limb**: a tail grown near the centroid's vertex
//!   reaches little from it (the procedural body's tail of 20 % of the
//!   height: under the sixth's limit from the centroid, 91 % of the fifth
//!   from the centre). A sixth branch found from the centre alone is
//!   believed when it scores (detour less disc ratio,
//!   [`super::branches`]) at least as high as the least of the five tips
//!   found with it: it is as much a tip as the limbs' ends are. The one
//!   sixth from the centre on the captures (samba without hands, frame
//!   48) scores −0.28, its five from 0.26: not believed.
//!
//! Otherwise the centroid's are kept, so that a body whose centroid lies
//! in its trunk rigs exactly as before (on 478 of the 525 frames above
//! the guard keeps them, and on none of those are they wrong).

/// The centroid's vertex lies on a limb's end when one of the five tips
/// found from the centre is nearer it along the surface than this
/// fraction of their fifth reach (the measures: the module's).
pub const SEED_ON_TIP: f64 = 0.25;

/// What the guard measured and kept.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Guard {
    /// The geodesic centre's vertex.
    pub centre: u32,
    /// The least geodesic distance from the centroid's vertex to one of
    /// the five tips found from the centre, over the fifth of their reach
    /// (infinite when none was found).
    pub seed_to_tip: f64,
    /// The score of the sixth branch found from the centroid's vertex.
    pub centroid_sixth: Option<f64>,
    /// The score of the sixth branch found from the centre.
    pub centre_sixth: Option<f64>,
    /// The least score of the five tips found from the centre (infinite
    /// when none).
    pub centre_least: f64,
    /// The centre's tips were kept.
    pub kept_centre: bool,
}

impl Guard {
    /// The guard's verdict on its measures: the centre's tips when the
    /// centroid's vertex lies on a limb's end, or when a sixth branch is
    /// found from the centre alone and scores as a tip does.
    pub fn decide(
        centre: u32,
        seed_to_tip: f64,
        centroid_sixth: Option<f64>,
        centre_sixth: Option<f64>,
        centre_least: f64,
    ) -> Guard {
        let on_tip = seed_to_tip < SEED_ON_TIP;
        let hidden_sixth =
            centroid_sixth.is_none() && centre_sixth.is_some_and(|s| s >= centre_least);
        Guard {
            centre,
            seed_to_tip,
            centroid_sixth,
            centre_sixth,
            centre_least,
            kept_centre: on_tip || hidden_sixth,
        }
    }

    /// Why the centre's tips were kept (`None` when they were not).
    pub fn why(&self) -> Option<String> {
        if !self.kept_centre {
            return None;
        }
        Some(if self.seed_to_tip < SEED_ON_TIP {
            format!(
                "the vertex nearest the centroid lies on a limb's end ({:.0}% of the fifth extremity's reach from it, under {:.0}%): the extremities sought from the body's geodesic centre",
                100.0 * self.seed_to_tip,
                100.0 * SEED_ON_TIP
            )
        } else {
            format!(
                "a sixth branch seen from the body's geodesic centre scores as a tip ({:.2}, the five from {:.2}) though the centroid's vertex hides it",
                self.centre_sixth.unwrap_or(f64::NAN),
                self.centre_least
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_centre_is_kept_only_on_a_sign() {
        // A seed in the trunk, no sixth either way: the centroid's.
        let g = Guard::decide(7, 0.9, None, None, 0.1);
        assert!(!g.kept_centre && g.why().is_none());
        // On a hand: the centre's.
        let g = Guard::decide(7, 0.05, None, None, 0.1);
        assert!(g.kept_centre && g.why().unwrap().contains("limb's end"));
        // A sixth from the centre alone: believed when it scores as the
        // five do, not when it only clears the margin.
        assert!(Guard::decide(7, 0.9, None, Some(0.5), 0.1).kept_centre);
        assert!(!Guard::decide(7, 0.9, None, Some(-0.28), 0.1).kept_centre);
        // A sixth from the centroid is its own refusal: kept.
        assert!(!Guard::decide(7, 0.9, Some(0.2), Some(0.5), 0.1).kept_centre);
        let g = Guard::decide(7, 0.9, None, Some(0.5), 0.1);
        assert!(g.why().unwrap().contains("sixth"), "{:?}", g.why());
    }
}
