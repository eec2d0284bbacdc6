//! What a link counted, per service: sent, held back and missing at the source on the way out;
//! received, lost by the link, declared skipped by the sender and refused on the way in. The
//! one shape of `dicstream link --json`, of the file `--counts-json` keeps (written as the
//! link goes, resumed by a restarted link) and of `summary.json`'s `link`, whose `lost` the
//! run's verdict counts.

use crate::gaps::{ReceiveGaps, SendGaps};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use wire::linked::LinkedService;
use wire::stats::IdGaps;

/// One service going out.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct OutCounts {
    pub sent: u64,
    /// Held back by the rate limit (frames).
    pub held_back: u64,
    /// Ids missing in what the local instance gave the link (frames a correlator skipped).
    pub missing_at_source: u64,
    /// Samples dropped by this link, its queue to the network full (the receiver counts them
    /// lost); absent from the counts of an older link.
    #[serde(default)]
    pub overflowed: u64,
}

/// One service coming in.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct InCounts {
    pub received: u64,
    /// Ids lost by the link: gaps beyond what the sender declared it skipped.
    pub lost: u64,
    pub skipped_by_sender: u64,
    /// Ids going back (the source started again).
    pub restarts: u64,
    /// Samples whose bytes were refused (another layout version, not a dicstream link's).
    pub refused: u64,
    pub first_id: Option<u64>,
    pub last_id: Option<u64>,
}

/// A link's counts: `{"instance", "out": {service: OutCounts}, "in": {service: InCounts}}`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct LinkCounts {
    pub instance: String,
    pub out: BTreeMap<String, OutCounts>,
    #[serde(rename = "in")]
    pub into: BTreeMap<String, InCounts>,
}

impl SendGaps {
    pub fn counts(&self) -> OutCounts {
        OutCounts {
            sent: self.sent,
            held_back: self.held_back,
            missing_at_source: self.seen.lost,
            overflowed: self.overflowed,
        }
    }

    /// Sender `sender` started again after `counts`: the totals go on; its first sample
    /// declares nothing (what it missed while down was the link's loss, not the source's).
    pub fn resumed(counts: &OutCounts, sender: u64) -> SendGaps {
        SendGaps {
            sender,
            seen: IdGaps {
                lost: counts.missing_at_source,
                ..IdGaps::default()
            },
            held_back: counts.held_back,
            overflowed: counts.overflowed,
            sent: counts.sent,
            ..SendGaps::default()
        }
    }
}

impl ReceiveGaps {
    /// Its counts, with `refused` samples (counted by whoever checks the bytes).
    pub fn counts(&self, refused: u64) -> InCounts {
        InCounts {
            received: self.received,
            lost: self.lost,
            skipped_by_sender: self.declared,
            restarts: self.ids.restarts,
            refused,
            first_id: self.ids.first,
            last_id: self.ids.last,
        }
    }

    /// A receiver started again after `counts`: the totals go on from its last id, so that
    /// what came while it was down is counted lost by the link.
    pub fn resumed(counts: &InCounts) -> ReceiveGaps {
        ReceiveGaps {
            ids: IdGaps {
                first: counts.first_id,
                last: counts.last_id,
                lost: counts.lost + counts.skipped_by_sender,
                restarts: counts.restarts,
            },
            received: counts.received,
            lost: counts.lost,
            declared: counts.skipped_by_sender,
            ..ReceiveGaps::default()
        }
    }
}

impl LinkCounts {
    pub fn new(instance: &str) -> LinkCounts {
        LinkCounts {
            instance: instance.to_string(),
            ..LinkCounts::default()
        }
    }

    /// The counts of `service` going out (zero if none yet).
    pub fn out_of(&self, service: LinkedService) -> OutCounts {
        self.out.get(service.name()).cloned().unwrap_or_default()
    }

    /// The counts of `service` coming in (zero if none yet).
    pub fn in_of(&self, service: LinkedService) -> InCounts {
        self.into.get(service.name()).cloned().unwrap_or_default()
    }

    /// Notes the counts of `service` going out.
    pub fn set_out(&mut self, service: LinkedService, counts: OutCounts) {
        match self.out.get_mut(service.name()) {
            Some(entry) => *entry = counts,
            None => {
                self.out.insert(service.name().to_string(), counts);
            }
        }
    }

    /// Notes the counts of `service` coming in.
    pub fn set_in(&mut self, service: LinkedService, counts: InCounts) {
        match self.into.get_mut(service.name()) {
            Some(entry) => *entry = counts,
            None => {
                self.into.insert(service.name().to_string(), counts);
            }
        }
    }

    /// Ids lost by the link, in all services coming in.
    pub fn lost(&self) -> u64 {
        self.into.values().map(|c| c.lost).sum()
    }

    /// What the link lost, by service: `"1056 fields, 3 rig/state samples"`; None when nothing.
    pub fn lost_text(&self) -> Option<String> {
        let parts: Vec<String> = self
            .into
            .iter()
            .filter(|(_, c)| c.lost > 0)
            .map(|(service, c)| match service.as_str() {
                "fields" | "frames" => format!("{} {service}", c.lost),
                "identification" => format!("{} identification reports", c.lost),
                _ => format!("{} {service} samples", c.lost),
            })
            .collect();
        (!parts.is_empty()).then(|| parts.join(", "))
    }

    /// One line per service.
    pub fn lines(&self) -> Vec<String> {
        let out = self.out.iter().map(|(service, c)| {
            format!(
                "link: {service} out: {} sent, {} held back by the rate limit, {} ids missing at \
                 the source, {} dropped (the network took less than came)",
                c.sent, c.held_back, c.missing_at_source, c.overflowed
            )
        });
        let into = self.into.iter().map(|(service, c)| {
            format!(
                "link: {service} in: {} received, {} ids lost by the link, {} skipped by the \
                 sender, {} restarts, {} refused",
                c.received, c.lost, c.skipped_by_sender, c.restarts, c.refused
            )
        });
        out.chain(into).collect()
    }

    /// The counts in `text` (the JSON of a counts file), or why not.
    pub fn parse(text: &str) -> Result<LinkCounts, serde_json::Error> {
        serde_json::from_str(text)
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("counts serialise")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::envelope::Envelope;

    #[test]
    fn a_resumed_receiver_counts_what_came_while_it_was_down_as_lost() {
        let mut before = ReceiveGaps::default();
        for id in 0..10 {
            before.received(id, Envelope::default());
        }
        let counts = before.counts(1);
        let mut after = ReceiveGaps::resumed(&counts);
        // Ids 10 to 19 came while it was down.
        after.received(20, Envelope::default());
        let resumed = after.counts(1);
        assert_eq!(
            (resumed.received, resumed.lost, resumed.first_id),
            (11, 10, Some(0))
        );
    }

    #[test]
    fn a_resumed_sender_declares_nothing_for_its_downtime() {
        let mut before = SendGaps::default();
        for id in [0, 1, 3] {
            before.seen(id);
            before.send();
        }
        let mut after = SendGaps::resumed(&before.counts(), 2);
        after.seen(40);
        assert_eq!(after.send().skipped_total, 0);
        assert_eq!(after.counts().sent, 4);
        assert_eq!(after.counts().missing_at_source, 1);
    }

    #[test]
    fn counts_read_back_as_written_and_say_what_was_lost() {
        let mut counts = LinkCounts::new("lab");
        counts.into.insert(
            "fields".into(),
            InCounts {
                received: 5,
                lost: 3,
                ..InCounts::default()
            },
        );
        counts.into.insert(
            "rig/state".into(),
            InCounts {
                received: 9,
                lost: 2,
                ..InCounts::default()
            },
        );
        counts
            .out
            .insert("identification".into(), OutCounts::default());
        let json = counts.to_json();
        assert!(json.contains("\"in\""), "{json}");
        assert_eq!(LinkCounts::parse(&json).unwrap(), counts);
        assert_eq!(counts.lost(), 5);
        assert_eq!(
            counts.lost_text().as_deref(),
            Some("3 fields, 2 rig/state samples")
        );
        assert_eq!(LinkCounts::new("lab").lost_text(), None);
        assert_eq!(counts.lines().len(), 3);
    }
}
