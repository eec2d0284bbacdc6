//! The CSV log of the rig: one header, one row per logged snapshot. Rows are formatted into a
//! caller-owned `String` (reused, so no allocation once it has grown).

use crate::ids::{ActuatorId, Axis};
use crate::snapshot::{ProgramStatus, RigSnapshot};
use crate::strain::ControlColumns;
use std::fmt::Write;

pub fn csv_header() -> String {
    let mut h = String::from("t_s,program,hydraulics_on,limits_tripped");
    for id in ActuatorId::ALL {
        let n = id.name();
        for field in ["position_mm", "command", "error", "force_n", "valve"] {
            let _ = write!(h, ",{n}_{field}");
        }
    }
    for axis in Axis::ALL {
        let n = axis.name();
        let _ = write!(h, ",{n}_centre_mm,{n}_elongation_mm,{n}_force_n");
    }
    h.push_str(",stretch_x,stretch_y,rotation_deg,centre_x_mm,centre_y_mm,broken");
    // Who drives the X and Y set-points: displacement (programs, campaigns), strain (the strain
    // loop on the correlator's fields) or held (strain control held by an interlock or waiting
    // for its first field); the strain loop's target log strains, empty under displacement.
    h.push_str(",control,target_log_exx,target_log_eyy");
    h
}

pub fn program_code(status: ProgramStatus) -> u8 {
    match status {
        ProgramStatus::Idle => 0,
        ProgramStatus::Running => 1,
        ProgramStatus::Held => 2,
        ProgramStatus::Stopped => 3,
        ProgramStatus::Finished => 4,
    }
}

/// Appends one row (with its newline) to `out`, under displacement control.
pub fn write_csv_row(s: &RigSnapshot, out: &mut String) {
    write_csv_row_with(s, &ControlColumns::DISPLACEMENT, out)
}

/// Appends one row (with its newline) to `out`, with its control columns.
pub fn write_csv_row_with(s: &RigSnapshot, control: &ControlColumns, out: &mut String) {
    let _ = write!(
        out,
        "{:.6},{},{},{}",
        s.t_s,
        program_code(s.program),
        u8::from(s.hydraulics_on),
        s.limits_tripped
    );
    for a in &s.actuators {
        // The command and its error are a force in force control: N, as every force here.
        let unit = match a.mode {
            Some(crate::control::ControlMode::Force) => 1e3,
            _ => 1.0,
        };
        let _ = write!(
            out,
            ",{:.6},{:.6},{:.6},{:.6},{:.6}",
            a.position_mm,
            a.command * unit,
            a.error * unit,
            a.force_kn * 1e3,
            a.valve
        );
    }
    for x in &s.axes {
        let _ = write!(
            out,
            ",{:.6},{:.6},{:.6}",
            x.centre_mm,
            x.elongation_mm,
            x.force_kn * 1e3
        );
    }
    let k = &s.specimen;
    let _ = write!(
        out,
        ",{:.6},{:.6},{:.4},{:.6},{:.6},{},{}",
        k.stretch_x,
        k.stretch_y,
        k.rotation_deg,
        k.centre_x_mm,
        k.centre_y_mm,
        u8::from(k.broken),
        control.mode.name()
    );
    match control.target_log {
        Some([x, y]) => {
            let _ = writeln!(out, ",{x:.6},{y:.6}");
        }
        None => out.push_str(",,\n"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::ControlMode;

    #[test]
    fn forces_are_newtons_also_as_a_command_and_its_error() {
        let mut s = RigSnapshot::default();
        s.actuators[0].mode = Some(ControlMode::Force);
        s.actuators[0].command = 1.5; // kN
        s.actuators[0].error = -0.002;
        s.actuators[0].force_kn = 1.502;
        s.actuators[1].mode = Some(ControlMode::Displacement);
        s.actuators[1].command = 2.25; // mm
        let mut row = String::new();
        write_csv_row(&s, &mut row);
        let header = csv_header();
        let names: Vec<&str> = header.split(',').collect();
        let cells: Vec<&str> = row.trim_end().split(',').collect();
        assert_eq!(names.len(), cells.len());
        let cell = |name: &str| -> f64 {
            let k = names.iter().position(|n| *n == name).unwrap();
            cells[k].parse().unwrap()
        };
        let (a, b) = (ActuatorId::ALL[0].name(), ActuatorId::ALL[1].name());
        assert_eq!(cell(&format!("{a}_command")), 1500.0);
        assert_eq!(cell(&format!("{a}_error")), -2.0);
        assert_eq!(cell(&format!("{a}_force_n")), 1502.0);
        assert_eq!(cell(&format!("{b}_command")), 2.25);
    }
}
