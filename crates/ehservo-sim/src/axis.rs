//! The quantity a plant's output is: an angle (a rotary axis, the paper's
//! motor) or a length (a linear axis, a cylinder's rod).
//!
//! Everything inside the loop is SI: rad or m, and their derivatives. What
//! a person reads is in the axis's display unit: degrees for a rotary
//! axis, millimetres for a linear one. The names of trace columns and
//! metrics follow from the axis ([`Axis::column`], [`Axis::metric`]): a
//! rotary axis keeps the names the paper's scenarios always had
//! (`theta_deg`, `e_deg`, `e_max_deg`), a linear one says `y_mm`, `e_mm`
//! and `e_max` with `unit = "mm"` beside it.
//!
//! **The loop's quantity.** A loop may close on a force or a pressure
//! instead of the position (issue #49 item 1, `[reference] quantity`,
//! docs/force-control.md): its axis is then [`Axis::Force`] (N inside,
//! kN outside: `f_kN`, `e_kN`) or [`Axis::Pressure`] (the load pressure
//! p_L = p_A − α·p_B, Pa inside, bar outside: `p_l_bar`). The controller
//! then measures x = (q, ẏ, ÿ): the quantity and the rod's motion, whose
//! columns keep the rod's axis ([`Axis::motion`]: `y_dot_mm_s`).

use ehservo_core::math::DR;
use serde::{Deserialize, Serialize};

/// A plant's output quantity.
///
/// ```
/// use ehservo_sim::axis::Axis;
///
/// // SI inside, the display unit outside: π rad is 180°, 0.012 m is 12 mm.
/// assert!((Axis::Rotary.display(std::f64::consts::PI) - 180.0).abs() < 1e-12);
/// assert_eq!(Axis::Linear.display(0.012), 12.0);
/// assert_eq!(Axis::Linear.to_si(12.0), 0.012);
/// // Names follow the axis: trace columns, metrics, the laws' SI units.
/// assert_eq!(Axis::Rotary.column("_dot", "_s"), "theta_dot_deg_s");
/// assert_eq!(Axis::Linear.column("_dot", "_s"), "y_dot_mm_s");
/// assert_eq!(Axis::Rotary.metric("e_max"), "e_max_deg");
/// assert_eq!(Axis::Linear.metric("e_max"), "e_max");
/// assert_eq!(Axis::Linear.si_name("z1_rad_s"), "z1_m_s");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Axis {
    /// An angle θ: SI rad, shown in degrees.
    #[default]
    Rotary,
    /// A length y: SI m, shown in millimetres.
    Linear,
    /// A force F (a load cell's): SI N, shown in kilonewtons.
    Force,
    /// A load pressure p_L = p_A − α·p_B: SI Pa, shown in bar.
    Pressure,
}

/// What a loop closes on: `[reference] quantity` (default `"position"`).
///
/// ```
/// use ehservo_sim::axis::{Axis, Quantity};
///
/// assert_eq!(Quantity::Position.axis_on(Axis::Linear), Axis::Linear);
/// assert_eq!(Quantity::Force.axis_on(Axis::Linear), Axis::Force);
/// assert_eq!(Quantity::LoadPressure.axis_on(Axis::Linear), Axis::Pressure);
/// ```
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum Quantity {
    /// The plant's position (the rod's y, or θ): every loop before issue #49.
    #[default]
    Position,
    /// The environment's force on the rod, as a load cell between the rod
    /// and the environment measures it (N).
    Force,
    /// The load pressure p_L = p_A − α·p_B, α = A_B/A_A (Pa).
    LoadPressure,
}

impl Quantity {
    /// The scenario's spelling.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Position => "position",
            Quantity::Force => "force",
            Quantity::LoadPressure => "load-pressure",
        }
    }

    /// Whether this is the default, the position.
    pub fn is_position(&self) -> bool {
        *self == Quantity::Position
    }

    /// The loop's axis on a plant whose own axis is `plant`.
    pub fn axis_on(self, plant: Axis) -> Axis {
        match self {
            Quantity::Position => plant,
            Quantity::Force => Axis::Force,
            Quantity::LoadPressure => Axis::Pressure,
        }
    }
}

impl Axis {
    /// `"rotary"` or `"linear"`.
    pub fn name(self) -> &'static str {
        match self {
            Axis::Rotary => "rotary",
            Axis::Linear => "linear",
            Axis::Force => "force",
            Axis::Pressure => "pressure",
        }
    }

    /// What is measured: `"angle"` or `"length"`.
    pub fn quantity(self) -> &'static str {
        match self {
            Axis::Rotary => "angle",
            Axis::Linear => "length",
            Axis::Force => "force",
            Axis::Pressure => "load pressure",
        }
    }

    /// The position's symbol in names: `theta` or `y` (`f`, `p_l` for a
    /// force or a load pressure).
    pub fn symbol(self) -> &'static str {
        match self {
            Axis::Rotary => "theta",
            Axis::Linear => "y",
            Axis::Force => "f",
            Axis::Pressure => "p_l",
        }
    }

    /// The position's symbol in text: θ or y.
    pub fn letter(self) -> &'static str {
        match self {
            Axis::Rotary => "θ",
            Axis::Linear => "y",
            Axis::Force => "F",
            Axis::Pressure => "p_L",
        }
    }

    /// The SI unit of the position: `rad` or `m`.
    pub fn si_unit(self) -> &'static str {
        match self {
            Axis::Rotary => "rad",
            Axis::Linear => "m",
            Axis::Force => "N",
            Axis::Pressure => "Pa",
        }
    }

    /// The display unit as it appears in names: `deg` or `mm`.
    pub fn unit(self) -> &'static str {
        match self {
            Axis::Rotary => "deg",
            Axis::Linear => "mm",
            Axis::Force => "kN",
            Axis::Pressure => "bar",
        }
    }

    /// The display unit as it is printed after a number: `°` or ` mm`.
    pub fn suffix(self) -> &'static str {
        match self {
            Axis::Rotary => "°",
            Axis::Linear => " mm",
            Axis::Force => " kN",
            Axis::Pressure => " bar",
        }
    }

    /// The display unit as a table's heading gives it: `°` or `mm`.
    pub fn symbol_unit(self) -> &'static str {
        match self {
            Axis::Rotary => "°",
            Axis::Linear => "mm",
            Axis::Force => "kN",
            Axis::Pressure => "bar",
        }
    }

    /// The display unit in an axis label: `deg` or `mm`.
    pub fn label_unit(self) -> &'static str {
        self.unit()
    }

    /// An SI position (or a derivative of it) in the display unit: rad →
    /// degrees by division by π/180 (the bits the paper's outputs always
    /// had), m → mm by multiplication by 1000.
    #[inline(always)]
    pub fn display(self, si: f64) -> f64 {
        match self {
            Axis::Rotary => si / DR,
            Axis::Linear => si * 1e3,
            Axis::Force => si / 1e3,
            Axis::Pressure => si / 1e5,
        }
    }

    /// A position in the display unit in SI (degrees → rad by `·π/180`,
    /// the conversion the scenarios' `_deg` keys always had; mm → m by
    /// division by 1000).
    #[inline]
    pub fn to_si(self, shown: f64) -> f64 {
        match self {
            Axis::Rotary => shown * DR,
            Axis::Linear => shown / 1e3,
            Axis::Force => shown * 1e3,
            Axis::Pressure => shown * 1e5,
        }
    }

    /// A trace column for the position or a derivative: `stem` is what
    /// follows the symbol (`""`, `"_d"`, `"_dot"`, `"_meas"` …) and `per`
    /// the time unit's suffix (`""`, `"_s"`, `"_s2"`):
    /// `theta_dot_deg_s`, `y_dot_mm_s`.
    pub fn column(self, stem: &str, per: &str) -> String {
        format!("{}{stem}_{}{per}", self.symbol(), self.unit())
    }

    /// A metric's name: a rotary axis keeps the `_deg` suffix its keys
    /// always had (`e_max_deg`); a linear one has the bare name, with the
    /// unit given beside it.
    pub fn metric(self, bare: &str) -> String {
        match self {
            Axis::Rotary => format!("{bare}_deg"),
            Axis::Linear | Axis::Force | Axis::Pressure => bare.to_string(),
        }
    }

    /// Whether x is a position (a rotary or a linear axis), not a force
    /// or a pressure.
    pub fn is_position(self) -> bool {
        matches!(self, Axis::Rotary | Axis::Linear)
    }

    /// The axis of x's second and third channels: a position's own; the
    /// rod's (linear) on a force or pressure loop, whose controller
    /// measures x = (q, ẏ, ÿ) (the motion a force law feeds forward).
    pub fn motion(self) -> Axis {
        match self {
            Axis::Rotary | Axis::Linear => self,
            Axis::Force | Axis::Pressure => Axis::Linear,
        }
    }

    /// A controller signal's SI name or unit rewritten for this axis: the
    /// laws are written in rad, and on a linear axis the same law works
    /// in m. Every `rad` token of a name (`z1_rad_s` → `z1_m_s`) or unit
    /// (`rad/s³` → `m/s³`) becomes `m`; nothing changes on a rotary axis.
    pub fn si_name(self, name: &str) -> String {
        match self {
            Axis::Rotary | Axis::Force | Axis::Pressure => name.to_string(),
            Axis::Linear => {
                let mut out = String::with_capacity(name.len());
                let mut rest = name;
                while let Some(i) = rest.find("rad") {
                    let before = rest[..i].chars().next_back();
                    let after = rest[i + 3..].chars().next();
                    let word = |c: Option<char>| c.is_none_or(|c| !c.is_ascii_alphanumeric());
                    out.push_str(&rest[..i]);
                    out.push_str(if word(before) && word(after) {
                        "m"
                    } else {
                        "rad"
                    });
                    rest = &rest[i + 3..];
                }
                out.push_str(rest);
                out
            }
        }
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact conversions are the point
mod tests {
    use super::*;

    #[test]
    fn names_keep_the_rotary_spelling_and_say_mm_on_a_linear_axis() {
        let r = Axis::Rotary;
        assert_eq!(r.column("_d", ""), "theta_d_deg");
        assert_eq!(r.column("", ""), "theta_deg");
        assert_eq!(r.column("_dot", "_s"), "theta_dot_deg_s");
        assert_eq!(r.column("_ddot_meas", "_s2"), "theta_ddot_meas_deg_s2");
        assert_eq!(r.metric("e_max"), "e_max_deg");
        let l = Axis::Linear;
        assert_eq!(l.column("_d", ""), "y_d_mm");
        assert_eq!(l.column("_dot", "_s"), "y_dot_mm_s");
        assert_eq!(l.metric("e_max"), "e_max");
    }

    #[test]
    fn conversions() {
        // 1 rad is 180/π degrees; 0.0125 m is 12.5 mm.
        assert_eq!(Axis::Rotary.display(1.0), 1.0 / DR);
        assert_eq!(Axis::Linear.display(0.0125), 12.5);
        assert_eq!(Axis::Linear.to_si(12.5), 0.0125);
        assert_eq!(Axis::Rotary.to_si(5.0), 5.0 * DR);
    }

    #[test]
    fn force_and_pressure_show_kn_and_bar() {
        // 20 000 N is 20 kN; 50e5 Pa is 50 bar; the rod's motion keeps mm.
        assert_eq!(Axis::Force.display(20_000.0), 20.0);
        assert_eq!(Axis::Force.to_si(20.0), 20_000.0);
        assert_eq!(Axis::Pressure.display(5e6), 50.0);
        assert_eq!(Axis::Pressure.to_si(50.0), 5e6);
        assert_eq!(Axis::Force.column("", ""), "f_kN");
        assert_eq!(Axis::Force.column("_d", ""), "f_d_kN");
        assert_eq!(Axis::Pressure.column("", ""), "p_l_bar");
        assert_eq!(Axis::Force.motion().column("_dot", "_s"), "y_dot_mm_s");
        assert_eq!(Axis::Force.metric("e_max"), "e_max");
        assert_eq!(Axis::Force.si_name("p_N"), "p_N");
        assert!(!Axis::Force.is_position() && Axis::Linear.is_position());
    }

    #[test]
    fn si_names_swap_whole_rad_tokens_only() {
        let l = Axis::Linear;
        assert_eq!(l.si_name("z1_rad_s"), "z1_m_s");
        assert_eq!(l.si_name("wphi_rad_s3"), "wphi_m_s3");
        assert_eq!(l.si_name("rad/s³"), "m/s³");
        assert_eq!(l.si_name("radius_rad"), "radius_m");
        assert_eq!(l.si_name("u_V"), "u_V");
        assert_eq!(Axis::Rotary.si_name("z1_rad_s"), "z1_rad_s");
    }
}
