//! [`Embedding`]'s read access and its checked construction from parts
//! (issue 40: validated constructors instead of public fields). The fields
//! are private to the crate; a caller reads them through the accessors and
//! builds or edits an embedding through [`EmbeddingParts`], which
//! [`Embedding::from_parts`] checks for the invariant every consumer relies
//! on (one label and one skin entry per vertex, one regressor per joint,
//! every index in range). A file is read through the same check
//! ([`Embedding::parse`]).

use super::embedding::Embedding;
use super::parts::Part;
use super::regress::Regressor;
use crate::rig::Canonical;
use serde::Deserialize;

/// The fields of an [`Embedding`], public, for a caller that builds or edits
/// one (a test's faulty rig, a tool's hand-made embedding) and gets back an
/// embedding that holds the invariant again, or the reason it does not. The
/// meaning of each field is its accessor's on [`Embedding`].
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct EmbeddingParts {
    /// [`Embedding::vertex_count`].
    pub vertex_count: usize,
    /// [`Embedding::joints`].
    pub joints: [[f64; 3]; Canonical::COUNT],
    /// [`Embedding::head_top`].
    pub head_top: [f64; 3],
    /// [`Embedding::hand_tips`].
    pub hand_tips: [[f64; 3]; 2],
    /// [`Embedding::toe_tips`].
    pub toe_tips: [[f64; 3]; 2],
    /// [`Embedding::up`].
    pub up: [f64; 3],
    /// [`Embedding::facing`].
    pub facing: [f64; 3],
    /// [`Embedding::left`].
    pub left: [f64; 3],
    /// [`Embedding::height`].
    pub height: f64,
    /// [`Embedding::labels`].
    pub labels: Vec<u8>,
    /// [`Embedding::regions`].
    pub regions: Vec<Vec<u32>>,
    /// [`Embedding::skin`].
    pub skin: Vec<([u8; 4], [f64; 4])>,
    /// [`Embedding::regressors`].
    pub regressors: Vec<Regressor>,
    /// [`Embedding::notes`].
    pub notes: Vec<String>,
    /// [`Embedding::absent`].
    #[serde(default)]
    pub absent: Vec<String>,
}

impl TryFrom<EmbeddingParts> for Embedding {
    type Error = String;

    fn try_from(p: EmbeddingParts) -> Result<Embedding, String> {
        Embedding::from_parts(p)
    }
}

impl Embedding {
    /// An embedding from its parts, checked: one label and one skin entry
    /// per vertex, one regressor per joint with as many weights as
    /// vertices, every vertex, part and joint index in range, the height
    /// positive and finite. The error says which.
    pub fn from_parts(p: EmbeddingParts) -> Result<Embedding, String> {
        check_parts(&p)?;
        Ok(Embedding {
            vertex_count: p.vertex_count,
            joints: p.joints,
            head_top: p.head_top,
            hand_tips: p.hand_tips,
            toe_tips: p.toe_tips,
            up: p.up,
            facing: p.facing,
            left: p.left,
            height: p.height,
            labels: p.labels,
            regions: p.regions,
            skin: p.skin,
            regressors: p.regressors,
            notes: p.notes,
            absent: p.absent,
        })
    }

    /// The embedding's fields, for editing ([`Embedding::from_parts`]).
    pub fn into_parts(self) -> EmbeddingParts {
        EmbeddingParts {
            vertex_count: self.vertex_count,
            joints: self.joints,
            head_top: self.head_top,
            hand_tips: self.hand_tips,
            toe_tips: self.toe_tips,
            up: self.up,
            facing: self.facing,
            left: self.left,
            height: self.height,
            labels: self.labels,
            regions: self.regions,
            skin: self.skin,
            regressors: self.regressors,
            notes: self.notes,
            absent: self.absent,
        }
    }

    /// The embedding with `edit` applied to its parts, checked again.
    pub fn edited(self, edit: impl FnOnce(&mut EmbeddingParts)) -> Result<Embedding, String> {
        let mut p = self.into_parts();
        edit(&mut p);
        Embedding::from_parts(p)
    }

    /// Number of vertices of the mesh it was made for.
    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    /// Rest-frame joint positions, in [`Canonical::ALL`] order.
    pub fn joints(&self) -> &[[f64; 3]; Canonical::COUNT] {
        &self.joints
    }

    /// Top of the head.
    pub fn head_top(&self) -> [f64; 3] {
        self.head_top
    }

    /// Left and right hand tips.
    pub fn hand_tips(&self) -> [[f64; 3]; 2] {
        self.hand_tips
    }

    /// Left and right toe tips.
    pub fn toe_tips(&self) -> [[f64; 3]; 2] {
        self.toe_tips
    }

    /// Up direction of the rest frame.
    pub fn up(&self) -> [f64; 3] {
        self.up
    }

    /// Facing direction of the rest frame.
    pub fn facing(&self) -> [f64; 3] {
        self.facing
    }

    /// The character's left in the rest frame.
    pub fn left(&self) -> [f64; 3] {
        self.left
    }

    /// Height of the rest frame along [`Embedding::up`].
    pub fn height(&self) -> f64 {
        self.height
    }

    /// Part of each vertex ([`Part::ALL`] index); every part one connected
    /// region.
    pub fn labels(&self) -> &[u8] {
        &self.labels
    }

    /// Overlapping region of each part (vertex lists, [`Part::ALL`] order).
    pub fn regions(&self) -> &[Vec<u32>] {
        &self.regions
    }

    /// Skin: up to four (joint index, weight) per vertex, weights summing
    /// to 1.
    pub fn skin(&self) -> &[([u8; 4], [f64; 4])] {
        &self.skin
    }

    /// One regressor per joint, [`Canonical::ALL`] order.
    pub fn regressors(&self) -> &[Regressor] {
        &self.regressors
    }

    /// What was assumed while embedding.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// The body ends the mesh lacks (`head` for a headless body); empty for
    /// a whole body.
    pub fn absent(&self) -> &[String] {
        &self.absent
    }
}

/// [`Embedding::from_parts`]'s check.
fn check_parts(p: &EmbeddingParts) -> Result<(), String> {
    let n = p.vertex_count;
    if p.labels.len() != n || p.skin.len() != n {
        return Err(format!(
            "inconsistent sizes: {n} vertices, {} labels, {} skin entries",
            p.labels.len(),
            p.skin.len()
        ));
    }
    if p.regressors.len() != Canonical::COUNT {
        return Err(format!(
            "inconsistent sizes: {} regressors for {} joints",
            p.regressors.len(),
            Canonical::COUNT
        ));
    }
    if !(p.height.is_finite() && p.height > 0.0) {
        return Err(format!("the height {} is not a positive length", p.height));
    }
    let in_range = |v: &u32| (*v as usize) < n;
    if let Some(j) = p
        .regressors
        .iter()
        .position(|r| r.vertices.len() != r.weights.len() || !r.vertices.iter().all(in_range))
    {
        return Err(format!(
            "an index is out of range: the regressor of joint {} (its vertices and weights, {n} vertices)",
            Canonical::ALL[j].name()
        ));
    }
    if let Some(k) = p.regions.iter().position(|r| !r.iter().all(in_range)) {
        return Err(format!(
            "an index is out of range: region {k} names a vertex beyond {n}"
        ));
    }
    if let Some(v) = p.labels.iter().position(|&l| l as usize >= Part::COUNT) {
        return Err(format!(
            "an index is out of range: vertex {v}'s part {} (there are {})",
            p.labels[v],
            Part::COUNT
        ));
    }
    if let Some(v) = p
        .skin
        .iter()
        .position(|(j, _)| j.iter().any(|&x| x as usize >= Canonical::COUNT))
    {
        return Err(format!(
            "an index is out of range: vertex {v}'s skin names a joint beyond {}",
            Canonical::COUNT
        ));
    }
    Ok(())
}

impl Embedding {
    /// The embedding of a mesh without its vertices in no triangle
    /// ([`super::stray::Compact`]) as the whole mesh's: each such vertex
    /// with its carrier's label, skin and regions; the regressors' vertices
    /// numbered back.
    pub(crate) fn with_stray(
        self,
        c: &super::stray::Compact,
    ) -> Result<Embedding, super::embedding::EmbedError> {
        let n = c.vertex_count();
        let mut p = self.into_parts();
        p.labels = c.spread(&p.labels, 0u8);
        p.skin = c.spread(&p.skin, ([0u8; 4], [1.0, 0.0, 0.0, 0.0]));
        let mut member = vec![false; n];
        for r in &mut p.regions {
            member.fill(false);
            for &v in r.iter() {
                member[c.old(v) as usize] = true;
            }
            for &(s, k) in c.stray().pairs() {
                member[s as usize] = member[k as usize];
            }
            *r = (0..n as u32).filter(|&v| member[v as usize]).collect();
        }
        for g in &mut p.regressors {
            g.vertices.iter_mut().for_each(|v| *v = c.old(*v));
        }
        p.vertex_count = n;
        p.notes.push(format!(
            "{} vertices in no triangle: the rig embedded without them, each given the part and skin of its nearest vertex in a triangle",
            c.stray().len()
        ));
        Embedding::from_parts(p).map_err(|e| {
            super::embedding::EmbedError::Mesh(format!(
                "with its vertices in no triangle given their carriers' rig: {e}"
            ))
        })
    }
}
