//! The ids a link lost, counted from each sample's own id (`LinkedService::sample_id`).
//!
//! The sender counts the ids missing in what it takes from its instance (a field skips the
//! frames its correlator did not correlate; a full queue dropped some) and those its rate limit
//! held back, and declares their running total with every sample it sends (`Envelope`). A
//! sample it took but could not hand to Zenoh (its queue to the network full: the network
//! took less than came) is not declared: the receiver counts it lost by the link. The
//! receiver counts a gap in the ids it receives, less what the sender declared since the last
//! sample received (a declaration is not lost with a dropped sample), as lost by the link: dropped
//! on the way, or never sent because the sending link was down. A sender restarted mid-stream
//! declares nothing for what it missed while down, so that gap is counted at the receiver.
//! An id at or below the last one is a source that started again (a restarted rig counts from
//! 0): counted as a restart, not a loss, and the count goes on from it. Both sides count
//! with `wire::stats::IdGaps`, as `dicstream tap` does.

use crate::envelope::Envelope;
use wire::stats::{IdGaps, IdStep};

/// The sender's side: ids it did not send, declared as a running total with every sample it
/// does send.
#[derive(Debug, Clone, Default)]
pub struct SendGaps {
    /// This sender, drawn at its start (`Envelope::sender`).
    pub sender: u64,
    /// The ids taken from the local instance: `lost` is what was missing there.
    pub seen: IdGaps,
    /// Ids not sent on purpose since this sender started (missing at the source, held back).
    pub(crate) declared_total: u64,
    /// Samples taken but held back by the rate limit.
    pub held_back: u64,
    /// Samples taken but dropped, their queue to the network full (not declared: lost).
    pub overflowed: u64,
    pub sent: u64,
}

impl SendGaps {
    /// A sample with `id` taken from the local instance.
    pub fn seen(&mut self, id: u64) {
        if let IdStep::Forward { skipped } = self.seen.observe(id) {
            self.declared_total += skipped;
        }
    }

    /// The sample last seen is not sent (rate limit).
    pub fn hold_back(&mut self) {
        self.held_back += 1;
        self.declared_total += 1;
    }

    /// What to declare with the sample last seen, if it is sent.
    pub fn envelope(&self) -> Envelope {
        Envelope {
            sender: self.sender,
            skipped_total: self.declared_total,
        }
    }

    /// The sample last seen is sent: what to declare with it.
    pub fn send(&mut self) -> Envelope {
        self.sent += 1;
        self.envelope()
    }

    /// The sample last seen could not be sent (its queue to the network full): not declared,
    /// so the receiver counts it lost by the link.
    pub fn overflow(&mut self) {
        self.overflowed += 1;
    }
}

/// What one received sample says about the link.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Arrival {
    /// The first sample, or the next one after what the sender declared.
    InOrder,
    /// `lost` ids before this sample were lost by the link.
    AfterLoss { lost: u64 },
    /// The id is at or below the last: the source started again.
    Restarted,
}

/// The receiver's side: gaps less what the sender declared.
#[derive(Debug, Clone, Default)]
pub struct ReceiveGaps {
    /// The ids received: `lost` counts every gap, `restarts` the ids going back.
    pub ids: IdGaps,
    pub received: u64,
    /// Ids lost by the link (dropped, or not sent while the sending link was down).
    pub lost: u64,
    /// Ids the sender declared it did not send (missing at its source, held back).
    pub declared: u64,
    /// The last envelope received: what its sender had declared by then.
    pub(crate) last: Option<Envelope>,
}

impl ReceiveGaps {
    /// A sample with `id` and its sender's `envelope`.
    pub fn received(&mut self, id: u64, envelope: Envelope) -> Arrival {
        self.received += 1;
        // Declared since the last sample received: the difference of the running totals, or
        // the whole total of a sender that started again.
        let newly_declared = match self.last.replace(envelope) {
            Some(last) if last.sender == envelope.sender => {
                envelope.skipped_total.saturating_sub(last.skipped_total)
            }
            _ => envelope.skipped_total,
        };
        match self.ids.observe(id) {
            IdStep::First => Arrival::InOrder,
            IdStep::Back { .. } => Arrival::Restarted,
            IdStep::Forward { skipped } => {
                let declared = newly_declared.min(skipped);
                self.declared += declared;
                match skipped - declared {
                    0 => Arrival::InOrder,
                    lost => {
                        self.lost += lost;
                        Arrival::AfterLoss { lost }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sends ids through a sender that holds back what `hold` says, and a receiver that gets
    /// what `deliver` says; returns the receiver.
    fn carry(
        ids: impl Iterator<Item = u64>,
        mut hold: impl FnMut(u64) -> bool,
        mut deliver: impl FnMut(u64) -> bool,
    ) -> (SendGaps, ReceiveGaps) {
        let (mut sender, mut receiver) = (SendGaps::default(), ReceiveGaps::default());
        for id in ids {
            sender.seen(id);
            if hold(id) {
                sender.hold_back();
                continue;
            }
            let envelope = sender.send();
            if deliver(id) {
                receiver.received(id, envelope);
            }
        }
        (sender, receiver)
    }

    #[test]
    fn nothing_lost_when_everything_arrives() {
        let (sender, receiver) = carry(0..100, |_| false, |_| true);
        assert_eq!(
            (sender.sent, receiver.received, receiver.lost),
            (100, 100, 0)
        );
    }

    #[test]
    fn held_back_and_source_gaps_are_declared_not_lost() {
        // Fields of every other frame, one in three of them held back by the rate limit.
        let (sender, receiver) = carry((0..60).map(|i| 2 * i), |id| id % 3 == 1, |_| true);
        assert_eq!(sender.seen.lost, 59);
        assert_eq!(sender.held_back, 20);
        assert_eq!(receiver.lost, 0);
        // The last id, 118, is held back: it and the gap before it have no sample to go with.
        assert_eq!(receiver.declared, 59 + 20 - 2);
    }

    #[test]
    fn a_dropped_sample_does_not_take_its_senders_declaration_with_it() {
        // Fields of every other frame (the odd ids declared), five of them dropped on the way.
        let (_, receiver) = carry(
            (0..60).map(|i| 2 * i),
            |_| false,
            |id| !(40..50).contains(&id),
        );
        assert_eq!((receiver.received, receiver.lost), (55, 5));
    }

    #[test]
    fn a_sample_its_queue_had_no_room_for_is_lost_not_declared() {
        let (mut sender, mut receiver) = (SendGaps::default(), ReceiveGaps::default());
        for id in 0..10 {
            sender.seen(id);
            match (3..6).contains(&id) {
                true => sender.overflow(),
                false => {
                    receiver.received(id, sender.send());
                }
            }
        }
        assert_eq!((sender.sent, sender.overflowed), (7, 3));
        assert_eq!(
            (receiver.received, receiver.lost, receiver.declared),
            (7, 3, 0)
        );
    }

    #[test]
    fn ids_dropped_on_the_way_are_lost() {
        let (_, receiver) = carry(0..100, |_| false, |id| !(40..45).contains(&id));
        assert_eq!((receiver.received, receiver.lost), (95, 5));
    }

    #[test]
    fn a_restarted_sender_declares_nothing_for_what_it_missed() {
        let mut receiver = ReceiveGaps::default();
        let mut sender = SendGaps::default();
        for id in 0..10 {
            sender.seen(id);
            receiver.received(id, sender.send());
        }
        // The sending link is restarted: a new SendGaps, its first sample id 25.
        let mut sender = SendGaps {
            sender: 2,
            ..SendGaps::default()
        };
        sender.seen(25);
        assert_eq!(
            receiver.received(25, sender.send()),
            Arrival::AfterLoss { lost: 15 }
        );
        assert_eq!(receiver.lost, 15);
    }

    #[test]
    fn a_source_starting_again_is_a_restart_not_a_loss() {
        let mut receiver = ReceiveGaps::default();
        let none = Envelope::default();
        assert_eq!(receiver.received(7, none), Arrival::InOrder);
        assert_eq!(receiver.received(0, none), Arrival::Restarted);
        assert_eq!(receiver.received(1, none), Arrival::InOrder);
        assert_eq!((receiver.ids.restarts, receiver.lost), (1, 0));
    }
}
