//! What `transfer` prints of a [`TransferReport`]: its JSON summary and
//! its text, the automatic landmarks (when neither landmarks nor markers
//! were given) first.

use super::{JobError, TransferReport};
use std::path::Path;

impl TransferReport {
    /// `transfer --json`: [`TransferReport::short_json`] with the
    /// automatic landmarks used.
    pub fn summary_json(&self) -> Result<serde_json::Value, JobError> {
        let mut v = self.short_json()?;
        if let (Some(auto), Some(o)) = (&self.automatic_landmarks, v.as_object_mut()) {
            o.insert("automatic_landmarks".into(), serde_json::to_value(auto)?);
        }
        Ok(v)
    }

    /// `transfer`'s text for `scan` (`truth`: the sequence the error was
    /// measured against; `landmarks_written`: where the automatic
    /// landmarks were saved): the automatic landmarks' confidence and
    /// symmetry fit, then [`super::text::transfer`].
    pub fn summary_text(
        &self,
        scan: &str,
        truth: Option<&str>,
        landmarks_written: Option<&Path>,
    ) -> String {
        let mut text = String::new();
        if let Some(auto) = &self.automatic_landmarks {
            text += &format!(
                "landmarks: automatic (confidence {:.2}; symmetry fit {:.2}% of the height){}\n",
                auto.confidence,
                auto.symmetry_percent,
                landmarks_written
                    .map(|p| format!(" → {}", p.display()))
                    .unwrap_or_default()
            );
        }
        text + &super::text::transfer(scan, truth, self)
    }
}
