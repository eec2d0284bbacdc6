//! Names of the actuators, axes and control channels.

use serde::{Deserialize, Serialize};

/// The six actuators, in the order of every per-actuator array of the crate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ActuatorId {
    XPlus = 0,
    XMinus = 1,
    YPlus = 2,
    YMinus = 3,
    ZPlus = 4,
    ZMinus = 5,
}

impl ActuatorId {
    pub const ALL: [ActuatorId; 6] = [
        ActuatorId::XPlus,
        ActuatorId::XMinus,
        ActuatorId::YPlus,
        ActuatorId::YMinus,
        ActuatorId::ZPlus,
        ActuatorId::ZMinus,
    ];

    pub fn index(self) -> usize {
        self as usize
    }

    pub fn axis(self) -> Axis {
        Axis::ALL[self.index() / 2]
    }

    pub fn name(self) -> &'static str {
        ["X+", "X-", "Y+", "Y-", "Z+", "Z-"][self.index()]
    }
}

/// The three axes, each an opposed pair of actuators.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Axis {
    X = 0,
    Y = 1,
    Z = 2,
}

impl Axis {
    pub const ALL: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];

    pub fn index(self) -> usize {
        self as usize
    }

    pub fn plus(self) -> ActuatorId {
        ActuatorId::ALL[2 * self.index()]
    }

    pub fn minus(self) -> ActuatorId {
        ActuatorId::ALL[2 * self.index() + 1]
    }

    pub fn name(self) -> &'static str {
        ["X", "Y", "Z"][self.index()]
    }
}

/// A quantity the controller (and a program) can drive.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Channel {
    /// One actuator on its own: position (mm) or force (kN) by its mode.
    Actuator(ActuatorId),
    /// Centroid mode: sum of the two displacements (mm) or mean pair force (kN).
    Elongation(Axis),
    /// Centroid mode: centre of the pair, half the difference of the displacements (mm).
    Centre(Axis),
}

/// As a program file names it: `x+`, `x.elongation`, `y.centre`.
impl std::fmt::Display for Channel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Channel::Actuator(id) => f.write_str(&id.name().to_ascii_lowercase()),
            Channel::Elongation(axis) => {
                write!(f, "{}.elongation", axis.name().to_ascii_lowercase())
            }
            Channel::Centre(axis) => write!(f, "{}.centre", axis.name().to_ascii_lowercase()),
        }
    }
}

impl Channel {
    /// Parse "x+", "x-", "x.elongation", "y.centre" (case-insensitive).
    pub fn parse(text: &str) -> Option<Channel> {
        let lower = text.trim().to_ascii_lowercase();
        let axis = match lower.as_bytes().first()? {
            b'x' => Axis::X,
            b'y' => Axis::Y,
            b'z' => Axis::Z,
            _ => return None,
        };
        match &lower[1..] {
            "+" => Some(Channel::Actuator(axis.plus())),
            "-" => Some(Channel::Actuator(axis.minus())),
            ".elongation" => Some(Channel::Elongation(axis)),
            ".centre" | ".center" => Some(Channel::Centre(axis)),
            _ => None,
        }
    }
}
