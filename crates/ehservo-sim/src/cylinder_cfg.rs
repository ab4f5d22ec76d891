//! The cylinder's `[plant]` tables (geometry, fluid, load, stops,
//! initial pressures, transmission, nominal point) and their validation
//! into [`Cylinder`](super::Cylinder): the configuration side of
//! `cylinder.rs`, whose physics reads only the validated constants.

use super::*;
use crate::environment::EnvironmentCfg;
use crate::error::{finite, non_negative, positive, KeyError};

/// `[plant.cylinder]`: the geometry, by areas or by diameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct CylinderGeom {
    /// Piston-side area A_A (m²), or give `bore`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub area_a: Option<f64>,
    /// Rod-side area A_B (m²), or give `rod_diameter`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub area_b: Option<f64>,
    /// Bore D (m): A_A = πD²/4 (a double-rod's both sides A = π(D² − d²)/4).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bore: Option<f64>,
    /// Rod diameter d (m): A_B = π(D² − d²)/4.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rod_diameter: Option<f64>,
    /// With `bore`: 1 (single-rod, the default) or 2 (double-rod).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rods: Option<u8>,
    /// Stroke (m).
    pub stroke: f64,
    /// Dead volume of chamber A at y = 0 (m³).
    pub dead_volume_a: f64,
    /// Dead volume of chamber B at y = stroke (m³).
    pub dead_volume_b: f64,
    /// Cross-piston leakage C_l (m³/(s·Pa)). Default 0.
    pub leakage: f64,
    /// Viscous friction of the piston B_p (N·s/m). Default 0.
    pub viscous: f64,
}

/// `[plant.fluid]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct FluidCfg {
    /// Density ρ (kg/m³).
    pub density: f64,
    /// Effective bulk modulus βe (Pa).
    pub bulk_modulus: f64,
    /// Kinematic viscosity ν (m²/s): the orifices' laminar transition.
    /// Default 46e-6 (ISO VG 46 at 40 °C).
    pub viscosity: f64,
}

impl Default for FluidCfg {
    fn default() -> Self {
        Self {
            density: 0.0,
            bulk_modulus: 0.0,
            viscosity: ISO_VG46_VISCOSITY,
        }
    }
}

/// `[plant.load]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct LoadCfg {
    /// The moving mass M (kg): rod, piston and load.
    pub mass: f64,
    /// Spring stiffness K (N/m). Default 0.
    pub spring: f64,
    /// Where the spring is relaxed, y_K (m). Default 0.
    pub spring_origin: f64,
    /// External viscous damping (N·s/m). Default 0.
    pub damping: f64,
    /// Inclination of the axis (deg): gravity pulls M·g·sin α toward y = 0.
    /// Default 0 (horizontal).
    pub incline_deg: f64,
    /// g (m/s²). Default 9.80665.
    pub gravity: f64,
    /// `[plant.load.friction]`: Stribeck friction of the rod (N, m/s),
    /// run as stick–slip: at rest it holds any net force up to `stiction`,
    /// sliding it cannot reverse the rod within a step (docs/cylinder.md);
    /// `smoothing` shapes only the controller's nominal model.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(schema_with = "linear_friction_schema")]
    pub friction: Option<Friction>,
    /// `[plant.load.force]`: an external force F(t) (N) opposing extension.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub force: Option<ForceCfg>,
}

impl Default for LoadCfg {
    fn default() -> Self {
        Self {
            mass: 0.0,
            spring: 0.0,
            spring_origin: 0.0,
            damping: 0.0,
            incline_deg: 0.0,
            gravity: STANDARD_GRAVITY,
            friction: None,
            force: None,
        }
    }
}

/// `[plant.end_stop]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct EndStopCfg {
    /// Contact stiffness k_s (N/m); default 100·βe·(A_A²/V_A + A_B²/V_B) at mid-stroke.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    /// Contact damping c_s (N·s/m); default 2·√(k_s·M).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
}

/// `[plant.initial]`: the pressures at t = 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct InitialCfg {
    /// p_A(0) (Pa); default: the pair that holds the load at x(0) about
    /// the mid pressure (Ps + Pt)/2.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pressure_a: Option<f64>,
    /// p_B(0) (Pa).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pressure_b: Option<f64>,
}

/// `[plant.transmission]`: a rack and pinion that makes the axis rotary.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TransmissionCfg {
    /// Pinion radius r (m): θ = (y − stroke/2)/r.
    pub radius: f64,
}

/// `[plant.nominal]`: where the controller's model is linearised.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct NominalCfg {
    /// The rod position of the operating point (m); default mid-stroke.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub position: Option<f64>,
}

/// `[plant] model = "cylinder"`: the tables of a valve-controlled cylinder.
///
/// ```
/// use ehservo_sim::axis::Axis;
/// use ehservo_sim::cylinder::{CylinderCfg, CylinderVariation};
/// use ehservo_sim::plant::{Factors, Plant, PlantConfig};
/// # use ehservo_sim::plant::{PlantContext, UncertaintySpec};
/// # let ctx = PlantContext {
/// #     load: None,
/// #     load_given: false,
/// #     uncertainty: UncertaintySpec::NONE,
/// #     x0: [0.0; 3],
/// #     base_dir: None,
/// #     reference_range: None,
/// #     quantity: Default::default(),
/// # };
/// // A 63/36 mm single-rod cylinder, 0.5 m stroke, on a fixed 200 bar supply,
/// // a critically centred valve: the inside of a scenario's `[plant]` table.
/// let cfg: CylinderCfg = toml::from_str(r#"
/// [cylinder]
/// bore = 0.063
/// rod_diameter = 0.036
/// stroke = 0.5
/// dead_volume_a = 2e-4
/// dead_volume_b = 2e-4
/// [fluid]
/// density = 870.0
/// bulk_modulus = 1.4e9
/// [valve]
/// spool_limit = 5e-4
/// gain = 5e-5
/// discharge_coefficient = 0.65
/// area_gradient = 0.02
/// [supply]
/// kind = "fixed"
/// pressure = 2e7
/// [load]
/// mass = 250.0
/// "#).unwrap();
/// let plant = cfg.build(&ctx).unwrap();
/// assert_eq!(plant.axis(), Axis::Linear);
/// // At rest at mid-stroke the chambers hold the rod about Ps/2:
/// // p_A = A_B·Ps/(A_A + A_B), p_B = Ps − p_A, so A_A·p_A = A_B·p_B.
/// let v = CylinderVariation { f: Factors::ONE };
/// let s = plant.initial_state([0.25, 0.0, 0.0], &v);
/// let q = std::f64::consts::PI / 4.0;
/// let (aa, ab) = (q * 0.063 * 0.063, q * (0.063 * 0.063 - 0.036 * 0.036));
/// assert!((s[2] - ab * 2e7 / (aa + ab)).abs() < 1e-6);
/// // The valve closed: nothing moves, nothing flows.
/// let mut ds = [0.0; 6];
/// plant.deriv(0.0, &s, 0.0, &v, &mut ds);
/// assert!(ds.iter().all(|d| d.abs() < 1e-9), "{ds:?}");
/// // At u = 1 V the spool opens Kv·u = 5e-5 m of P→A: the turbulent orifice
/// // passes Q = Cd·w·x·√(2(Ps − p_A)/ρ) into V_A = V_0A + A_A·y, and
/// // ṗ_A = βe·Q/V_A.
/// plant.deriv(0.0, &s, 1.0, &v, &mut ds);
/// let flow = 0.65 * 0.02 * 5e-5 * (2.0 * (2e7 - s[2]) / 870.0).sqrt();
/// let rate = 1.4e9 * flow / (2e-4 + aa * 0.25);
/// assert!((ds[2] - rate).abs() < 1e-6 * rate);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct CylinderCfg {
    /// `[plant.cylinder]`.
    pub cylinder: CylinderGeom,
    /// `[plant.fluid]`.
    pub fluid: FluidCfg,
    /// `[plant.valve]`.
    pub valve: ValveCfg,
    /// `[plant.supply]`.
    pub supply: SupplyCfg,
    /// `[plant.load]`.
    pub load: LoadCfg,
    /// `[plant.end_stop]`.
    #[serde(skip_serializing_if = "is_default")]
    pub end_stop: EndStopCfg,
    /// `[plant.initial]`.
    #[serde(skip_serializing_if = "is_default")]
    pub initial: InitialCfg,
    /// `[plant.transmission]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub transmission: Option<TransmissionCfg>,
    /// `[plant.hose]`: the hoses to the ports (their volume and swelling
    /// added to the chambers: [`crate::hose`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hose: Option<crate::hose::HoseCfg>,
    /// `[plant.nominal]`.
    #[serde(skip_serializing_if = "is_default")]
    pub nominal: NominalCfg,
    /// `[plant.environment]`: a specimen or a preloaded spring the rod
    /// works against, its contact point fixed or moving
    /// (docs/environments.md).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub environment: Option<EnvironmentCfg>,
}

fn is_default<T: Default + PartialEq>(v: &T) -> bool {
    *v == T::default()
}

/// Puts a key error of a table under `plant.<table>.`.
fn at(table: &'static str) -> impl Fn(KeyError) -> KeyError {
    move |e| e.under(&format!("plant.{table}"))
}

/// [`Cylinder::stated_penetration`]'s bound at factors 1 (m), written as
/// (F/k_s)·(1 + √(1 + 2·k_s·L/F)) so that it stays finite for any finite F
/// (F² overflowed beyond 1e154 N, and an infinite δ let every position
/// pass [`Cylinder::beyond_stops`]). Refused when the static forces that
/// can hold the rod on a stop (the supply's on the piston, the weight, the
/// load force's peak, the load spring's and the environment's force at
/// the stop, [`crate::environment::Environment::stop_force`]) would rest it deeper than the
/// stroke is long, F_s/k_s > L: the rod would sit outside the cylinder
/// (issue #46: a spring preload of −1e12 N left a 400 mm rod 714 m out,
/// "bounded"). The key is the largest part of F_s.
fn stated_penetration(c: &Cylinder, ps: f64, ks: f64) -> Result<f64, KeyError> {
    let l = c.stroke;
    let supply_key = match c.supply {
        Supply::Fixed { .. } => "plant.supply.pressure",
        Supply::Pump(_) => "plant.supply.relief_pressure",
        Supply::PcPump(_) => "plant.supply.compensator_pressure",
    };
    let env = c.environment.as_ref();
    let parts = [
        (supply_key, c.area[0] * ps),
        ("plant.load.mass", c.gravity_force.abs()),
        ("plant.load.force", c.force.peak()),
        (
            "plant.load.spring",
            c.spring * c.spring_origin.abs().max((l - c.spring_origin).abs()),
        ),
    ];
    let others: f64 = parts.iter().map(|p| p.1).sum();
    let at_stop = others + env.map_or(0.0, |e| e.stop_force(l));
    let rest = at_stop / ks;
    if rest.is_nan() || rest > l {
        let (key, part) = parts
            .iter()
            .copied()
            .chain([("plant.environment", env.map_or(0.0, |e| e.stop_force(l)))])
            .fold(("plant.end_stop.stiffness", 0.0), |a, p| {
                if p.1 > a.1 {
                    p
                } else {
                    a
                }
            });
        return Err(KeyError::new(
            key,
            format!(
                "up to {part:.3e} N (of {at_stop:.3e} N in all) holds the rod on an end stop (k_s = {ks:.3e} N/m) {rest:.3e} m deep, more than the stroke ({l:e} m): lower it, or stiffen plant.end_stop"
            ),
        ));
    }
    let f = others + env.map_or(0.0, |e| e.peak(l));
    if f <= 0.0 {
        return Ok(0.0);
    }
    Ok(f / ks * (1.0 + (1.0 + 2.0 * ks * l / f).sqrt()))
}

impl CylinderCfg {
    /// Checks every key; the error is the full key path and the reason.
    pub fn resolve(&self, ctx: &PlantContext) -> Result<Cylinder, KeyError> {
        let g = &self.cylinder;
        let cyl = at("cylinder");
        let area = match (g.area_a, g.area_b, g.bore, g.rod_diameter) {
            (Some(a), Some(b), None, None) => {
                if g.rods.is_some() {
                    return Err(cyl(KeyError::new("rods", "goes with bore and rod_diameter, not areas")));
                }
                let a = positive("area_a", a).map_err(&cyl)?;
                let b = positive("area_b", b).map_err(&cyl)?;
                if b > a {
                    return Err(cyl(KeyError::new(
                        "area_b",
                        format!("the rod side ({b} m²) is larger than the piston side ({a} m²): area_a is the piston side"),
                    )));
                }
                [a, b]
            }
            (None, None, Some(d), Some(dr)) => {
                let d = positive("bore", d).map_err(&cyl)?;
                let dr = positive("rod_diameter", dr).map_err(&cyl)?;
                if dr >= d {
                    return Err(cyl(KeyError::new(
                        "rod_diameter",
                        format!("the rod ({dr} m) must be thinner than the bore ({d} m): A_rod ≥ A_A leaves no rod-side area"),
                    )));
                }
                let q = core::f64::consts::PI / 4.0;
                let annulus = q * (d * d - dr * dr);
                match g.rods.unwrap_or(1) {
                    1 => [q * d * d, annulus],
                    2 => [annulus, annulus],
                    n => {
                        return Err(cyl(KeyError::new(
                            "rods",
                            format!("must be 1 (single-rod) or 2 (double-rod), got {n}"),
                        )))
                    }
                }
            }
            (None, None, None, None) => {
                return Err(cyl(KeyError::new(
                    "area_a",
                    "the geometry is required: area_a and area_b (m²), or bore and rod_diameter (m) with rods = 1 or 2",
                )))
            }
            _ => {
                return Err(cyl(KeyError::new(
                    "area_a",
                    "give either area_a and area_b, or bore and rod_diameter, not a mix",
                )))
            }
        };
        let stroke = positive("stroke", g.stroke).map_err(&cyl)?;
        let v0a = g.dead_volume_a;
        let v0b = g.dead_volume_b;
        if !(v0a.is_finite() && v0a > 0.0) {
            return Err(cyl(KeyError::new(
                "dead_volume_a",
                format!("must be finite and > 0 (got {v0a:?}): chamber A's volume V_0A + A_A·y would not be positive at y = 0"),
            )));
        }
        if !(v0b.is_finite() && v0b > 0.0) {
            return Err(cyl(KeyError::new(
                "dead_volume_b",
                format!("must be finite and > 0 (got {v0b:?}): chamber B's volume V_0B + A_B·(stroke − y) would not be positive at y = stroke"),
            )));
        }
        let leakage = non_negative("leakage", g.leakage).map_err(&cyl)?;
        let bp = non_negative("viscous", g.viscous).map_err(&cyl)?;
        let fl = at("fluid");
        let rho = positive("density", self.fluid.density).map_err(&fl)?;
        let beta = positive("bulk_modulus", self.fluid.bulk_modulus).map_err(&fl)?;
        let nu = positive("viscosity", self.fluid.viscosity).map_err(&fl)?;
        let valve = SpoolValve::try_new(&self.valve, rho, nu).map_err(at("valve"))?;
        let (supply, pt) = Supply::try_new(&self.supply, beta).map_err(at("supply"))?;
        let (v0a, v0b, hose_drop) = match &self.hose {
            None => (v0a, v0b, 0.0),
            Some(h) => {
                let [ha, hb] = h.equivalent_volumes(beta).map_err(at("hose"))?;
                // The valve's full flow: full opening, half the supply
                // across each land.
                let pm = 0.5 * (supply.holding_pressure(pt) + pt);
                let q = valve
                    .flows(valve.x_max, supply.holding_pressure(pt), pt, pm, pm)
                    .a;
                (v0a + ha, v0b + hb, h.drop(q, rho, nu))
            }
        };
        let l = &self.load;
        let ld = at("load");
        let mass = positive("mass", l.mass).map_err(&ld)?;
        let spring = non_negative("spring", l.spring).map_err(&ld)?;
        let spring_origin = finite("spring_origin", l.spring_origin).map_err(&ld)?;
        let damping = non_negative("damping", l.damping).map_err(&ld)?;
        let incline = finite("incline_deg", l.incline_deg).map_err(&ld)?;
        if incline.abs() > 90.0 {
            return Err(ld(KeyError::new(
                "incline_deg",
                format!("must be within ±90° (got {incline:?})"),
            )));
        }
        let gravity = non_negative("gravity", l.gravity).map_err(&ld)?;
        if let Some(f) = &l.friction {
            // The value always shown, NaN included (`KeyError::param`
            // leaves out a NaN, the core's mark of a combination).
            f.validate().map_err(|e| {
                KeyError::new(
                    format!("plant.load.friction.{}", e.name),
                    format!("{} (got {:?})", e.reason, e.value),
                )
            })?;
        }
        let force = match &l.force {
            None => Force::Zero,
            Some(f) => Force::try_new(f, ctx.base_dir.as_deref()).map_err(at("load.force"))?,
        };
        let gravity_force = mass * gravity * incline.to_radians().sin();
        // The oil column's stiffness at mid-stroke, for the stop's default.
        let half = 0.5 * stroke;
        let kh = beta
            * (area[0] * area[0] / (v0a + area[0] * half)
                + area[1] * area[1] / (v0b + area[1] * half));
        let es = at("end_stop");
        let ks = match self.end_stop.stiffness {
            None => 100.0 * kh,
            Some(k) => positive("stiffness", k).map_err(&es)?,
        };
        let cs = match self.end_stop.damping {
            None => 2.0 * (ks * mass).sqrt(),
            Some(c) => non_negative("damping", c).map_err(&es)?,
        };
        let radius = match &self.transmission {
            None => None,
            Some(t) => Some(positive("radius", t.radius).map_err(at("transmission"))?),
        };
        let ini = at("initial");
        let initial = [
            self.initial
                .pressure_a
                .map(|p| non_negative("pressure_a", p))
                .transpose()
                .map_err(&ini)?,
            self.initial
                .pressure_b
                .map(|p| non_negative("pressure_b", p))
                .transpose()
                .map_err(&ini)?,
        ];
        if initial[0].is_some() != initial[1].is_some() {
            return Err(ini(KeyError::new(
                "pressure_a",
                "give both pressure_a and pressure_b, or neither",
            )));
        }
        let mut c = Cylinder {
            area,
            stroke,
            v0: [v0a, v0b],
            leakage,
            viscous: bp + damping,
            beta,
            rho,
            mass,
            spring,
            spring_origin,
            gravity_force,
            friction: l.friction,
            force,
            external: 0.0,
            stop: [ks, cs],
            penetration: 0.0,
            stick_rate: (kh / mass).sqrt(),
            valve,
            supply,
            pt,
            radius,
            initial,
            hose_drop,
            environment: match &self.environment {
                None => None,
                Some(e) => Some(
                    Environment::try_new(e, stroke, ctx.base_dir.as_deref())
                        .map_err(at("environment"))?,
                ),
            },
        };
        // The relief must be able to hold the static load: a supply that
        // cannot push the load off the bottom of the stroke is a mistake.
        let ps = c.supply.holding_pressure(pt);
        c.penetration = stated_penetration(&c, ps, ks)?;
        // At the supply's setting (a fixed pressure, a relief's cracking
        // pressure, a compensator's setting): a relief that cracks below
        // the pressure that holds the load would pass the pump's flow to
        // tank while holding it.
        let ps = c.supply.setting(pt);
        let hold = c.area[0] * (ps - pt) - (c.area[0] - c.area[1]) * pt;
        let static_load = c.gravity_force + c.force.static_part();
        if static_load > 0.0 && hold <= static_load {
            return Err(KeyError::new(
                match c.supply {
                    Supply::Fixed { .. } => "plant.supply.pressure",
                    Supply::Pump(_) => "plant.supply.relief_pressure",
                    Supply::PcPump(_) => "plant.supply.compensator_pressure",
                },
                format!(
                    "the supply's setting ({:.4e} Pa) cannot hold the static load of {static_load:.4e} N on the piston side's {:.4e} m²",
                    ps, c.area[0]
                ),
            ));
        }
        // The operating point and the run's positions inside the stroke.
        let y_nom = self.nominal.position.unwrap_or(half);
        if !(y_nom.is_finite() && (0.0..=stroke).contains(&y_nom)) {
            return Err(KeyError::new(
                "plant.nominal.position",
                format!("must be within the stroke [0, {stroke}] m (got {y_nom:?})"),
            ));
        }
        let to_y = |p: f64| match radius {
            None => p,
            Some(r) => half + r * p,
        };
        let y0 = to_y(ctx.x0[0]);
        if !(0.0..=stroke).contains(&y0) {
            return Err(KeyError::new(
                "simulation.x0",
                format!("the rod starts at y = {y0} m, outside the stroke [0, {stroke}] m"),
            ));
        }
        if let Some((lo, hi)) = ctx.reference_range {
            let (ylo, yhi) = (to_y(lo), to_y(hi));
            if ylo < 0.0 || yhi > stroke {
                return Err(KeyError::new(
                    "reference",
                    format!(
                        "asks for y from {:.6} to {:.6} m: outside the stroke [0, {stroke}] m",
                        ylo.min(yhi),
                        ylo.max(yhi)
                    ),
                ));
            }
        }
        Ok(c)
    }
}

impl PlantConfig for CylinderCfg {
    const MODEL: &'static str = "cylinder";
    const DOC: &'static str =
        "a valve-controlled single- or double-rod cylinder with its supply, load and end stops, in (y, ẏ, p_A, p_B, p_s, x_r)";
    const PAPER_UNCERTAINTY: bool = false;
    const USES_LOAD: bool = false;
    const END_STOPS: bool = true;
    type Plant = CylinderPlant;

    fn axis(&self) -> Axis {
        if self.transmission.is_some() {
            Axis::Rotary
        } else {
            Axis::Linear
        }
    }

    /// With an environment, its force as a seventh column.
    fn states(&self) -> &'static [Signal] {
        match self.environment {
            None => &CYLINDER_STATES,
            Some(_) => &ENVIRONMENT_STATES,
        }
    }

    fn build(&self, ctx: &PlantContext) -> Result<CylinderPlant, KeyError> {
        let c = self.resolve(ctx)?;
        check_quantity(ctx.quantity, &c)?;
        let y = self.nominal.position.unwrap_or(0.5 * c.stroke);
        let p = CylinderPlant::new(c, y).with_output(ctx.quantity);
        // Values each finite can still make the model's constants overflow
        // (an area of 1e308, a subnormal mass): what the controller would
        // be designed on must be numbers.
        let m = p.nominal();
        let derived = m
            .coeffs
            .as_array()
            .into_iter()
            .chain([m.b_at_rest(), m.offset()]);
        if let Err(e) = m.params.validate() {
            return Err(KeyError::new(
                "plant",
                format!(
                    "the cylinder's nominal model is not a model: its {} is {:?} ({}); check the sizes of the plant's keys",
                    e.name, e.value, e.reason
                ),
            ));
        }
        if derived.into_iter().any(|v| !v.is_finite()) {
            return Err(KeyError::new(
                "plant",
                format!(
                    "the cylinder's nominal model overflows (a1, a2, a3 = {:?}, b at rest = {:e}): check the sizes of the plant's keys",
                    m.coeffs.as_array(),
                    m.b_at_rest()
                ),
            ));
        }
        Ok(p)
    }
}

/// Whether the loop's quantity `q` can be measured on `c`: a force needs
/// the environment whose force the load cell reads, and a force or a
/// pressure loop a rod without a pinion (its x is then (q, ẏ, ÿ) of the rod).
fn check_quantity(q: crate::axis::Quantity, c: &Cylinder) -> Result<(), KeyError> {
    use crate::axis::Quantity;
    if q.is_position() {
        return Ok(());
    }
    if c.radius.is_some() {
        return Err(KeyError::new(
            "reference.quantity",
            format!(
                "`{}` is a linear cylinder's: remove [plant.transmission] (a rack and pinion turns the axis rotary)",
                q.name()
            ),
        ));
    }
    if q == Quantity::Force && c.environment.is_none() {
        return Err(KeyError::new(
            "reference.quantity",
            "`force` is the environment's force on the rod (a load cell's): give [plant.environment], or use `load-pressure`",
        ));
    }
    Ok(())
}

/// The schema of the rod's friction: [`Friction`]'s own (one struct serves
/// both axes, each in its SI units) with every unit a description names
/// read on a linear axis (N·m → N, rad/s → m/s, N·m·s → N·s/m) and the
/// rod for the motor shaft. The schema's unit column comes from these
/// descriptions.
fn linear_friction_schema(g: &mut schemars::SchemaGenerator) -> schemars::Schema {
    let mut v = <Friction as schemars::JsonSchema>::json_schema(g).to_value();
    linear_units(&mut v);
    schemars::Schema::try_from(v).unwrap_or_default()
}

/// Rotary units in every `description` of `v` read as their linear ones.
fn linear_units(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(o) => {
            for (k, x) in o.iter_mut() {
                if k == "description" {
                    if let serde_json::Value::String(d) = x {
                        *d = d
                            .replace("N·m·s", "N·s/m")
                            .replace("N·m", "N")
                            .replace("rad/s", "m/s")
                            .replace("the plant's Bm", "`[plant.cylinder]`'s `viscous`")
                            .replace("motor shaft", "rod");
                    }
                } else {
                    linear_units(x);
                }
            }
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(linear_units),
        _ => {}
    }
}
