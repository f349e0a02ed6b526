//! The setup report of `db init` ([`Setup`]) as text, as the CLI prints
//! it: the rest frame and why, the contacts, the parts' rigidity and the
//! regions that follow another part, the rig's notes and warnings.

use super::db_init::{ContactReport, Setup};

impl Setup {
    /// The report as `db init` prints it (one line each; warnings start
    /// with `WARN`).
    pub fn text(&self) -> String {
        let s = self;
        let mut out = format!("rest frame: {} ({})\n", s.rest_frame, s.why);
        let contacts = |list: &[ContactReport]| {
            list.iter()
                .map(|c| {
                    format!(
                        "{} ({} vertices, gap {:.3})",
                        c.parts.join(" ↔ "),
                        c.vertices,
                        c.gap
                    )
                })
                .collect::<Vec<_>>()
                .join("; ")
        };
        if !s.topology_contacts.is_empty() {
            out += &format!(
                "contacts on the topology's frame: {}\n",
                contacts(&s.topology_contacts)
            );
        }
        if !s.rest_contacts.is_empty() {
            out += &format!(
                "contacts on the rest frame: {}\n",
                contacts(&s.rest_contacts)
            );
        }
        if s.frames_examined > 0 {
            // The topology's positions are examined as a frame of their
            // own, before every sequence's.
            let which = match s.contact_frames.len() {
                0 => String::new(),
                n if n <= 12 => format!(": {}", s.contact_frames.join(", ")),
                n => format!(": {}, … ({n} runs)", s.contact_frames[..12].join(", ")),
            };
            out += &format!(
                "frames with a contact: {} of {} (the topology and {} frames of the sequences){which}\n",
                s.frames_in_contact,
                s.frames_examined,
                s.frames_examined - 1
            );
        }
        let worst = s
            .rigidity
            .iter()
            .max_by(|a, b| a.rms_percent.total_cmp(&b.rms_percent));
        if let Some(w) = worst {
            out += &format!(
                "part rigidity: the least rigid part is {} ({:.1} % of the height rms off one rigid motion)\n",
                w.part, w.rms_percent
            );
        }
        for p in &s.rigidity {
            for st in &p.stray {
                let shown: Vec<String> = st.vertices.iter().take(8).map(u32::to_string).collect();
                out += &format!(
                    "WARN part {}: {} vertices follow {} instead (vertices {}{}; frames {:?})\n",
                    p.part,
                    st.vertices.len(),
                    st.follows,
                    shown.join(", "),
                    if st.vertices.len() > 8 { ", …" } else { "" },
                    st.frames
                );
            }
        }
        // A missing head is said once: the checks skipped and the chin
        // placed, on one line (none when the automatic rig said it).
        let no_head = |n: &&String| n.starts_with("no head: ");
        for n in s.rig_notes.iter().filter(|n| !no_head(n)) {
            out += &format!("rig: {n}\n");
        }
        for k in s.check.skipped.iter().filter(|n| !no_head(n)) {
            out += &format!("rig: {k}\n");
        }
        let head: Vec<&str> = (s.check.skipped.iter().filter(no_head))
            .chain(s.rig_notes.iter().filter(no_head))
            .map(|n| n.trim_start_matches("no head: "))
            .collect();
        if !head.is_empty() && !s.head_said {
            out += &format!("rig: no head: {}\n", head.join("; "));
        }
        for w in &s.check.warnings {
            out += &format!("WARN rig: {}\n", w.message);
        }
        if let Some(p) = &s.png {
            out += &format!("wrote {}\n", p.display());
        }
        out += &format!("wrote {}", s.path.display());
        out
    }
}
