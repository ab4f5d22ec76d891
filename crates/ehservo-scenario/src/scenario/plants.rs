//! The plant registry: the one place that maps `plant.model` to a plant's
//! configuration type, as [`super::registry`] does for controllers.
//!
//! A model is a type implementing [`PlantConfig`] (its `model` name, its
//! axis, how to check its keys and build its plant) with serde's derive
//! (its `[plant]` keys, `deny_unknown_fields`). Adding a plant is one
//! file in `crates/ehservo-sim/src/` (the plant and its configuration) and
//! one line in the [`plants!`] call below (the line names the model as
//! its `PlantConfig::MODEL` does, or it does not compile); runs, traces, metrics, plots,
//! studies, tuning, the league and the bindings then know it, with its
//! axis's units. Code that is generic over the plant implements
//! [`PlantVisit`] and calls [`AnyPlant::visit`].

use super::tagged::{tagged_serde, Tagged};
use ehservo_core::control::Signal;
use ehservo_core::servo::{NominalModel, ServoParams};
use ehservo_sim::axis::Axis;
use ehservo_sim::error::KeyError;
use ehservo_sim::physical::PhysicalCfg;
use ehservo_sim::plant::{Plant, PlantConfig, PlantContext};
use ehservo_sim::third_order::ThirdOrderCfg;
use std::any::Any;

/// Code generic over the (built) plant.
pub trait PlantVisit {
    /// What the visit returns.
    type Out;
    /// Called with the scenario's plant, typed.
    fn visit<P: Plant + Clone + std::fmt::Debug + Send + Sync + 'static>(
        self,
        plant: &P,
    ) -> Self::Out;
}

/// The default model when a scenario names none (the paper's (8)–(9)).
pub const DEFAULT_MODEL: &str = "third-order";

macro_rules! plants {
    ($($variant:ident $name:literal => $ty:ty),* $(,)?) => {
        /// A scenario's `[plant]` table: one of the registered models with
        /// its keys (built once per run: the variants' sizes do not matter).
        #[derive(Debug, Clone, PartialEq)]
        #[allow(clippy::large_enum_variant)]
        pub enum PlantCfg {
            $(
                #[doc = concat!("`model = \"", $name, "\"`.")]
                $variant($ty),
            )*
        }

        /// A built plant, of one of the registered models.
        #[derive(Debug, Clone)]
        #[allow(clippy::large_enum_variant)]
        pub enum AnyPlant {
            $(
                #[doc = concat!("The plant of `model = \"", $name, "\"`.")]
                $variant(<$ty as PlantConfig>::Plant),
            )*
        }

        // Each line names its model as its `PlantConfig::MODEL` does.
        $(const _: () = assert!(
            ehservo_core::control::str_eq(<$ty as PlantConfig>::MODEL, $name),
            concat!("plants!: the line of `", $name, "` is not its PlantConfig::MODEL")
        );)*

        impl PlantCfg {
            /// Every registered model, in registry order.
            pub const MODELS: &'static [&'static str] = &[$($name),*];

            /// Every registered model with its one-line description.
            pub const DOCS: &'static [(&'static str, &'static str)] =
                &[$(($name, <$ty as PlantConfig>::DOC)),*];

            /// The model's name.
            pub fn model(&self) -> &'static str {
                match self {
                    $(Self::$variant(_) => $name,)*
                }
            }

            /// The axis of the plant this configures.
            pub fn axis(&self) -> Axis {
                match self {
                    $(Self::$variant(c) => c.axis(),)*
                }
            }

            /// The physical states its trace carries.
            pub fn states(&self) -> &'static [Signal] {
                match self {
                    $(Self::$variant(c) => c.states(),)*
                }
            }

            /// Whether the paper's Δa_i/Δb form of `[uncertainty]` applies.
            pub fn paper_uncertainty(&self) -> bool {
                match self {
                    $(Self::$variant(_) => <$ty as PlantConfig>::PAPER_UNCERTAINTY,)*
                }
            }

            /// Whether the plant has end stops (no position limit then).
            pub fn end_stops(&self) -> bool {
                match self {
                    $(Self::$variant(_) => <$ty as PlantConfig>::END_STOPS,)*
                }
            }

            /// Whether the plant steps itself over a sample period (a
            /// co-simulation FMU: [`Plant::STEPS_ITSELF`]).
            pub fn steps_itself(&self) -> bool {
                match self {
                    $(Self::$variant(_) => <<$ty as PlantConfig>::Plant as Plant>::STEPS_ITSELF,)*
                }
            }

            /// Whether the scenario's `[load]` (a torque) loads this plant.
            pub fn uses_load(&self) -> bool {
                match self {
                    $(Self::$variant(_) => <$ty as PlantConfig>::USES_LOAD,)*
                }
            }

            /// The paper's physical parameters, for a model of the
            /// third-order family ([`PlantConfig::paper_params`]).
            pub fn paper_params(&self) -> Option<ServoParams> {
                match self {
                    $(Self::$variant(c) => c.paper_params(),)*
                }
            }

            /// This model with the paper's parameters `p` in place of its
            /// own ([`PlantConfig::with_paper_params`]); `None` outside the
            /// third-order family.
            pub fn with_paper_params(&self, p: ServoParams) -> Option<PlantCfg> {
                match self {
                    $(Self::$variant(c) => c.with_paper_params(p).map(Self::$variant),)*
                }
            }

            /// Checks the keys and builds the plant.
            pub fn build(&self, ctx: &PlantContext) -> Result<AnyPlant, KeyError> {
                match self {
                    $(Self::$variant(c) => c.build(ctx).map(AnyPlant::$variant),)*
                }
            }

            /// The parameters, if they are of type `T`.
            pub fn get<T: 'static>(&self) -> Option<&T> {
                match self {
                    $(Self::$variant(c) => (c as &dyn Any).downcast_ref::<T>(),)*
                }
            }

            /// The model's defaults.
            pub fn default_of(model: &str) -> Option<Self> {
                match model {
                    $($name => Some(Self::$variant(<$ty>::default())),)*
                    _ => None,
                }
            }

            /// Every model with the JSON Schema of its keys (`ehservo schema`).
            pub fn model_schemas(
                g: &mut schemars::SchemaGenerator,
            ) -> Vec<(&'static str, schemars::Schema)> {
                vec![$(($name, g.subschema_for::<$ty>())),*]
            }
        }

        impl Tagged for PlantCfg {
            const SECTION: &'static str = "plant";
            const TAG: &'static str = "model";
            const WHAT: &'static str = "plant model";
            const DEFAULT: &'static str = DEFAULT_MODEL;
            const NAMES: &'static [&'static str] = Self::MODELS;

            fn name(&self) -> &'static str {
                self.model()
            }

            fn from_named(
                name: &str,
                value: toml::Value,
            ) -> Option<Result<Self, serde_path_to_error::Error<toml::de::Error>>> {
                match name {
                    $($name => Some(serde_path_to_error::deserialize(value).map(Self::$variant)),)*
                    _ => None,
                }
            }

            fn params_table(&self) -> Result<toml::Table, toml::ser::Error> {
                match self {
                    $(Self::$variant(c) => toml::Table::try_from(c),)*
                }
            }

            fn check_keys(name: &str, table: &toml::Table) -> Result<(), KeyError> {
                environment_on_a_piston(name, table)
            }
        }

        impl AnyPlant {
            /// The model's name (`plant.model`).
            pub fn model(&self) -> &'static str {
                match self {
                    $(Self::$variant(_) => $name,)*
                }
            }

            /// Calls `v` with the typed plant.
            pub fn visit<V: PlantVisit>(&self, v: V) -> V::Out {
                match self {
                    $(Self::$variant(p) => v.visit(p),)*
                }
            }

            /// The nominal model a controller is designed on.
            pub fn nominal(&self) -> &NominalModel {
                match self {
                    $(Self::$variant(p) => p.nominal(),)*
                }
            }

            /// The axis.
            pub fn axis(&self) -> Axis {
                match self {
                    $(Self::$variant(p) => p.axis(),)*
                }
            }

            /// The physical states a trace carries.
            pub fn states(&self) -> &'static [Signal] {
                match self {
                    $(Self::$variant(p) => p.signals(),)*
                }
            }

            /// The number of the plant's state components ([`Plant::state_dim`]).
            pub fn state_dim(&self) -> usize {
                match self {
                    $(Self::$variant(p) => p.state_dim(),)*
                }
            }

            /// The plant, if it is of type `T`.
            pub fn get<T: 'static>(&self) -> Option<&T> {
                match self {
                    $(Self::$variant(p) => (p as &dyn Any).downcast_ref::<T>(),)*
                }
            }
        }
    };
}

/// The registry's lines, with `$extra` after them.
macro_rules! registered {
    ($($extra:tt)*) => {
        plants! {
            ThirdOrder "third-order" => ThirdOrderCfg,
            Physical "physical" => PhysicalCfg,
            Cylinder "cylinder" => ehservo_sim::cylinder::CylinderCfg,
            Ifac9007 "ifac9007" => ehservo_sim::ifac9007::Ifac9007Cfg,
            $($extra)*
        }
    };
}

// A plant from an FMU needs the archive and dynamic loading (feature
// `fmu-import`: the lab has it; the C ABI and the browser do not).
#[cfg(feature = "fmu-import")]
registered!(Fmu "fmu" => crate::fmu_plant::FmuCfg);
#[cfg(not(feature = "fmu-import"))]
registered!();

/// `[plant.environment]` acts on a cylinder's rod: a model without a
/// piston (the paper's third-order servo, its physical form, IFAC 9007)
/// refuses it by name rather than as an unknown key.
fn environment_on_a_piston(model: &str, table: &toml::Table) -> Result<(), KeyError> {
    if model == "cylinder" || !table.contains_key("environment") {
        return Ok(());
    }
    Err(KeyError::new(
        "environment",
        format!("an environment (specimen or spring) acts on a cylinder's rod; model = \"{model}\" has no piston: use model = \"cylinder\""),
    ))
}

impl Default for PlantCfg {
    fn default() -> Self {
        Self::default_of(DEFAULT_MODEL).expect("the default model is registered")
    }
}

impl PlantCfg {
    /// The `[plant]` table: `model` and every key.
    pub fn to_table(&self) -> toml::Table {
        Tagged::to_table(self)
    }

    /// Reads a `[plant]` table (its `model` defaults to [`DEFAULT_MODEL`]).
    /// The error's key is the key inside `[plant]`.
    pub fn from_toml(table: toml::Table) -> Result<Self, KeyError> {
        <Self as Tagged>::from_toml(table)
    }
}

tagged_serde!(PlantCfg);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn models_round_trip_through_their_tables() {
        for &m in PlantCfg::MODELS {
            let c = PlantCfg::default_of(m).unwrap();
            assert_eq!(c.model(), m);
            assert_eq!(PlantCfg::from_toml(c.to_table()).unwrap(), c);
        }
    }

    #[test]
    fn unknown_models_and_keys_are_named() {
        let mut t = toml::Table::new();
        t.insert("model".into(), toml::Value::String("fourth-order".into()));
        let e = PlantCfg::from_toml(t).unwrap_err();
        assert_eq!(e.key, "model");
        let r = e.reason.to_string();
        assert!(
            r.contains("fourth-order") && r.contains("third-order"),
            "{r}"
        );
        let mut t = toml::Table::new();
        t.insert("mass".into(), toml::Value::Float(3.0));
        let e = PlantCfg::from_toml(t).unwrap_err();
        assert_eq!(e.key, "mass");
        assert!(e.reason.to_string().contains("unknown field"), "{e}");
    }
}
