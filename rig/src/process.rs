//! The rig process shell: runs the core in simulated time, paced to the wall clock (real time,
//! N× or as fast as possible), publishes `rig/state` (decimated, 500 Hz by default), answers
//! `rig/command` (request-response: accepted or refused with the reason) and writes `rig.csv`
//! as it goes. All IPC of the crate lives in this file; the core knows nothing of it.

use crate::builtin::BuiltinTest;
use crate::campaign::{Campaign, CampaignEvent};
use crate::codes;
use crate::config::RigConfig;
use crate::control::{AxisControl, ControlMode};
use crate::ids::{ActuatorId, Axis};
use crate::limits::LimitKind;
use crate::program::{Program, StopTransition};
use crate::rig::{Rig, RigCommand};
use crate::snapshot::ProgramStatus;
use iceoryx2::prelude::*;
use std::io::Write;
use std::path::PathBuf;
use std::time::{Duration, Instant};
use wire::rig::{RigCommandKind, RigReply, RigState};

type BoxError = Box<dyn std::error::Error + Send + Sync>;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Speed {
    Realtime,
    /// N× real time.
    Factor(f64),
    /// As fast as the core steps while a program runs; real time once it has ended.
    Max,
}

impl Speed {
    pub fn parse(text: &str) -> Result<Speed, String> {
        match text {
            "realtime" => Ok(Speed::Realtime),
            "max" => Ok(Speed::Max),
            n => match n.parse::<f64>() {
                Ok(f) if f.is_finite() && f > 0.0 => Ok(Speed::Factor(f)),
                _ => Err(format!(
                    "--speed {n:?}: expected realtime, max or a positive factor"
                )),
            },
        }
    }
}

#[derive(Clone, Debug)]
pub struct ProcessOptions {
    pub instance: String,
    pub config: RigConfig,
    pub seed: u64,
    /// Started at once, if any.
    pub program: Option<Program>,
    /// Tests run one after the other (each mounts its specimen), if any; exclusive with
    /// `program`.
    pub campaign: Option<Campaign>,
    /// Stretch rate and level of the built-in tests started over `rig/command`.
    pub test_rate_per_s: f64,
    pub test_stretch: f64,
    pub speed: Speed,
    pub publish_hz: f64,
    pub log_path: Option<PathBuf>,
    pub log_hz: f64,
    /// Stop after this much simulated time.
    pub duration_s: Option<f64>,
    /// Stop once the program has finished or stopped.
    pub exit_when_done: bool,
}

#[derive(Clone, Copy, Debug, Default)]
pub struct ProcessSummary {
    pub simulated_s: f64,
    pub wall_s: f64,
    pub samples_published: u64,
    pub rows_logged: u64,
    pub commands_accepted: u64,
    pub commands_refused: u64,
    pub limits_tripped: u32,
}

pub fn run(options: ProcessOptions) -> Result<ProcessSummary, BoxError> {
    let control_hz = options.config.control_hz;
    for (name, hz) in [
        ("publish_hz", options.publish_hz),
        ("log_hz", options.log_hz),
    ] {
        if !(hz.is_finite() && hz > 0.0 && hz <= control_hz) {
            return Err(format!("{name} {hz}: expected a rate in (0, {control_hz}] Hz").into());
        }
    }
    let publish_every = (control_hz / options.publish_hz).round().max(1.0) as u64;
    let log_every = (control_hz / options.log_hz).round().max(1.0) as u64;

    if options.program.is_some() && options.campaign.is_some() {
        return Err("a program and a campaign cannot run together: choose one".into());
    }
    if let Some(campaign) = &options.campaign {
        campaign.check_against(&options.config)?;
    }
    let instance = wire::Instance::new(&options.instance)?;
    let (node, removed) = instance.create_node("rig")?;
    if removed > 0 {
        eprintln!(
            "rig: cleaned {removed} dead node(s) of instance {}",
            instance.name()
        );
    }
    let publisher =
        wire::pubsub::ValuePublisher::<RigState>::create(&node, &wire::services::RIG_STATE)?;
    let command_service = node
        .service_builder(&ServiceName::new(wire::services::RIG_COMMAND)?)
        .request_response::<wire::RigCommand, RigReply>()
        .open_or_create()
        .map_err(|e| format!("service {}: {e:?}", wire::services::RIG_COMMAND))?;
    let server = command_service
        .server_builder()
        .create()
        .map_err(|e| format!("server {}: {e:?}", wire::services::RIG_COMMAND))?;

    eprintln!("rig: ready (instance {})", instance.name());
    let mut log = match &options.log_path {
        Some(path) => {
            let file =
                std::fs::File::create(path).map_err(|e| format!("log {}: {e}", path.display()))?;
            let mut w = std::io::BufWriter::new(file);
            writeln!(w, "{}", crate::log::csv_header())?;
            Some(w)
        }
        None => None,
    };
    let mut row = String::with_capacity(2048);

    let mut campaign = options.campaign.clone();
    // Index of the campaign test under way, published as `RigState::test_index`.
    let mut test_index = 0u32;
    let mut rig = Rig::new(options.config.clone(), options.seed)?;
    let mut summary = ProcessSummary::default();
    if let Some(program) = &options.program {
        rig.command(RigCommand::StartProgram(Box::new(program.clone())))
            .map_err(|e| format!("program refused: {e}"))?;
    }
    let started = Instant::now();
    let mut paced_from = (started, 0.0f64);
    let mut last_flush = started;
    let mut was_max = false;
    loop {
        // Commands, between publication periods.
        while let Some(active) = server
            .receive()
            .map_err(|e| format!("rig/command receive: {e:?}"))?
        {
            let reply = match handle(&mut rig, &active, &options) {
                Ok(()) => {
                    summary.commands_accepted += 1;
                    RigReply::accepted()
                }
                Err(reason) => {
                    summary.commands_refused += 1;
                    eprintln!("rig: command refused: {reason}");
                    RigReply::refused(&reason)
                }
            };
            active
                .send_copy(reply)
                .map_err(|e| format!("rig/command reply: {e:?}"))?;
        }

        if let Some(campaign) = campaign.as_mut() {
            match campaign.advance(&mut rig) {
                Ok(CampaignEvent::Started { index, test }) => {
                    test_index = index as u32;
                    eprintln!(
                        "rig: campaign test {}/{}: {:?} to λ {} at {} /s, started at t = {:.1} s",
                        index + 1,
                        campaign.tests().len(),
                        test.test,
                        test.stretch,
                        test.rate_per_s,
                        rig.state().t_s
                    )
                }
                Ok(CampaignEvent::Busy | CampaignEvent::Done) => {}
                Err(refusal) => return Err(format!("campaign halted: {refusal}").into()),
            }
        }
        for _ in 0..publish_every {
            rig.step();
            if let Some(w) = log.as_mut() {
                if rig.state().step.is_multiple_of(log_every) {
                    row.clear();
                    crate::log::write_csv_row(rig.state(), &mut row);
                    w.write_all(row.as_bytes())?;
                    summary.rows_logged += 1;
                }
            }
        }
        publisher.publish(RigState {
            test_index,
            ..to_wire(&rig, summary.samples_published)
        })?;
        summary.samples_published += 1;
        if let Some(w) = log.as_mut() {
            if last_flush.elapsed() >= Duration::from_millis(50) {
                w.flush()?;
                last_flush = Instant::now();
            }
        }

        let s = rig.state();
        let program_active = matches!(s.program, ProgramStatus::Running | ProgramStatus::Held);
        if options.duration_s.is_some_and(|d| s.t_s >= d) {
            break;
        }
        if options.exit_when_done {
            let done = match &campaign {
                Some(c) => c.is_done(&rig),
                None => !program_active && options.program.is_some(),
            };
            if done {
                break;
            }
        }
        // Pacing: the wall clock follows simulated time / factor.
        let factor = match options.speed {
            Speed::Realtime => Some(1.0),
            Speed::Factor(f) => Some(f),
            Speed::Max if program_active || campaign.as_ref().is_some_and(|c| !c.is_done(&rig)) => {
                None
            }
            Speed::Max => Some(1.0),
        };
        match factor {
            None => {
                was_max = true;
                // Check for termination requests every ~1000 periods without sleeping.
                if summary.samples_published.is_multiple_of(1000)
                    && node.wait(Duration::ZERO).is_err()
                {
                    break;
                }
            }
            Some(f) => {
                if was_max {
                    paced_from = (Instant::now(), s.t_s);
                    was_max = false;
                }
                let target = Duration::from_secs_f64(((s.t_s - paced_from.1) / f).max(0.0));
                let ahead = target.saturating_sub(paced_from.0.elapsed());
                if node.wait(ahead).is_err() {
                    break;
                }
            }
        }
    }
    if let Some(w) = log.as_mut() {
        w.flush()?;
    }
    summary.simulated_s = rig.state().t_s;
    summary.wall_s = started.elapsed().as_secs_f64();
    summary.limits_tripped = rig.state().limits_tripped;
    Ok(summary)
}

/// A `wire::RigCommand` to a core command, refused with a reason when malformed or refused.
fn handle(
    rig: &mut Rig,
    request: &wire::RigCommand,
    options: &ProcessOptions,
) -> Result<(), String> {
    if request.layout_version != wire::LAYOUT_VERSION {
        return Err(format!(
            "layout version {} is not {}",
            request.layout_version,
            wire::LAYOUT_VERSION
        ));
    }
    let kind = RigCommandKind::from_code(request.kind)
        .ok_or_else(|| format!("unknown command kind {}", request.kind))?;
    if !request.value.is_finite() {
        return Err("value is not a finite number".into());
    }
    let actuator = || {
        ActuatorId::ALL
            .get(request.channel as usize)
            .copied()
            .ok_or_else(|| format!("channel {} is not an actuator (0..6)", request.channel))
    };
    let axis = || {
        Axis::ALL
            .get(request.channel as usize)
            .copied()
            .ok_or_else(|| format!("channel {} is not an axis (0..3)", request.channel))
    };
    let command = match kind {
        RigCommandKind::StartProgram => {
            let text = wire::text::read_fixed(&request.text);
            let program = if !text.is_empty() {
                let path = PathBuf::from(&text);
                let toml = std::fs::read_to_string(&path)
                    .map_err(|e| format!("program {}: {e}", path.display()))?;
                let base = path.parent().map(PathBuf::from).unwrap_or_default();
                Program::from_toml(&toml, &base)?
            } else {
                let test = if request.value == codes::TEST_UNIAXIAL {
                    BuiltinTest::Uniaxial
                } else if request.value == codes::TEST_EQUIBIAXIAL {
                    BuiltinTest::Equibiaxial
                } else {
                    return Err(format!(
                        "built-in test {} is not 1 (uniaxial) or 2 (equibiaxial)",
                        request.value
                    ));
                };
                let mounted = rig.specimen().map(|s| s.config().loading);
                if mounted != Some(test.specimen().loading) {
                    return Err(format!(
                        "built-in test {test:?} needs its specimen; mounted: {mounted:?}"
                    ));
                }
                test.program(options.test_rate_per_s, options.test_stretch)?
            };
            RigCommand::StartProgram(Box::new(program))
        }
        RigCommandKind::Hold => RigCommand::HoldProgram,
        RigCommandKind::Resume => RigCommand::ResumeProgram,
        RigCommandKind::Stop => RigCommand::StopProgram {
            transition: Some(if request.value == 0.0 {
                StopTransition::Stay
            } else {
                StopTransition::RampToZero
            }),
        },
        RigCommandKind::SetMode => match request.value as u32 {
            codes::MODE_DISPLACEMENT => RigCommand::SetActuatorMode {
                actuator: actuator()?,
                mode: ControlMode::Displacement,
            },
            codes::MODE_FORCE => RigCommand::SetActuatorMode {
                actuator: actuator()?,
                mode: ControlMode::Force,
            },
            codes::MODE_CENTROID_DISPLACEMENT => RigCommand::SetAxisControl {
                axis: axis()?,
                control: AxisControl::Centroid(ControlMode::Displacement),
            },
            codes::MODE_CENTROID_FORCE => RigCommand::SetAxisControl {
                axis: axis()?,
                control: AxisControl::Centroid(ControlMode::Force),
            },
            codes::MODE_INDEPENDENT => RigCommand::SetAxisControl {
                axis: axis()?,
                control: AxisControl::Independent,
            },
            other => return Err(format!("mode code {other} is not 0..=4")),
        },
        RigCommandKind::SetLimit => {
            let id = actuator()?;
            let mut limits = rig.config().limits.channels[id.index()];
            let v = request.value;
            match request.limit {
                codes::LIMIT_STROKE_MIN_MM => limits.stroke_min_mm = v,
                codes::LIMIT_STROKE_MAX_MM => limits.stroke_max_mm = v,
                codes::LIMIT_FORCE_MIN_KN => limits.force_min_kn = v,
                codes::LIMIT_FORCE_MAX_KN => limits.force_max_kn = v,
                codes::LIMIT_FOLLOWING_ERROR_MM => limits.following_error_mm = v,
                codes::LIMIT_FOLLOWING_ERROR_KN => limits.following_error_kn = v,
                codes::LIMIT_RATE_MM_S => limits.rate_max_mm_s = v,
                other => return Err(format!("limit code {other} is not 0..=6")),
            }
            RigCommand::SetLimits {
                actuator: id,
                limits,
            }
        }
        RigCommandKind::EmergencyStop => RigCommand::EmergencyStop,
        RigCommandKind::SetPoint => RigCommand::SetSetpoint {
            channel: codes::channel(request.channel)
                .ok_or_else(|| format!("channel {} is not 0..12", request.channel))?,
            value: request.value,
        },
    };
    rig.command(command).map_err(|e| e.to_string())
}

/// The published sample. `command_mm` / `following_error_mm` carry kN for an actuator in
/// force control (its `mode` says which).
pub fn to_wire(rig: &Rig, sample_id: u64) -> RigState {
    let s = rig.state();
    let mut state = RigState {
        layout_version: wire::LAYOUT_VERSION,
        program_state: codes::program_state(s.program),
        sample_id,
        t_sim_s: s.t_s,
        t_published_ns: wire::monotonic_ns(),
        hydraulics_on: u32::from(s.hydraulics_on),
        specimen_stretch_x: s.specimen.stretch_x,
        specimen_stretch_y: s.specimen.stretch_y,
        specimen_rotation_rad: s.specimen.rotation_deg.to_radians(),
        specimen_centre_offset_mm: [s.specimen.centre_x_mm, s.specimen.centre_y_mm],
        load_case: codes::load_case(rig.specimen().map(|sp| sp.config().loading)),
        ..RigState::default()
    };
    if let Some(specimen) = rig.specimen() {
        let [x, y] = specimen.current_sections_mm2(s.specimen.stretch_x, s.specimen.stretch_y);
        state.specimen_section_x_mm2 = x;
        state.specimen_section_y_mm2 = y;
    }
    for id in ActuatorId::ALL {
        let a = &s.actuators[id.index()];
        let flags = LimitKind::ALL
            .iter()
            .enumerate()
            .filter(|(_, kind)| s.limits_tripped & kind.bit(id.index()) != 0)
            .fold(0u32, |acc, (k, _)| acc | 1 << k);
        state.actuators[id.index()] = wire::ActuatorState {
            position_mm: a.position_mm,
            command_mm: a.command,
            following_error_mm: a.error,
            force_kn: a.force_kn,
            mode: codes::actuator_mode(s.axes[id.axis().index()].control, a.mode),
            limit_flags: flags,
        };
    }
    for axis in Axis::ALL {
        state.axis_centre_mm[axis.index()] = s.axes[axis.index()].centre_mm;
        state.axis_elongation_mm[axis.index()] = s.axes[axis.index()].elongation_mm;
    }
    state
}
