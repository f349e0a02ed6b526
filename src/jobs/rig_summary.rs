//! What `rig embed` prints of a [`RigEmbedReport`]: the automatic
//! landmarks (when none were given) with each mark's confidence and how it
//! was found, the landmarks that contradict them, then
//! [`super::text::rig_embed`].

use super::rig::RigEmbedReport;
use std::path::Path;

impl RigEmbedReport {
    /// `rig embed`'s text (`landmarks_written`: where the automatic
    /// landmarks were saved).
    pub fn summary_text(&self, landmarks_written: Option<&Path>) -> String {
        let mut text = String::new();
        if let Some(auto) = &self.automatic {
            text += &format!(
                "landmarks: automatic (confidence {:.2}; up ({:.2}, {:.2}, {:.2}), symmetry fit {:.2}% of the height){}\n",
                auto.confidence,
                auto.up[0],
                auto.up[1],
                auto.up[2],
                auto.symmetry_percent,
                landmarks_written
                    .map(|p| format!(" → {}", p.display()))
                    .unwrap_or_default()
            );
            for (name, m) in &auto.marks {
                text += &format!(
                    "  {name:<10} ({:>8.3}, {:>8.3}, {:>8.3})  confidence {:.2}  {}\n",
                    m.point[0], m.point[1], m.point[2], m.confidence, m.how
                );
            }
        }
        for d in &self.disagreements {
            text += &format!("warning: landmark {}: {}\n", d.landmark, d.reason);
        }
        text + &super::text::rig_embed(self)
    }
}
