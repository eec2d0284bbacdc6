//! `dicstream tap SERVICE`: watch one service, like `ros2 topic hz`. Sleeps in a WaitSet (a
//! sample event or the one-second tick wakes it, never polling) and prints once a second the
//! rate, the drops (gaps in ids), the delivery latency (HDR histogram: p50, p90, p99, max) and a
//! one-line summary of the last payload; at exit, a summary (one JSON object with `--json`).
//!
//! Ids: `frame_id` for frames and fields, `sample_id` for rig/state. Identification reports
//! carry the frame that triggered a refit: their ids are not consecutive by design, so no drop
//! is counted for them. Latency: from the capture time for frames, from the publish time for
//! the other services, to receipt, on the shared monotonic clock. Frames are checked against
//! their header (layout, size, depth) and their `pixel_checksum`.

use std::time::{Duration, Instant};

use anyhow::Context;
use hdrhistogram::Histogram;
use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::*;
use serde_json::{json, Value};
use wire::frame::pixel_checksum;
use wire::pubsub::{SliceSubscriber, ValueSubscriber};
use wire::{
    services, FieldHeader, FieldNode, FrameHeader, IdentificationReport, Instance, RigState,
    StrainMeasure,
};

/// Options of `dicstream tap`.
#[derive(Debug, clap::Args)]
pub struct TapArgs {
    /// Service to watch: frames, fields, rig/state or identification
    pub service: String,
    /// Stop after this many samples
    #[arg(long)]
    pub count: Option<u64>,
    /// Stop after this many seconds
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Print one JSON object at exit on stdout (the once-a-second lines go to stderr)
    #[arg(long)]
    pub json: bool,
    /// Instance name (shared-memory prefix) of the run to watch
    #[arg(long, default_value_t = Instance::default_name())]
    pub instance: String,
}

/// The service being tapped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Frames,
    Fields,
    RigState,
    Identification,
}

impl Kind {
    fn of(name: &str) -> Option<Kind> {
        match name {
            "frames" => Some(Kind::Frames),
            "fields" => Some(Kind::Fields),
            "rig/state" => Some(Kind::RigState),
            "identification" => Some(Kind::Identification),
            _ => None,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Kind::Frames => services::FRAMES.name,
            Kind::Fields => services::FIELDS.name,
            Kind::RigState => services::RIG_STATE.name,
            Kind::Identification => services::IDENTIFICATION.name,
        }
    }

    /// Whether ids are consecutive, so that a gap is a drop.
    fn counts_drops(self) -> bool {
        self != Kind::Identification
    }

    /// Which header time the latency starts from.
    fn latency_from(self) -> &'static str {
        match self {
            Kind::Frames => "capture",
            _ => "publish",
        }
    }
}

/// Drops and restarts from a sequence of ids that should be consecutive.
#[derive(Debug, Default, Clone, PartialEq)]
struct IdTracker {
    first: Option<u64>,
    last: Option<u64>,
    drops: u64,
    /// An id that did not go forward: the publisher restarted (its ids start again).
    restarts: u64,
}

impl IdTracker {
    /// Notes `id`; returns how many ids were skipped just before it.
    fn observe(&mut self, id: u64) -> u64 {
        let gap = match self.last {
            Some(last) if id > last => id - last - 1,
            Some(_) => {
                self.restarts += 1;
                0
            }
            None => 0,
        };
        self.first.get_or_insert(id);
        self.last = Some(id);
        self.drops += gap;
        gap
    }
}

/// The last sample seen, kept to summarise it.
#[derive(Debug, Clone)]
enum LastSample {
    Frame {
        header: FrameHeader,
        checksum_ok: bool,
    },
    Field {
        header: FieldHeader,
    },
    Rig {
        state: RigState,
    },
    Identification {
        // Boxed: a report is three times a frame header (and comes a few times a second).
        report: Box<IdentificationReport>,
    },
}

/// Mean of an actuator pair's forces (kN): the axis force, as the identifier reads it.
fn axis_force_kn(state: &RigState, axis: usize) -> f64 {
    0.5 * (state.actuators[2 * axis].force_kn + state.actuators[2 * axis + 1].force_kn)
}

fn rig_id(id: u64) -> Value {
    if id == wire::NO_RIG_SAMPLE {
        Value::Null
    } else {
        json!(id)
    }
}

impl LastSample {
    fn line(&self) -> String {
        match self {
            LastSample::Frame {
                header,
                checksum_ok,
            } => {
                let mut line = format!(
                    "frame {}: {}x{} {} bit, checksum {}",
                    header.frame_id,
                    header.width_px,
                    header.height_px,
                    header.bit_depth,
                    if *checksum_ok { "ok" } else { "BAD" }
                );
                if header.rig_sample_id != wire::NO_RIG_SAMPLE {
                    line.push_str(&format!(", rig sample {}", header.rig_sample_id));
                }
                if header.has_truth == 1 {
                    let f = header.truth.deformation_gradient;
                    line.push_str(&format!(
                        ", truth F [{:.5} {:.5}; {:.5} {:.5}] t ({:.3}, {:.3}) px",
                        f[0],
                        f[1],
                        f[2],
                        f[3],
                        header.truth.translation_px[0],
                        header.truth.translation_px[1]
                    ));
                }
                line
            }
            LastSample::Field { header } => {
                let g = header.gauge_of(StrainMeasure::Log);
                format!(
                    "field of frame {}: {}/{} valid nodes, u mean {:.4} px, v mean {:.4} px, \
                     gauge log strain xx {:.3e} yy {:.3e} xy {:.3e}",
                    header.frame_id,
                    header.valid_nodes,
                    header.node_count(),
                    header.u_mean_px,
                    header.v_mean_px,
                    g.exx,
                    g.eyy,
                    g.exy
                )
            }
            LastSample::Rig { state } => format!(
                "rig sample {}: t_sim {:.3} s, stretch x {:.4} y {:.4}, force X {:.4} kN Y {:.4} kN",
                state.sample_id,
                state.t_sim_s,
                state.specimen_stretch_x,
                state.specimen_stretch_y,
                axis_force_kn(state, 0),
                axis_force_kn(state, 1)
            ),
            LastSample::Identification { report } => {
                let coefficients = |values: &[f64], count: u32| {
                    values[..(count as usize).min(values.len())]
                        .iter()
                        .map(|v| format!("{v:.4e}"))
                        .collect::<Vec<_>>()
                        .join(" ")
                };
                let best = if report.ranked_count > 0 {
                    wire::text::read_fixed(&report.ranking[0].name)
                } else {
                    "-".to_string()
                };
                format!(
                    "identification at frame {}: points uniaxial {} equibiaxial {} shear {}, \
                     a [{}], b [{}], rms {:.4} MPa, best {best}",
                    report.frame_id,
                    report.points[0],
                    report.points[1],
                    report.points[2],
                    coefficients(&report.a, report.a_count),
                    coefficients(&report.b, report.b_count),
                    report.rms_mpa
                )
            }
        }
    }

    fn json(&self) -> Value {
        match self {
            LastSample::Frame {
                header,
                checksum_ok,
            } => json!({
                "frame_id": header.frame_id,
                "width_px": header.width_px,
                "height_px": header.height_px,
                "bit_depth": header.bit_depth,
                "checksum_ok": checksum_ok,
                "rig_sample_id": rig_id(header.rig_sample_id),
                "scenario_id": header.scenario_id,
                "has_truth": header.has_truth == 1,
                "deformation_gradient": header.truth.deformation_gradient,
                "translation_px": header.truth.translation_px,
                "centre_px": header.truth.centre_px,
            }),
            LastSample::Field { header } => {
                let g = header.gauge_of(StrainMeasure::Log);
                json!({
                    "frame_id": header.frame_id,
                    "rig_sample_id": rig_id(header.rig_sample_id),
                    "valid_nodes": header.valid_nodes,
                    "nodes": header.node_count(),
                    "u_mean_px": header.u_mean_px,
                    "v_mean_px": header.v_mean_px,
                    "gauge_log_strain": {"xx": g.exx, "yy": g.eyy, "xy": g.exy},
                    "correlator_frames_dropped": header.frames_dropped,
                })
            }
            LastSample::Rig { state } => json!({
                "sample_id": state.sample_id,
                "t_sim_s": state.t_sim_s,
                "stretch_x": state.specimen_stretch_x,
                "stretch_y": state.specimen_stretch_y,
                "force_x_kn": axis_force_kn(state, 0),
                "force_y_kn": axis_force_kn(state, 1),
            }),
            LastSample::Identification { report } => json!({
                "frame_id": report.frame_id,
                "points": report.points,
                "a": &report.a[..(report.a_count as usize).min(report.a.len())],
                "b": &report.b[..(report.b_count as usize).min(report.b.len())],
                "rms_mpa": report.rms_mpa,
            }),
        }
    }
}

/// One received sample, as the statistics see it.
#[derive(Debug, Clone)]
struct Observation {
    /// The id that should be consecutive, if the service has one.
    id: Option<u64>,
    /// Capture or publish time from the header (monotonic ns; 0 if unset).
    sent_ns: u64,
    received_ns: u64,
    /// Frames: whether the payload matched its checksum.
    checksum_ok: Option<bool>,
    /// The header did not validate (layout version, size, depth).
    invalid: bool,
    last: LastSample,
}

fn latency_histogram() -> Histogram<u64> {
    // 1 ns to 1 h at 3 significant digits.
    Histogram::new_with_bounds(1, 3_600_000_000_000, 3).expect("valid histogram bounds")
}

/// Everything the tap counts (pure: fed with observations).
struct TapStats {
    kind: Kind,
    received: u64,
    ids: IdTracker,
    checksum_failures: u64,
    invalid: u64,
    latency_ns: Histogram<u64>,
    first_received_ns: Option<u64>,
    last_received_ns: u64,
    window_received: u64,
    window_drops: u64,
    window_latency_ns: Histogram<u64>,
    last: Option<LastSample>,
}

impl TapStats {
    fn new(kind: Kind) -> Self {
        TapStats {
            kind,
            received: 0,
            ids: IdTracker::default(),
            checksum_failures: 0,
            invalid: 0,
            latency_ns: latency_histogram(),
            first_received_ns: None,
            last_received_ns: 0,
            window_received: 0,
            window_drops: 0,
            window_latency_ns: latency_histogram(),
            last: None,
        }
    }

    fn observe(&mut self, o: Observation) {
        self.received += 1;
        self.window_received += 1;
        if let Some(id) = o.id {
            if self.kind.counts_drops() {
                self.window_drops += self.ids.observe(id);
            } else {
                self.ids.first.get_or_insert(id);
                self.ids.last = Some(id);
            }
        }
        if o.checksum_ok == Some(false) {
            self.checksum_failures += 1;
        }
        if o.invalid {
            self.invalid += 1;
        }
        if o.sent_ns > 0 {
            let latency = o.received_ns.saturating_sub(o.sent_ns).max(1);
            self.latency_ns.saturating_record(latency);
            self.window_latency_ns.saturating_record(latency);
        }
        self.first_received_ns.get_or_insert(o.received_ns);
        self.last_received_ns = o.received_ns;
        self.last = Some(o.last);
    }

    /// Rate over the samples received so far (first to last receipt), Hz.
    fn rate_hz(&self) -> f64 {
        match self.first_received_ns {
            Some(first) if self.received > 1 && self.last_received_ns > first => {
                (self.received - 1) as f64 * 1e9 / (self.last_received_ns - first) as f64
            }
            _ => 0.0,
        }
    }

    fn drops_text(&self, drops: u64) -> String {
        if self.kind.counts_drops() {
            drops.to_string()
        } else {
            "n/a".to_string()
        }
    }

    /// The once-a-second line for a window of `window_s` seconds; resets the window.
    fn window_line(&mut self, window_s: f64) -> String {
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
                self.drops_text(self.ids.drops),
                latency_text(&self.window_latency_ns),
                self.last.as_ref().map(|l| l.line()).unwrap_or_default()
            )
        };
        self.window_received = 0;
        self.window_drops = 0;
        self.window_latency_ns.reset();
        line
    }

    fn summary_line(&self, elapsed_s: f64) -> String {
        let mut line = format!(
            "tap {}: {} received in {elapsed_s:.2} s ({:.1} Hz), drops {}",
            self.kind.name(),
            self.received,
            self.rate_hz(),
            self.drops_text(self.ids.drops),
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

    fn json(&self, instance: &str, elapsed_s: f64, stopped_by: &str) -> Value {
        let latency = if self.latency_ns.is_empty() {
            Value::Null
        } else {
            let us = |ns: u64| ns as f64 / 1e3;
            json!({
                "p50": us(self.latency_ns.value_at_quantile(0.50)),
                "p90": us(self.latency_ns.value_at_quantile(0.90)),
                "p99": us(self.latency_ns.value_at_quantile(0.99)),
                "max": us(self.latency_ns.max()),
            })
        };
        json!({
            "service": self.kind.name(),
            "instance": instance,
            "received": self.received,
            "drops": self.kind.counts_drops().then_some(self.ids.drops),
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

fn latency_text(h: &Histogram<u64>) -> String {
    if h.is_empty() {
        return "-".to_string();
    }
    let ms = |ns: u64| ns as f64 / 1e6;
    format!(
        "p50 {:.3} ms p90 {:.3} ms p99 {:.3} ms max {:.3} ms",
        ms(h.value_at_quantile(0.50)),
        ms(h.value_at_quantile(0.90)),
        ms(h.value_at_quantile(0.99)),
        ms(h.max())
    )
}

/// The subscriber of the tapped service.
enum Tap {
    Frames(SliceSubscriber<u16, FrameHeader>),
    Fields(SliceSubscriber<FieldNode, FieldHeader>),
    Rig(ValueSubscriber<RigState>),
    Identification(ValueSubscriber<IdentificationReport>),
}

impl Tap {
    fn open(node: &Node<ipc::Service>, kind: Kind) -> anyhow::Result<Tap> {
        Ok(match kind {
            Kind::Frames => Tap::Frames(SliceSubscriber::create(node, &services::FRAMES)?),
            Kind::Fields => Tap::Fields(SliceSubscriber::create(node, &services::FIELDS)?),
            Kind::RigState => Tap::Rig(ValueSubscriber::create(node, &services::RIG_STATE)?),
            Kind::Identification => {
                Tap::Identification(ValueSubscriber::create(node, &services::IDENTIFICATION)?)
            }
        })
    }

    fn listener(&self) -> &Listener<ipc::Service> {
        match self {
            Tap::Frames(s) => s.listener(),
            Tap::Fields(s) => s.listener(),
            Tap::Rig(s) => s.listener(),
            Tap::Identification(s) => s.listener(),
        }
    }

    fn clear_events(&self) {
        match self {
            Tap::Frames(s) => s.clear_events(),
            Tap::Fields(s) => s.clear_events(),
            Tap::Rig(s) => s.clear_events(),
            Tap::Identification(s) => s.clear_events(),
        }
    }

    /// Receives queued samples into `stats` until the queue is empty or `budget` are taken.
    fn drain(&self, stats: &mut TapStats, mut budget: u64) -> anyhow::Result<()> {
        self.clear_events();
        while budget > 0 {
            let Some(o) = self.receive_one()? else {
                break;
            };
            stats.observe(o);
            budget -= 1;
        }
        Ok(())
    }

    fn receive_one(&self) -> anyhow::Result<Option<Observation>> {
        Ok(match self {
            Tap::Frames(s) => s.receive()?.map(|sample| {
                let received_ns = wire::monotonic_ns();
                let header = *sample.user_header();
                let pixels = sample.payload();
                let invalid = header.validate(pixels.len()).is_err();
                let checksum_ok = pixel_checksum(pixels) == header.pixel_checksum;
                Observation {
                    id: Some(header.frame_id),
                    sent_ns: header.t_capture_ns,
                    received_ns,
                    checksum_ok: Some(checksum_ok),
                    invalid,
                    last: LastSample::Frame {
                        header,
                        checksum_ok,
                    },
                }
            }),
            Tap::Fields(s) => s.receive()?.map(|sample| {
                let received_ns = wire::monotonic_ns();
                let header = *sample.user_header();
                Observation {
                    id: Some(header.frame_id),
                    sent_ns: header.t_published_ns,
                    received_ns,
                    checksum_ok: None,
                    invalid: header.layout_version != wire::LAYOUT_VERSION
                        || sample.payload().len() != header.node_count(),
                    last: LastSample::Field { header },
                }
            }),
            Tap::Rig(s) => s.receive()?.map(|state| Observation {
                id: Some(state.sample_id),
                sent_ns: state.t_published_ns,
                received_ns: wire::monotonic_ns(),
                checksum_ok: None,
                invalid: state.layout_version != wire::LAYOUT_VERSION,
                last: LastSample::Rig { state },
            }),
            Tap::Identification(s) => s.receive()?.map(|report| Observation {
                id: Some(report.frame_id),
                sent_ns: report.t_published_ns,
                received_ns: wire::monotonic_ns(),
                checksum_ok: None,
                invalid: report.layout_version != wire::LAYOUT_VERSION,
                last: LastSample::Identification {
                    report: Box::new(report),
                },
            }),
        })
    }
}

pub fn run(args: TapArgs) -> anyhow::Result<()> {
    let kind = Kind::of(&args.service).ok_or_else(|| {
        anyhow::anyhow!(
            "unknown service {:?}: expected one of {}",
            args.service,
            services::TAPPABLE.map(|s| s.name).join(", ")
        )
    })?;
    anyhow::ensure!(
        args.count != Some(0),
        "--count 0: expected at least 1 sample"
    );
    if let Some(seconds) = args.seconds {
        anyhow::ensure!(
            seconds.is_finite() && seconds > 0.0,
            "--seconds {seconds}: expected a positive duration"
        );
    }
    let instance = Instance::new(&args.instance)?;
    let (node, cleaned) = instance.create_node("tap")?;
    if cleaned > 0 {
        eprintln!(
            "tap: cleaned {cleaned} dead node(s) of instance {}",
            instance.name()
        );
    }
    let tap = Tap::open(&node, kind)?;
    let waitset =
        wire::signals::waitset().map_err(|e| anyhow::anyhow!("creating the WaitSet: {e:?}"))?;
    let sample_guard = waitset
        .attach_notification(tap.listener())
        .map_err(|e| anyhow::anyhow!("attaching {} to the WaitSet: {e:?}", kind.name()))?;
    let tick_guard = waitset
        .attach_interval(Duration::from_secs(1))
        .map_err(|e| anyhow::anyhow!("attaching the 1 s tick to the WaitSet: {e:?}"))?;
    eprintln!(
        "tap: watching {} of instance {} (Ctrl-C to stop)",
        kind.name(),
        instance.name()
    );

    let started = Instant::now();
    let deadline = args.seconds.map(|s| started + Duration::from_secs_f64(s));
    let limit = args.count.unwrap_or(u64::MAX);
    let mut stats = TapStats::new(kind);
    let mut window_started = started;
    let print_window = |stats: &mut TapStats, window_started: &mut Instant| {
        let line = stats.window_line(window_started.elapsed().as_secs_f64());
        *window_started = Instant::now();
        if args.json {
            eprintln!("{line}");
        } else {
            println!("{line}");
        }
    };
    // History samples (rig/state, fields, identification keep the last one) need no event.
    tap.drain(&mut stats, limit)?;
    let stopped_by = loop {
        if stats.received >= limit {
            break "count";
        }
        let timeout = match deadline {
            Some(deadline) => {
                let left = deadline.saturating_duration_since(Instant::now());
                if left.is_zero() {
                    break "seconds";
                }
                left
            }
            None => Duration::MAX,
        };
        let (mut sample_ready, mut tick) = (false, false);
        waitset
            .wait_and_process_once_with_timeout(
                |id| {
                    sample_ready |= id.has_event_from(&sample_guard);
                    tick |= id.has_event_from(&tick_guard);
                    CallbackProgression::Continue
                },
                timeout,
            )
            .map_err(|e| anyhow::anyhow!("waiting on the WaitSet: {e:?}"))?;
        if sample_ready || !tick {
            let budget = limit - stats.received;
            tap.drain(&mut stats, budget)
                .with_context(|| format!("receiving from {}", kind.name()))?;
        }
        if tick {
            print_window(&mut stats, &mut window_started);
        }
        // The 1 s tick bounds the wait, so a request is seen within a second.
        if wire::signals::requested().is_some() {
            break "signal";
        }
    };
    let elapsed_s = started.elapsed().as_secs_f64();
    if args.json {
        println!("{}", stats.json(instance.name(), elapsed_s, stopped_by));
    } else {
        println!("{}", stats.summary_line(elapsed_s));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn gaps_are_drops_and_going_back_is_a_restart() {
        let mut ids = IdTracker::default();
        assert_eq!(ids.observe(10), 0);
        assert_eq!(ids.observe(11), 0);
        assert_eq!(ids.observe(14), 2);
        assert_eq!(ids.observe(0), 0);
        assert_eq!(ids.observe(1), 0);
        assert_eq!((ids.drops, ids.restarts), (2, 1));
        assert_eq!((ids.first, ids.last), (Some(10), Some(1)));
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
        assert_eq!(stats.ids.drops, 2);
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
            ..FieldHeader::default()
        };
        let line = LastSample::Field { header }.line();
        assert!(
            line.contains("5/6 valid nodes") && line.contains("u mean 0.2500"),
            "{line}"
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
