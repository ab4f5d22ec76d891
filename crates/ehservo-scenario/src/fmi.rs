//! The FMI 3.0 contract that `ehservo fmu` (which writes the FMU) and
//! `ehservo-ffi` (whose `fmi3*` functions serve it) share: the kinds of
//! FMU, their variables with value references and units, and the
//! instantiation token that ties a binary to the scenario it was exported
//! with. The archive and its `modelDescription.xml` are written by the
//! lab's `ehservo::fmu`.
//!
//! Angles are in rad (SI, as everywhere in the C ABI); `e_deg` and
//! `e_max_deg` are in degrees as `summary.json` gives them. On a linear
//! axis ([`variables_on`]) the position is `y` in m and the error's display
//! `e_mm` and metric `e_max` are in mm, at the same value references. The
//! plant FMU's variables ([`plant_variables`]) depend on its plant: x in
//! the same units, the pressures in Pa, and a load input on a cylinder.
/// The FMU's `modelIdentifier` (and the binary's file stem).
pub const MODEL_IDENTIFIER: &str = "ehservo";

/// The platform folder of the binary.
pub const PLATFORM: &str = "x86_64-linux";

/// Which FMU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FmuKind {
    /// The controller alone: inputs θ, θ̇, θ̈; output u.
    Controller,
    /// The whole loop (plant, actuator, sensors, controller): no inputs.
    ClosedLoop,
    /// The plant with its actuator: inputs u and, when the plant takes
    /// one, an external load; outputs x and the pressures
    /// ([`plant_variables`]).
    Plant,
}

impl FmuKind {
    /// Its name in the instantiation token.
    pub fn as_str(self) -> &'static str {
        match self {
            FmuKind::Controller => "controller",
            FmuKind::ClosedLoop => "closed-loop",
            FmuKind::Plant => "plant",
        }
    }
}

/// A variable's role.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Causality {
    /// The independent variable, time.
    Independent,
    /// Set by the importer.
    Input,
    /// Computed by the FMU.
    Output,
}

/// One Float64 variable of an FMU.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Variable {
    /// Its value reference.
    pub vr: u32,
    /// Its name.
    pub name: &'static str,
    /// Its role.
    pub causality: Causality,
    /// Its unit (a `<Unit>` of the model description).
    pub unit: &'static str,
    /// What it is.
    pub description: &'static str,
}

/// Value references: the same numbers in both kinds where they mean the
/// same thing.
pub mod vr {
    /// Time (s).
    pub const TIME: u32 = 0;
    /// θ (rad).
    pub const THETA: u32 = 1;
    /// θ̇ (rad/s).
    pub const THETA_DOT: u32 = 2;
    /// θ̈ (rad/s²).
    pub const THETA_DDOT: u32 = 3;
    /// u (V).
    pub const U: u32 = 4;
    /// θd (rad).
    pub const THETA_D: u32 = 5;
    /// e = θd − θ (rad).
    pub const E: u32 = 6;
    /// e in degrees.
    pub const E_DEG: u32 = 7;
    /// max |e| over t ≥ settle so far (deg).
    pub const E_MAX_DEG: u32 = 8;
    /// What the plant receives after the actuator (V).
    pub const U_PLANT: u32 = 9;
    /// The plant FMU's external load input (N, or N·m on a rotary axis).
    pub const F_LOAD: u32 = 10;
    /// The plant FMU's first pressure output; the i-th pressure state of
    /// the plant is `PRESSURE + i`.
    pub const PRESSURE: u32 = 16;
}

const TIME: Variable = Variable {
    vr: vr::TIME,
    name: "time",
    causality: Causality::Independent,
    unit: "s",
    description: "Simulation time",
};

const CONTROLLER: &[Variable] = &[
    TIME,
    Variable {
        vr: vr::THETA,
        name: "theta",
        causality: Causality::Input,
        unit: "rad",
        description: "Measured angle θ",
    },
    Variable {
        vr: vr::THETA_DOT,
        name: "theta_dot",
        causality: Causality::Input,
        unit: "rad/s",
        description: "Measured angular velocity θ̇",
    },
    Variable {
        vr: vr::THETA_DDOT,
        name: "theta_ddot",
        causality: Causality::Input,
        unit: "rad/s2",
        description: "Measured angular acceleration θ̈",
    },
    Variable {
        vr: vr::U,
        name: "u",
        causality: Causality::Output,
        unit: "V",
        description: "Command to the servo valve, the law at the current sample (direct feedthrough of the inputs)",
    },
    Variable {
        vr: vr::THETA_D,
        name: "theta_d",
        causality: Causality::Output,
        unit: "rad",
        description: "The scenario's reference θd at the current sample",
    },
];

const CLOSED_LOOP: &[Variable] = &[
    TIME,
    Variable {
        vr: vr::THETA,
        name: "theta",
        causality: Causality::Output,
        unit: "rad",
        description: "Angle θ of the plant",
    },
    Variable {
        vr: vr::THETA_DOT,
        name: "theta_dot",
        causality: Causality::Output,
        unit: "rad/s",
        description: "Angular velocity θ̇ of the plant",
    },
    Variable {
        vr: vr::THETA_DDOT,
        name: "theta_ddot",
        causality: Causality::Output,
        unit: "rad/s2",
        description: "Angular acceleration θ̈ of the plant",
    },
    Variable {
        vr: vr::U,
        name: "u",
        causality: Causality::Output,
        unit: "V",
        description: "The controller's command",
    },
    Variable {
        vr: vr::THETA_D,
        name: "theta_d",
        causality: Causality::Output,
        unit: "rad",
        description: "Reference θd",
    },
    Variable {
        vr: vr::E,
        name: "e",
        causality: Causality::Output,
        unit: "rad",
        description: "Tracking error e = θd − θ",
    },
    Variable {
        vr: vr::E_DEG,
        name: "e_deg",
        causality: Causality::Output,
        unit: "deg",
        description: "Tracking error in degrees",
    },
    Variable {
        vr: vr::E_MAX_DEG,
        name: "e_max_deg",
        causality: Causality::Output,
        unit: "deg",
        description: "max |e| over the samples at t >= simulation.settle so far (summary.json's e_max_deg at the horizon; 0 before settle)",
    },
    Variable {
        vr: vr::U_PLANT,
        name: "u_plant",
        causality: Causality::Output,
        unit: "V",
        description: "What the plant receives after the actuator",
    },
];

/// The variables of a kind of FMU on `axis`: a rotary axis's are
/// [`variables`]; on a linear one the position is `y` (m, m/s, m/s2), the
/// error in the display unit `e_mm` and the metric `e_max` (mm), with the
/// same value references.
pub fn variables_on(kind: FmuKind, axis: crate::axis::Axis) -> Vec<Variable> {
    let vars = variables(kind);
    if axis == crate::axis::Axis::Rotary {
        return vars.to_vec();
    }
    vars.iter()
        .map(|v| {
            let (name, unit, description) = match v.vr {
                vr::THETA => ("y", "m", "Rod position y"),
                vr::THETA_DOT => ("y_dot", "m/s", "Rod velocity ẏ"),
                vr::THETA_DDOT => ("y_ddot", "m/s2", "Rod acceleration ÿ"),
                vr::THETA_D => ("y_d", "m", "Reference yd"),
                vr::E => ("e", "m", "Tracking error e = yd − y"),
                vr::E_DEG => ("e_mm", "mm", "Tracking error in millimetres"),
                vr::E_MAX_DEG => (
                    "e_max",
                    "mm",
                    "max |e| over the samples at t >= simulation.settle so far (summary.json's e_max, in mm, at the horizon; 0 before settle)",
                ),
                _ => (v.name, v.unit, v.description),
            };
            Variable {
                name,
                unit,
                description,
                ..*v
            }
        })
        .collect()
}

/// The variables of a kind of FMU (a rotary axis: [`variables_on`] gives
/// a linear one's). The plant FMU's depend on its plant:
/// [`plant_variables`].
pub fn variables(kind: FmuKind) -> &'static [Variable] {
    match kind {
        FmuKind::Controller => CONTROLLER,
        FmuKind::ClosedLoop => CLOSED_LOOP,
        FmuKind::Plant => PLANT,
    }
}

/// The plant FMU's variables that every plant has (x as the closed loop's,
/// u in, u_plant out); [`plant_variables`] adds a plant's load input and
/// pressures.
const PLANT: &[Variable] = &[
    TIME,
    CLOSED_LOOP[1],
    CLOSED_LOOP[2],
    CLOSED_LOOP[3],
    Variable {
        vr: vr::U,
        name: "u",
        causality: Causality::Input,
        unit: "V",
        description: "Command to the servo valve, held over each communication step",
    },
    Variable {
        vr: vr::U_PLANT,
        name: "u_plant",
        causality: Causality::Output,
        unit: "V",
        description: "What the plant receives after the actuator",
    },
];

/// The plant FMU's variables on `axis`: the input `u` (V) and, when the
/// plant takes one (`external_load`), `f_load` (N on a linear axis, N.m
/// on a rotary one); the outputs x in the axis's SI unit as the closed
/// loop's (`theta` … in rad, or `y` … in m), `u_plant` (V), and each of
/// the plant's `states` in Pa, at `vr::PRESSURE + i` for its index `i`
/// among `states`.
pub fn plant_variables(
    axis: crate::axis::Axis,
    states: &'static [ehservo_core::control::Signal],
    external_load: bool,
) -> Vec<Variable> {
    let mut out = variables_on(FmuKind::Plant, axis);
    if external_load {
        let (unit, description) = match axis {
            crate::axis::Axis::Linear | crate::axis::Axis::Force | crate::axis::Axis::Pressure => (
                "N",
                "External force on the rod, opposing extension, added to the scenario's load",
            ),
            crate::axis::Axis::Rotary => (
                "N.m",
                "External torque, opposing positive rotation, added to the scenario's load",
            ),
        };
        out.push(Variable {
            vr: vr::F_LOAD,
            name: "f_load",
            causality: Causality::Input,
            unit,
            description,
        });
    }
    for (i, s) in states.iter().enumerate() {
        if s.unit == "Pa" {
            out.push(Variable {
                vr: vr::PRESSURE + i as u32,
                name: s.key,
                causality: Causality::Output,
                unit: "Pa",
                description: s.doc,
            });
        }
    }
    out
}

/// The instantiation token of an FMU of `kind` built from `scenario_toml`:
/// the kind and the scenario file's FNV-1a fingerprint
/// ([`ehservo_wire::fnv1a`], 64 bits; not a security measure: it catches
/// resources swapped by mistake).
pub fn token(kind: FmuKind, scenario_toml: &str) -> String {
    format!(
        "{{ehservo-{}-{:016x}}}",
        kind.as_str(),
        ehservo_wire::fnv1a(scenario_toml.as_bytes())
    )
}

/// Every kind of FMU.
pub const KINDS: [FmuKind; 3] = [FmuKind::Controller, FmuKind::ClosedLoop, FmuKind::Plant];

/// An instantiation token that is not this scenario's: the token given
/// and the two it could have been.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "the instantiation token {given:?} is not {:?}, {:?} or {:?}: resources/scenario.toml is not the file this FMU was exported with",
    expected[0],
    expected[1],
    expected[2]
)]
pub struct TokenError {
    /// The token the importer passed.
    pub given: String,
    /// The controller FMU's, the closed loop's and the plant's tokens of
    /// the scenario.
    pub expected: [String; 3],
}

/// The kind a token names, if it is one of ours for exactly this scenario
/// text; otherwise why not.
pub fn check_token(token_text: &str, scenario_toml: &str) -> Result<FmuKind, TokenError> {
    for kind in KINDS {
        if token_text == token(kind, scenario_toml) {
            return Ok(kind);
        }
    }
    Err(TokenError {
        given: token_text.to_string(),
        expected: KINDS.map(|k| token(k, scenario_toml)),
    })
}
