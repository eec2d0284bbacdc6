//! What a link says at exit, per service: sent, held back and missing at the source on the way
//! out; received, lost by the link, declared skipped and refused on the way in.

use super::inbound::Received;
use super::outbound::Sent;
use serde_json::json;

/// The counts of a link's run.
pub struct LinkReport {
    pub sent: Vec<Sent>,
    pub received: Vec<Received>,
}

impl LinkReport {
    /// One line per service.
    pub fn lines(&self) -> Vec<String> {
        let out = self.sent.iter().map(|s| {
            format!(
                "link: {} out: {} sent, {} held back by the rate limit, {} ids missing at the source",
                s.service, s.gaps.sent, s.gaps.held_back, s.gaps.seen.lost
            )
        });
        let into =
            self.received.iter().map(|r| {
                format!(
                "link: {} in: {} received, {} ids lost by the link, {} skipped by the sender, {} \
                 restarts, {} refused",
                r.service, r.gaps.received, r.gaps.lost, r.gaps.declared, r.gaps.ids.restarts,
                r.refused
            )
            });
        out.chain(into).collect()
    }

    /// `{"instance", "out": {service: counts}, "in": {service: counts}}`.
    pub fn json(&self, instance: &str) -> serde_json::Value {
        let out: serde_json::Map<String, serde_json::Value> = self
            .sent
            .iter()
            .map(|s| {
                (
                    s.service.to_string(),
                    json!({
                        "sent": s.gaps.sent,
                        "held_back": s.gaps.held_back,
                        "missing_at_source": s.gaps.seen.lost,
                    }),
                )
            })
            .collect();
        let into: serde_json::Map<String, serde_json::Value> = self
            .received
            .iter()
            .map(|r| {
                (
                    r.service.to_string(),
                    json!({
                        "received": r.gaps.received,
                        "lost": r.gaps.lost,
                        "skipped_by_sender": r.gaps.declared,
                        "restarts": r.gaps.ids.restarts,
                        "refused": r.refused,
                        "first_id": r.gaps.ids.first,
                        "last_id": r.gaps.ids.last,
                    }),
                )
            })
            .collect();
        json!({ "instance": instance, "out": out, "in": into })
    }
}
