//! The units a user or a machine's file names, each with its factor to the unit the code
//! computes in (s, N, mm, MPa): one definition for the rig's follower of a machine's log and
//! the identifier's data files.

/// Seconds, milliseconds or minutes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeUnit {
    S,
    Ms,
    Min,
}

/// Newtons or kilonewtons.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ForceUnit {
    Newton,
    KiloNewton,
}

/// Millimetres, micrometres or metres.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LengthUnit {
    Mm,
    Um,
    M,
}

/// A stress: MPa (= N/mm²), kPa, Pa or GPa.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StressUnit {
    MPa,
    KPa,
    Pa,
    GPa,
}

crate::named!(TimeUnit, "time unit", { S => "s" | "sec", Ms => "ms", Min => "min" });

impl TimeUnit {
    pub fn to_s(self) -> f64 {
        match self {
            TimeUnit::S => 1.0,
            TimeUnit::Ms => 1e-3,
            TimeUnit::Min => 60.0,
        }
    }
}

crate::named!(ForceUnit, "force unit", { Newton => "N", KiloNewton => "kN" | "KN" });

impl ForceUnit {
    pub fn to_n(self) -> f64 {
        match self {
            ForceUnit::Newton => 1.0,
            ForceUnit::KiloNewton => 1e3,
        }
    }
}

crate::named!(LengthUnit, "displacement unit", { Mm => "mm", Um => "um" | "µm", M => "m" });

impl LengthUnit {
    pub fn to_mm(self) -> f64 {
        match self {
            LengthUnit::Mm => 1.0,
            LengthUnit::Um => 1e-3,
            LengthUnit::M => 1e3,
        }
    }
}

crate::named!(StressUnit, "stress unit", {
    MPa => "MPa" | "N/mm²" | "N/mm2" | "N/mm^2",
    KPa => "kPa",
    Pa => "Pa",
    GPa => "GPa",
});

impl StressUnit {
    pub fn to_mpa(self) -> f64 {
        match self {
            StressUnit::MPa => 1.0,
            StressUnit::KPa => 1e-3,
            StressUnit::Pa => 1e-6,
            StressUnit::GPa => 1e3,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::names::Named;

    #[test]
    fn units_read_as_written_and_convert() {
        assert_eq!(ForceUnit::parse_name("kN").unwrap().to_n(), 1e3);
        assert_eq!(LengthUnit::parse_name("m").unwrap().to_mm(), 1e3);
        assert_eq!(StressUnit::parse_name("N/mm²").unwrap(), StressUnit::MPa);
        assert_eq!(StressUnit::parse_name("kPa").unwrap().to_mpa(), 1e-3);
        assert!(StressUnit::parse_name("psi").is_err());
    }
}
