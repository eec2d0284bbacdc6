//! `dicstream bench pipeline`: the live bench's per-frame latency, sustained rate, drops and
//! CPU per process on this machine, and the simulated camera's CPU on the finite-element
//! cruciform (see `live::pipeline`).

use super::named_arg::named;
use anyhow::Result;
use correlator::settings::Method;
use live::pipeline::{measure, PipelineResult, PipelineSettings};
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct PipelineBenchArgs {
    /// Frame width and height, px.
    #[arg(long, default_value_t = 1024)]
    pub width: u32,
    #[arg(long, default_value_t = 1024)]
    pub height: u32,
    /// Sub-pixel method (with --zoi 33 for icgn1, icgn2 or icgn).
    #[arg(long, value_parser = named::<Method>(), default_value_t = Method::default())]
    pub method: Method,
    /// ZOI side and step, px.
    #[arg(long, default_value_t = 32)]
    pub zoi: usize,
    #[arg(long, default_value_t = 16)]
    pub step: usize,
    /// Correlator threads.
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Frames per second, or `max`: the highest rate without a dropped frame (trials of
    /// --seconds each at doubling, then bisected, rates).
    #[arg(long, default_value = "10")]
    pub fps: String,
    /// Length of the measured stream per trial (s of wall time).
    #[arg(long, default_value_t = 60.0)]
    pub seconds: f64,
    /// Parent folder of the trials' results folders.
    #[arg(long, default_value = "results/bench")]
    pub out: PathBuf,
    /// Print one JSON object (keys fps_sustained, frames, dropped, latency_ms{field,
    /// identification}{p50,p90,p99,p999,max}, latency_field_parts_ms{waiting, correlating,
    /// delivering}, cpu_cores, frame_gaps{missing, gaps, longest, after_renewal, skipped,
    /// lost}, renewal_costs{renewals, renewing, after[3], others: {fields, waiting,
    /// correlating, latency}}, camera_on_cruciform{width_px, height_px, mm_per_px,
    /// grip_stretch, frames, cpu_ms_per_frame, fps, cores}) instead of text.
    #[arg(long)]
    pub json: bool,
}

fn describe(r: &PipelineResult) -> String {
    let l = |name: &str| {
        r.latency_ms.get(name).map_or(String::new(), |p| {
            format!(
                "{name}: p50 {:.1} p90 {:.1} p99 {:.1} p99.9 {:.1} max {:.1} ms",
                p.p50, p.p90, p.p99, p.p999, p.max
            )
        })
    };
    let cpu: Vec<String> = r
        .cpu_cores
        .iter()
        .map(|(name, cores)| format!("{name} {:.0} %", 100.0 * cores))
        .collect();
    let parts = &r.latency_field_parts_ms;
    let part = |name: &str, p: &live::latency::Percentiles| {
        format!("{name} p50 {:.1} p99 {:.1}", p.p50, p.p99)
    };
    let g = &r.frame_gaps;
    let split = |n: Option<u64>| n.map_or("?".to_string(), |n| n.to_string());
    let gaps = format!(
        "not correlated: {} frame(s) in {} gap(s) of frame ids (longest {}), {} right after a reference renewal; the correlator skipped {} (superseded by a newer frame while busy) and lost {} (overwritten in its 2-frame queue)",
        g.missing,
        g.gaps,
        g.longest,
        g.after_renewal,
        split(g.skipped),
        split(g.lost)
    );
    let c = &r.renewal_costs;
    let cost = |name: &str, f: &live::pipeline::FieldCostMs| {
        format!(
            "{name} {:.1} / {:.1} / {:.1}",
            f.waiting, f.correlating, f.latency
        )
    };
    let renewals = format!(
        "{} reference renewal(s); medians of waiting / correlating / latency, ms: {}, {}, {}, {}, {}",
        c.renewals,
        cost("renewing field", &c.renewing),
        cost("next", &c.after[0]),
        cost("second", &c.after[1]),
        cost("third", &c.after[2]),
        cost("others", &c.others)
    );
    let budget = r.field_p99_budget_ms();
    let field_p99 = r.latency_ms.get("field").map_or(f64::NAN, |p| p.p99);
    format!(
        "{:.1} frames/s asked, {:.2} sustained; {} frames, {} dropped\n  latency from capture to {}\n    of which {}, {}, {} ms\n    field p99 {field_p99:.1} ms against the work's {budget:.1} ms (correlating p99 + one period): {}\n  latency from capture to {}\n  {}\n  {gaps}\n  CPU (100 % = one core): {}\n  results: {}",
        r.fps_requested,
        r.fps_sustained,
        r.frames,
        r.dropped,
        l("field"),
        part("waiting", &parts.waiting),
        part("correlating", &parts.correlating),
        part("delivering", &parts.delivering),
        if field_p99 <= budget { "within" } else { "over: frames queue" },
        l("identification"),
        renewals,
        cpu.join(", "),
        r.results.display()
    )
}

pub fn run(args: PipelineBenchArgs) -> Result<()> {
    let fps = match args.fps.as_str() {
        "max" => None,
        text => match text.parse::<f64>() {
            Ok(f) if f.is_finite() && f > 0.0 => Some(f),
            _ => anyhow::bail!("--fps {text:?}: expected a positive rate or max"),
        },
    };
    if !(args.seconds.is_finite() && args.seconds >= 5.0) {
        anyhow::bail!("--seconds {}: expected at least 5 s", args.seconds);
    }
    let settings = PipelineSettings {
        width_px: args.width,
        height_px: args.height,
        method: args.method,
        zoi_px: args.zoi,
        step_px: args.step,
        correlator_threads: args.threads,
        fps,
        seconds: args.seconds,
        results_dir: args.out.clone(),
        exe: std::env::current_exe()?,
    };
    let json = args.json;
    let result = measure(&settings, |trial| {
        if !json {
            println!("trial: {}", describe(trial));
        } else {
            eprintln!(
                "trial at {:.1} frames/s: {} dropped",
                trial.fps_requested, trial.dropped
            );
        }
    })?;
    if json {
        println!("{}", serde_json::to_string_pretty(&result)?);
    } else {
        println!(
            "bench pipeline, {}x{} px, {} ZOI {} px, step {} px, {} correlator thread(s):\n  {}",
            args.width,
            args.height,
            args.method,
            args.zoi,
            args.step,
            args.threads,
            describe(&result)
        );
        if let Some(c) = &result.camera_on_cruciform {
            println!(
                "  simulated camera on the finite-element cruciform (a default run's, {}x{} px at {} mm/px, equibiaxial grip stretch up to {}): {:.1} ms CPU per frame over {} frames, {:.2} core at {} frames/s",
                c.width_px, c.height_px, c.mm_per_px, c.grip_stretch, c.cpu_ms_per_frame, c.frames, c.cores, c.fps
            );
        }
    }
    Ok(())
}
