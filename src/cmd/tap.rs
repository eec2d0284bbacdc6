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
use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::*;
use wire::frame::pixel_checksum;
use wire::pubsub::TappedSubscriber;
use wire::Instance;

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

mod sample;
mod stats;

use sample::LastSample;
use stats::{Kind, Observation, TapStats};

/// The subscriber of the tapped service.
struct Tap(TappedSubscriber);

impl Tap {
    fn open(node: &Node<ipc::Service>, kind: Kind) -> anyhow::Result<Tap> {
        let subscriber = TappedSubscriber::open(node, kind.name())
            .expect("every Kind names a tappable service")?;
        Ok(Tap(subscriber))
    }

    fn listener(&self) -> &Listener<ipc::Service> {
        self.0.listener()
    }

    fn clear_events(&self) {
        self.0.clear_events()
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
        Ok(match &self.0 {
            TappedSubscriber::Frames(s) => s.receive()?.map(|sample| {
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
            TappedSubscriber::Fields(s) => s.receive()?.map(|sample| {
                let received_ns = wire::monotonic_ns();
                let header = *sample.user_header();
                Observation {
                    id: Some(header.frame_id),
                    sent_ns: header.t_published_ns,
                    received_ns,
                    checksum_ok: None,
                    invalid: header.validate(sample.payload().len()).is_err(),
                    last: LastSample::Field {
                        header,
                        mean_gradient: sample::mean_gradient(sample.payload()),
                        nodes_checksum: wire::field::nodes_checksum(sample.payload()),
                    },
                }
            }),
            TappedSubscriber::RigState(s) => s.receive()?.map(|state| Observation {
                id: Some(state.sample_id),
                sent_ns: state.t_published_ns,
                received_ns: wire::monotonic_ns(),
                checksum_ok: None,
                invalid: state.layout_version != wire::LAYOUT_VERSION,
                last: LastSample::Rig { state },
            }),
            TappedSubscriber::Identification(s) => s.receive()?.map(|report| Observation {
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
    let kind = check(&args)?;
    let instance = Instance::new(&args.instance)?;
    let (node, cleaned) = instance.create_node("tap")?;
    if cleaned > 0 {
        eprintln!(
            "tap: cleaned {cleaned} dead node(s) of instance {}",
            instance.name()
        );
    }
    let tap = Tap::open(&node, kind)?;
    let waitset = anyhow::Context::context(wire::signals::waitset(), "tap")?;
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
    // One wait: (a sample is ready, the tick came).
    let wait = |timeout: Duration| {
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
        Ok((sample_ready, tick))
    };
    let started = Instant::now();
    let mut stats = TapStats::new(kind);
    let stop = Stop {
        deadline: args.seconds.map(|s| started + Duration::from_secs_f64(s)),
        limit: args.count.unwrap_or(u64::MAX),
    };
    let window = Window {
        started,
        json: args.json,
    };
    let stopped_by = watch(&tap, &mut stats, stop, window, wait)?;
    let elapsed_s = started.elapsed().as_secs_f64();
    if args.json {
        println!("{}", stats.json(instance.name(), elapsed_s, stopped_by));
    } else {
        println!("{}", stats.summary_line(elapsed_s));
    }
    Ok(())
}

/// The service's kind, and the checks of the options no parser makes.
fn check(args: &TapArgs) -> anyhow::Result<Kind> {
    let kind = Kind::of(&args.service)
        .ok_or_else(|| anyhow::anyhow!(TappedSubscriber::unknown_text(&args.service)))?;
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
    Ok(kind)
}

/// When the tap stops: at `deadline` (`--seconds`), after `limit` samples (`--count`).
struct Stop {
    deadline: Option<Instant>,
    limit: u64,
}

/// The once-a-second lines: on stdout, or on stderr when stdout is for `--json`.
struct Window {
    started: Instant,
    json: bool,
}

impl Window {
    fn print(&mut self, stats: &mut TapStats) {
        let line = stats.window_line(self.started.elapsed().as_secs_f64());
        self.started = Instant::now();
        if self.json {
            eprintln!("{line}");
        } else {
            println!("{line}");
        }
    }
}

/// Receives into `stats` until a stop, waking on `wait` (a sample ready, the tick); returns
/// what stopped it: "count", "seconds" or "signal".
fn watch(
    tap: &Tap,
    stats: &mut TapStats,
    stop: Stop,
    mut window: Window,
    mut wait: impl FnMut(Duration) -> anyhow::Result<(bool, bool)>,
) -> anyhow::Result<&'static str> {
    // History samples (rig/state, fields, identification keep the last one) need no event.
    tap.drain(stats, stop.limit)?;
    loop {
        if stats.received >= stop.limit {
            return Ok("count");
        }
        let timeout = match stop.deadline {
            Some(deadline) => {
                let left = deadline.saturating_duration_since(Instant::now());
                if left.is_zero() {
                    return Ok("seconds");
                }
                left
            }
            None => Duration::MAX,
        };
        let (sample_ready, tick) = wait(timeout)?;
        if sample_ready || !tick {
            let budget = stop.limit - stats.received;
            tap.drain(stats, budget)
                .with_context(|| format!("receiving from {}", stats.kind.name()))?;
        }
        if tick {
            window.print(stats);
        }
        // The 1 s tick bounds the wait, so a request is seen within a second.
        if wire::signals::requested().is_some() {
            return Ok("signal");
        }
    }
}
