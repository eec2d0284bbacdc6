//! `dicstream rig --follow-csv FILE`: instead of the simulated machine, follow the CSV force
//! log a real test machine's software appends to, and publish its rows on `rig/state` in the
//! simulated rig's layout (see `rig::csv_follow`).

use anyhow::Context;
use rig::csv_follow::columns::{ForceUnit, LengthUnit, TimeUnit};
use rig::csv_follow::delimiter::Delimiter;
use rig::csv_follow::process::{run as follow, FollowOptions};
use rig::csv_follow::{ColumnSpec, CsvColumns};
use std::path::PathBuf;
use std::time::Duration;

#[derive(clap::Args, Debug, Clone)]
pub struct FollowCsvArgs {
    /// Follow this CSV, appended to by a test machine's software, instead of simulating the
    /// machine: one rig/state sample per row (the file is waited for if it does not exist)
    #[arg(long, value_name = "FILE", conflicts_with_all = ["program", "test", "campaign"])]
    pub follow_csv: Option<PathBuf>,
    /// With --follow-csv: the time column's name in the header (without its unit)
    #[arg(long, value_name = "NAME", requires = "follow_csv")]
    pub time_column: Option<String>,
    /// With --follow-csv: force columns of the X, Y and Z axes (at least one)
    #[arg(long, value_name = "NAME", requires = "follow_csv")]
    pub force_x_column: Option<String>,
    #[arg(long, value_name = "NAME", requires = "follow_csv")]
    pub force_y_column: Option<String>,
    #[arg(long, value_name = "NAME", requires = "follow_csv")]
    pub force_z_column: Option<String>,
    /// With --follow-csv: displacement (elongation) columns of the X, Y and Z axes, if logged
    #[arg(long, value_name = "NAME", requires = "follow_csv")]
    pub displacement_x_column: Option<String>,
    #[arg(long, value_name = "NAME", requires = "follow_csv")]
    pub displacement_y_column: Option<String>,
    #[arg(long, value_name = "NAME", requires = "follow_csv")]
    pub displacement_z_column: Option<String>,
    /// Unit of the time column: s, ms or min [default: as its header says, `Time (s)`]
    #[arg(long, requires = "follow_csv")]
    pub time_unit: Option<TimeUnit>,
    /// Unit of the force columns: N or kN [default: as their headers say]
    #[arg(long, requires = "follow_csv")]
    pub force_unit: Option<ForceUnit>,
    /// Unit of the displacement columns: mm, um or m [default: as their headers say]
    #[arg(long, requires = "follow_csv")]
    pub displacement_unit: Option<LengthUnit>,
    /// Cell delimiter: ",", ";" or "tab" (cells may be quoted, "4,5"; a comma inside a cell is
    /// a decimal comma)
    #[arg(long, default_value_t = Delimiter::Comma, requires = "follow_csv")]
    pub delimiter: Delimiter,
    /// Seconds added to the machine's time to put it on the camera's (camera − machine)
    #[arg(
        long,
        default_value_t = 0.0,
        allow_hyphen_values = true,
        requires = "follow_csv"
    )]
    pub offset_s: f64,
    /// Initial sections of the specimen normal to X and Y, mm² (Cauchy stress = force over
    /// the current section, which the identifier derives from them and the measured stretch)
    #[arg(long, default_value_t = 0.0, requires = "follow_csv")]
    pub section_x_mm2: f64,
    #[arg(long, default_value_t = 0.0, requires = "follow_csv")]
    pub section_y_mm2: f64,
    /// How often the file is looked at, ms
    #[arg(long, default_value_t = rig::csv_follow::process::DEFAULT_POLL_MS, requires = "follow_csv")]
    pub poll_ms: u64,
    /// End (exit 0) after this many seconds without a new row, once rows have come
    #[arg(long, value_name = "S", requires = "follow_csv")]
    pub idle_timeout_s: Option<f64>,
    /// Keep the follow's counts (rows, malformed_lines, restarts) in this JSON file, replaced
    /// as they change
    #[arg(long, value_name = "FILE", requires = "follow_csv")]
    pub counts_json: Option<PathBuf>,
}

/// The columns to follow (checked with the other options by `FollowOptions::check`).
pub fn columns(args: &FollowCsvArgs) -> anyhow::Result<CsvColumns> {
    let spec = |name: &Option<String>| name.as_deref().map(|n| ColumnSpec::new(n, None));
    let delimiter = args.delimiter.as_char();
    let columns = CsvColumns {
        time: ColumnSpec::new(
            args.time_column
                .as_deref()
                .ok_or_else(|| anyhow::anyhow!("--follow-csv needs --time-column NAME"))?,
            None,
        ),
        force: [
            spec(&args.force_x_column),
            spec(&args.force_y_column),
            spec(&args.force_z_column),
        ],
        displacement: [
            spec(&args.displacement_x_column),
            spec(&args.displacement_y_column),
            spec(&args.displacement_z_column),
        ],
        time_unit: args.time_unit,
        force_unit: args.force_unit,
        displacement_unit: args.displacement_unit,
        delimiter,
    };
    Ok(columns)
}

/// The follower's settings of the command line's flags.
pub fn options_of(args: &FollowCsvArgs, instance: String) -> anyhow::Result<FollowOptions> {
    let path = args.follow_csv.clone().expect("called with --follow-csv");
    let idle_timeout = match args.idle_timeout_s {
        Some(s) if s.is_finite() && s > 0.0 => Some(Duration::from_secs_f64(s)),
        Some(s) => anyhow::bail!("--idle-timeout-s {s}: expected a positive number of seconds"),
        None => None,
    };
    Ok(FollowOptions {
        instance,
        path,
        columns: columns(args)?,
        offset_s: args.offset_s,
        sections_mm2: [args.section_x_mm2, args.section_y_mm2],
        poll: Duration::from_millis(args.poll_ms),
        idle_timeout,
        counts_json: args.counts_json.clone(),
    })
}

/// Follows the log of `options`, checked first.
pub fn run(options: FollowOptions) -> anyhow::Result<()> {
    options.check().context("--follow-csv")?;
    let path = options.path.clone();
    let summary = follow(options).map_err(|e| wire::exit::in_context("rig", &e))?;
    eprintln!(
        "rig: followed {}: {} rows published, {} malformed lines skipped, {} truncation(s) or \
         rotation(s){}",
        path.display(),
        summary.counters.rows,
        summary.counters.malformed_lines,
        summary.counters.restarts,
        if summary.stopped_by_signal {
            "; stopped by signal"
        } else {
            "; idle"
        }
    );
    Ok(())
}
