//! `--replay CLIP`: a clip file played as a stream at its real frame rate
//! (or `speed` times it; 0 as fast as the session takes frames), `loops`
//! times over (the sender's frame number and the stream's clock go on
//! across the loops, the clip starting again from its first frame). When
//! the session falls behind, the frames already due but older than the
//! newest are dropped (newest wins) and counted.

use super::report::Counters;
use super::source::{Event, Incoming, Source, SourceError};
use crate::drive::query::ClipQuery;
use crate::pose::retarget::ClipNeutral;
use std::time::{Duration, Instant};

/// A clip played as a stream.
pub struct Replay {
    clip: ClipQuery,
    speed: f64,
    /// Frames to play in all (the clip's length times the loops).
    total: usize,
    next: usize,
    start: Option<Instant>,
    counters: Counters,
}

impl Replay {
    /// Plays `clip` (canonical poses at the database's rate, from
    /// [`crate::drive::query::load_mocap`]) at `speed` times its rate (0:
    /// no waiting), `loops` times over (at least once).
    pub fn new(clip: ClipQuery, speed: f64, loops: usize) -> Replay {
        let total = clip.poses.len().saturating_mul(loops.max(1));
        Replay {
            total,
            clip,
            speed: if speed.is_finite() && speed > 0.0 {
                speed
            } else {
                0.0
            },
            next: 0,
            start: None,
            counters: Counters::default(),
        }
    }

    /// When frame `k` is due.
    fn due(&self, start: Instant, k: usize) -> Instant {
        start + Duration::from_secs_f64(k as f64 / (self.clip.fps * self.speed))
    }
}

impl Source for Replay {
    fn next(&mut self, wait: Duration) -> Result<Event, SourceError> {
        if self.next >= self.total {
            return Ok(Event::End);
        }
        let now = Instant::now();
        let arrived = if self.speed == 0.0 {
            now
        } else {
            let start = *self.start.get_or_insert(now);
            // Newest wins: skip frames whose successor is already due.
            while self.next + 1 < self.total && self.due(start, self.next + 1) <= now {
                self.next += 1;
                self.counters.dropped += 1;
            }
            let due = self.due(start, self.next);
            if due > now {
                if due - now > wait {
                    std::thread::sleep(wait);
                    return Ok(Event::Idle);
                }
                std::thread::sleep(due - now);
            }
            due
        };
        let k = self.next;
        let i = k % self.clip.poses.len();
        self.next += 1;
        self.counters.received += 1;
        Ok(Event::Frame(Incoming {
            seq: k as u64,
            pose: self.clip.poses[i],
            rotations: self.clip.reference.rotations.get(i).copied(),
            arrived,
        }))
    }

    fn reference(&self) -> Option<ClipNeutral> {
        Some(self.clip.reference.without_rotations())
    }

    fn counters(&self) -> Counters {
        self.counters
    }

    fn waiting(&self) -> bool {
        self.next < self.total
            && match self.start {
                _ if self.speed == 0.0 => true,
                Some(start) => self.due(start, self.next) <= Instant::now(),
                None => false,
            }
    }
}
