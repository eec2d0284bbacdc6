//! What `dicstream tap` counts (pure: fed with observations, no IPC): samples, drops and
//! restarts (`wire::stats::IdGaps`), checksum failures, invalid headers, rates and the
//! delivery latency (`wire::stats::Durations`), per one-second window and in total.

use super::sample::LastSample;
use serde_json::{json, Value};
use wire::services;
use wire::stats::{Durations, IdGaps};

/// The service being tapped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Kind {
    Frames,
    Fields,
    RigState,
    Identification,
}

impl Kind {
    pub(super) fn of(name: &str) -> Option<Kind> {
        match name {
            "frames" => Some(Kind::Frames),
            "fields" => Some(Kind::Fields),
            "rig/state" => Some(Kind::RigState),
            "identification" => Some(Kind::Identification),
            _ => None,
        }
    }

    pub(super) fn name(self) -> &'static str {
        match self {
            Kind::Frames => services::FRAMES.name,
            Kind::Fields => services::FIELDS.name,
            Kind::RigState => services::RIG_STATE.name,
            Kind::Identification => services::IDENTIFICATION.name,
        }
    }

    /// Whether ids are consecutive, so that a gap is a drop.
    pub(super) fn counts_drops(self) -> bool {
        self != Kind::Identification
    }

    /// Which header time the latency starts from.
    pub(super) fn latency_from(self) -> &'static str {
        match self {
            Kind::Frames => "capture",
            _ => "publish",
        }
    }
}

/// One received sample, as the statistics see it.
#[derive(Debug, Clone)]
pub(super) struct Observation {
    /// The id that should be consecutive, if the service has one.
    pub(super) id: Option<u64>,
    /// Capture or publish time from the header (monotonic ns; 0 if unset).
    pub(super) sent_ns: u64,
    pub(super) received_ns: u64,
    /// Frames: whether the payload matched its checksum.
    pub(super) checksum_ok: Option<bool>,
    /// The header did not validate (layout version, size, depth).
    pub(super) invalid: bool,
    pub(super) last: LastSample,
}

/// Everything the tap counts (pure: fed with observations).
pub(super) struct TapStats {
    pub(super) kind: Kind,
    pub(super) received: u64,
    pub(super) ids: IdGaps,
    pub(super) checksum_failures: u64,
    pub(super) invalid: u64,
    pub(super) latency_ns: Durations,
    pub(super) first_received_ns: Option<u64>,
    pub(super) last_received_ns: u64,
    pub(super) window_received: u64,
    pub(super) window_drops: u64,
    pub(super) window_latency_ns: Durations,
    pub(super) last: Option<LastSample>,
}

impl TapStats {
    pub(super) fn new(kind: Kind) -> Self {
        TapStats {
            kind,
            received: 0,
            ids: IdGaps::default(),
            checksum_failures: 0,
            invalid: 0,
            latency_ns: Durations::new(),
            first_received_ns: None,
            last_received_ns: 0,
            window_received: 0,
            window_drops: 0,
            window_latency_ns: Durations::new(),
            last: None,
        }
    }

    pub(super) fn observe(&mut self, o: Observation) {
        self.received += 1;
        self.window_received += 1;
        if let Some(id) = o.id {
            if self.kind.counts_drops() {
                self.window_drops += self.ids.observe(id).skipped();
            } else {
                self.ids.note(id);
            }
        }
        if o.checksum_ok == Some(false) {
            self.checksum_failures += 1;
        }
        if o.invalid {
            self.invalid += 1;
        }
        if o.sent_ns > 0 {
            let latency = o.received_ns.saturating_sub(o.sent_ns);
            self.latency_ns.record_ns(latency);
            self.window_latency_ns.record_ns(latency);
        }
        self.first_received_ns.get_or_insert(o.received_ns);
        self.last_received_ns = o.received_ns;
        self.last = Some(o.last);
    }

    /// Rate over the samples received so far (first to last receipt), Hz.
    pub(super) fn rate_hz(&self) -> f64 {
        match self.first_received_ns {
            Some(first) if self.received > 1 && self.last_received_ns > first => {
                (self.received - 1) as f64 * 1e9 / (self.last_received_ns - first) as f64
            }
            _ => 0.0,
        }
    }

    pub(super) fn drops_text(&self, drops: u64) -> String {
        if self.kind.counts_drops() {
            drops.to_string()
        } else {
            "n/a".to_string()
        }
    }

    /// The once-a-second line for a window of `window_s` seconds; resets the window.
    pub(super) fn window_line(&mut self, window_s: f64) -> String {
        let line = if self.window_received == 0 {
            format!(
                "tap {}: no sample in the last {window_s:.1} s ({} received so far)",
                self.kind.name(),
                self.received
            )
        } else {
            format!(
                "tap {}: {:.1} Hz, drops {} (total {}), latency {} | {}",
                self.kind.name(),
                self.window_received as f64 / window_s.max(1e-9),
                self.drops_text(self.window_drops),
                self.drops_text(self.ids.lost),
                latency_text(&self.window_latency_ns),
                self.last.as_ref().map(|l| l.line()).unwrap_or_default()
            )
        };
        self.window_received = 0;
        self.window_drops = 0;
        self.window_latency_ns.reset();
        line
    }

    pub(super) fn summary_line(&self, elapsed_s: f64) -> String {
        let mut line = format!(
            "tap {}: {} received in {elapsed_s:.2} s ({:.1} Hz), drops {}",
            self.kind.name(),
            self.received,
            self.rate_hz(),
            self.drops_text(self.ids.lost),
        );
        if let (Some(first), Some(last)) = (self.ids.first, self.ids.last) {
            line.push_str(&format!(", ids {first}..{last}"));
        }
        if self.ids.restarts > 0 {
            line.push_str(&format!(", {} publisher restart(s)", self.ids.restarts));
        }
        if self.kind == Kind::Frames {
            line.push_str(&format!(", checksum failures {}", self.checksum_failures));
        }
        if self.invalid > 0 {
            line.push_str(&format!(", {} invalid header(s)", self.invalid));
        }
        line.push_str(&format!(
            ", latency ({} to receipt) {}",
            self.kind.latency_from(),
            latency_text(&self.latency_ns)
        ));
        if let Some(last) = &self.last {
            line.push_str(&format!("\n  last: {}", last.line()));
        }
        line
    }

    pub(super) fn json(&self, instance: &str, elapsed_s: f64, stopped_by: &str) -> Value {
        let latency = if self.latency_ns.is_empty() {
            Value::Null
        } else {
            let us = |ns: u64| ns as f64 / 1e3;
            json!({
                "p50": us(self.latency_ns.median_ns()),
                "p90": us(self.latency_ns.quantile_ns(0.90)),
                "p99": us(self.latency_ns.quantile_ns(0.99)),
                "max": us(self.latency_ns.max_ns()),
            })
        };
        json!({
            "service": self.kind.name(),
            "instance": instance,
            "received": self.received,
            "drops": self.kind.counts_drops().then_some(self.ids.lost),
            "restarts": self.ids.restarts,
            "checksum_failures": (self.kind == Kind::Frames).then_some(self.checksum_failures),
            "invalid": self.invalid,
            "first_id": self.ids.first,
            "last_id": self.ids.last,
            "elapsed_s": elapsed_s,
            "rate_hz": self.rate_hz(),
            "latency_from": self.kind.latency_from(),
            "latency_us": latency,
            "stopped_by": stopped_by,
            "last": self.last.as_ref().map(|l| l.json()),
        })
    }
}

pub(super) fn latency_text(d: &Durations) -> String {
    if d.is_empty() {
        return "-".to_string();
    }
    format!(
        "p50 {:.3} ms p90 {:.3} ms p99 {:.3} ms max {:.3} ms",
        d.median_ms(),
        d.quantile_ms(0.90),
        d.quantile_ms(0.99),
        d.max_ns() as f64 / 1e6
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use wire::{FieldHeader, FrameHeader, IdentificationReport, RigState};

    fn frame_observation(id: u64, sent_ns: u64, received_ns: u64, ok: bool) -> Observation {
        let header = FrameHeader {
            frame_id: id,
            width_px: 4,
            height_px: 2,
            bit_depth: 8,
            ..FrameHeader::default()
        };
        Observation {
            id: Some(id),
            sent_ns,
            received_ns,
            checksum_ok: Some(ok),
            invalid: false,
            last: LastSample::Frame {
                header,
                checksum_ok: ok,
            },
        }
    }

    #[test]
    fn stats_count_drops_checksums_and_latency_per_window_and_in_total() {
        let mut stats = TapStats::new(Kind::Frames);
        for (k, id) in [0u64, 1, 2, 5, 6].into_iter().enumerate() {
            let sent = 1_000_000_000 + k as u64 * 100_000_000;
            stats.observe(frame_observation(
                id,
                sent,
                sent + 200_000 * (k as u64 + 1),
                id != 5,
            ));
        }
        assert_eq!(stats.received, 5);
        assert_eq!(stats.ids.lost, 2);
        assert_eq!(stats.checksum_failures, 1);
        // Receipts 0.4 s apart in total, minus the latency growth: (5 - 1) / 0.4008 s.
        assert!((stats.rate_hz() - 4.0 / 0.4008).abs() < 1e-6);
        let line = stats.window_line(1.0);
        assert!(
            line.contains("5.0 Hz") && line.contains("drops 2 (total 2)"),
            "{line}"
        );
        assert!(
            line.contains("p50 0.6") && line.contains("max 1.00"),
            "{line}"
        );
        assert!(line.contains("frame 6: 4x2 8 bit, checksum ok"), "{line}");
        // The window was reset, the totals were not.
        assert!(stats.window_line(1.0).contains("no sample"));
        let json = stats.json("inst", 2.0, "count");
        assert_eq!(json["received"], 5);
        assert_eq!(json["drops"], 2);
        assert_eq!(json["checksum_failures"], 1);
        assert_eq!(json["first_id"], 0);
        assert_eq!(json["last_id"], 6);
        assert_eq!(json["last"]["checksum_ok"], true);
        assert_eq!(json["last"]["rig_sample_id"], Value::Null);
        let p50 = json["latency_us"]["p50"].as_f64().unwrap();
        assert!((p50 - 600.0).abs() < 1.0, "{p50}");
        assert!((json["latency_us"]["max"].as_f64().unwrap() - 1000.0).abs() < 1.0);
        assert!(stats.summary_line(2.0).contains("checksum failures 1"));
    }

    #[test]
    fn identification_ids_are_not_drops_and_payloads_summarise() {
        let mut stats = TapStats::new(Kind::Identification);
        let mut report = IdentificationReport {
            frame_id: 3,
            a_count: 2,
            a: [0.1, -0.02, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            points: [12, 0, 0],
            ..IdentificationReport::default()
        };
        for frame_id in [3, 9] {
            report.frame_id = frame_id;
            stats.observe(Observation {
                id: Some(frame_id),
                sent_ns: 0,
                received_ns: 5,
                checksum_ok: None,
                invalid: false,
                last: LastSample::Identification {
                    report: Box::new(report),
                },
            });
        }
        let json = stats.json("inst", 1.0, "signal");
        assert_eq!(json["drops"], Value::Null);
        assert_eq!(json["latency_us"], Value::Null);
        assert_eq!(json["last"]["a"], json!([0.1, -0.02]));
        let line = stats.summary_line(1.0);
        assert!(
            line.contains("drops n/a") && line.contains("uniaxial 12"),
            "{line}"
        );
        assert!(line.contains("a [1.0000e-1 -2.0000e-2]"), "{line}");

        let state = RigState {
            sample_id: 4,
            t_sim_s: 1.5,
            specimen_stretch_x: 1.25,
            specimen_stretch_y: 0.9,
            ..RigState::default()
        };
        let line = LastSample::Rig { state }.line();
        assert!(
            line.contains("t_sim 1.500 s") && line.contains("stretch x 1.2500"),
            "{line}"
        );
        let header = FieldHeader {
            frame_id: 8,
            mesh_cols: 3,
            mesh_rows: 2,
            valid_nodes: 5,
            u_mean_px: 0.25,
            gradient_source: wire::GradientSource::Icgn1 as u32,
            ..FieldHeader::default()
        };
        let ok = |du_dx: f32| wire::FieldNode {
            du_dx,
            dv_dy: -0.5,
            status: wire::NodeStatus::Ok as u32,
            ..wire::FieldNode::default()
        };
        let refused = wire::FieldNode {
            du_dx: 9.0,
            status: wire::NodeStatus::LowZncc as u32,
            ..wire::FieldNode::default()
        };
        let nodes = [ok(0.1), ok(0.3), refused];
        let mean_gradient = super::super::sample::mean_gradient(&nodes);
        let expected = [0.2, 0.0, 0.0, -0.5];
        assert!(
            mean_gradient
                .iter()
                .zip(expected)
                .all(|(m, e)| (m - e).abs() < 1e-6),
            "{mean_gradient:?}"
        );
        let last = LastSample::Field {
            header,
            mean_gradient,
            nodes_checksum: wire::field::nodes_checksum(&nodes),
        };
        let line = last.line();
        assert!(
            line.contains("5/6 valid nodes")
                && line.contains("u mean 0.2500")
                && line.contains("mean gradient (icgn1) du/dx 2.000e-1"),
            "{line}"
        );
        let json = last.json();
        assert_eq!(json["gradient_source"], "icgn1");
        assert_eq!(json["mean_gradient"]["dv_dy"], -0.5);
        assert_eq!(
            json["nodes_checksum"],
            wire::field::nodes_checksum(&nodes).to_string()
        );
    }

    #[test]
    fn every_tappable_service_has_a_kind() {
        for spec in services::TAPPABLE {
            assert_eq!(Kind::of(spec.name).unwrap().name(), spec.name);
        }
        assert!(Kind::of("nope").is_none());
    }
}
