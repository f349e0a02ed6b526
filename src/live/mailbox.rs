//! The hand-off between a network receiver thread and the session: one
//! slot, the newest frame wins (a frame replaced before the session took it
//! is counted as dropped), so a flood of packets holds one frame of memory.

use super::report::Counters;
use super::source::{Event, Incoming, Source, SourceError};
use crate::pose::retarget::ClipNeutral;
use std::net::SocketAddr;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Duration;

#[derive(Default)]
struct State {
    slot: std::collections::VecDeque<Incoming>,
    lossless: bool,
    last_seq: Option<u64>,
    reference: Option<ClipNeutral>,
    counters: Counters,
    closed: bool,
}

/// One frame slot shared by a receiver and the session.
#[derive(Default)]
pub struct Mailbox {
    state: Mutex<State>,
    ready: Condvar,
}

/// Frames a lossless mailbox holds at most (then the oldest is dropped).
pub(crate) const LOSSLESS_CAP: usize = 100_000;

impl Mailbox {
    /// A mailbox where no frame replaces another: every frame is taken in
    /// order (latency grows when the session is slower than the stream),
    /// up to [`LOSSLESS_CAP`] frames waiting.
    pub fn lossless() -> Mailbox {
        let m = Mailbox::default();
        m.lock().lossless = true;
        m
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Puts a frame: a sender number already seen is a duplicate, an older
    /// one late (both ignored); a gap counts the missing frames as dropped;
    /// a frame not yet taken is replaced (dropped).
    pub fn put(&self, f: Incoming) {
        let mut s = self.lock();
        if let Some(last) = s.last_seq {
            if f.seq == last {
                s.counters.duplicated += 1;
                return;
            }
            if f.seq < last {
                s.counters.late += 1;
                return;
            }
            s.counters.dropped += f.seq - last - 1;
        }
        s.last_seq = Some(f.seq);
        s.counters.received += 1;
        let cap = if s.lossless { LOSSLESS_CAP } else { 1 };
        while s.slot.len() >= cap {
            s.slot.pop_front();
            s.counters.dropped += 1;
        }
        s.slot.push_back(f);
        self.ready.notify_one();
    }

    /// The next frame, waiting at most `wait`.
    pub fn next(&self, wait: Duration) -> Result<Event, SourceError> {
        let mut s = self.lock();
        if s.slot.is_empty() {
            s = self
                .ready
                .wait_timeout(s, wait)
                .map(|(g, _)| g)
                .unwrap_or_else(|e| e.into_inner().0);
        }
        Ok(match s.slot.pop_front() {
            Some(f) => Event::Frame(f),
            None => Event::Idle,
        })
    }

    /// Updates the counters.
    pub fn count(&self, f: impl FnOnce(&mut Counters)) {
        f(&mut self.lock().counters);
    }

    /// True when a frame is waiting to be taken.
    pub fn waiting(&self) -> bool {
        !self.lock().slot.is_empty()
    }

    /// The counters.
    pub fn counters(&self) -> Counters {
        self.lock().counters
    }

    /// The stream's reference, once decided.
    pub fn reference(&self) -> Option<ClipNeutral> {
        self.lock().reference.clone()
    }

    /// Sets the stream's reference.
    pub fn set_reference(&self, r: ClipNeutral) {
        self.lock().reference = Some(r);
    }

    /// Asks the receiver to stop.
    pub fn close(&self) {
        self.lock().closed = true;
    }

    /// True once closed.
    pub fn closed(&self) -> bool {
        self.lock().closed
    }
}

/// A [`Source`] fed by a receiving thread through a [`Mailbox`]: the
/// network sources (BVH over TCP, VMC and Rokoko over UDP) are each a
/// listener on an address and one of these. Dropping it closes the
/// mailbox, which ends the thread at its next frame.
pub struct Fed {
    mailbox: Arc<Mailbox>,
    addr: SocketAddr,
}

impl Fed {
    /// Starts `receive` on a thread of its own with a new mailbox
    /// ([`Mailbox::lossless`] with `lossless`, else newest wins); `addr`
    /// is the address it listens on.
    pub fn spawn(
        addr: SocketAddr,
        lossless: bool,
        receive: impl FnOnce(&Mailbox) + Send + 'static,
    ) -> Fed {
        let mailbox = Arc::new(if lossless {
            Mailbox::lossless()
        } else {
            Mailbox::default()
        });
        let mb = mailbox.clone();
        std::thread::spawn(move || receive(&mb));
        Fed { mailbox, addr }
    }

    /// The address listened on.
    pub(crate) fn local_addr(&self) -> SocketAddr {
        self.addr
    }
}

impl Drop for Fed {
    fn drop(&mut self) {
        self.mailbox.close();
    }
}

impl Source for Fed {
    fn next(&mut self, wait: Duration) -> Result<Event, SourceError> {
        self.mailbox.next(wait)
    }
    fn reference(&self) -> Option<ClipNeutral> {
        self.mailbox.reference()
    }
    fn counters(&self) -> Counters {
        self.mailbox.counters()
    }
    fn waiting(&self) -> bool {
        self.mailbox.waiting()
    }
}
