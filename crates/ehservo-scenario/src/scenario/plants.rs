//! The plant registry: the one place that maps `plant.model` to a plant's
//! configuration type, as [`super::registry`] does for controllers.
//!
//! A model is a type implementing [`PlantConfig`] (its `model` name, its
//! axis, how to check its keys and build its plant) with serde's derive
//! (its `[plant]` keys, `deny_unknown_fields`). Adding a plant is one
//! file in `crates/ehservo-sim/src/` (the plant and its configuration) and
//! one line in the [`plants!`] call below; runs, traces, metrics, plots,
//! studies, tuning, the league and the bindings then know it, with its
//! axis's units. Code that is generic over the plant implements
//! [`PlantVisit`] and calls [`AnyPlant::visit`].

use ehservo_core::control::Signal;
use ehservo_core::servo::NominalModel;
use ehservo_sim::axis::Axis;
use ehservo_sim::physical::PhysicalCfg;
use ehservo_sim::plant::{Plant, PlantConfig, PlantContext};
use ehservo_sim::third_order::ThirdOrderCfg;
use serde::{Deserialize, Serialize};
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
    ($($variant:ident => $ty:ty),* $(,)?) => {
        /// A scenario's `[plant]` table: one of the registered models with
        /// its keys (built once per run: the variants' sizes do not matter).
        #[derive(Debug, Clone, PartialEq)]
        #[allow(clippy::large_enum_variant)]
        pub enum PlantCfg {
            $(
                #[doc = concat!("`model = \"…\"` (", stringify!($ty), ").")]
                $variant($ty),
            )*
        }

        /// A built plant, of one of the registered models.
        #[derive(Debug, Clone)]
        #[allow(clippy::large_enum_variant)]
        pub enum AnyPlant {
            $(
                #[doc = concat!("The plant of ", stringify!($ty), ".")]
                $variant(<$ty as PlantConfig>::Plant),
            )*
        }

        impl PlantCfg {
            /// Every registered model, in registry order.
            pub const MODELS: &'static [&'static str] = &[$(<$ty as PlantConfig>::MODEL),*];

            /// Every registered model with its one-line description.
            pub const DOCS: &'static [(&'static str, &'static str)] =
                &[$((<$ty as PlantConfig>::MODEL, <$ty as PlantConfig>::DOC)),*];

            /// The model's name.
            pub fn model(&self) -> &'static str {
                match self {
                    $(Self::$variant(_) => <$ty as PlantConfig>::MODEL,)*
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

            /// Whether the scenario's `[load]` (a torque) loads this plant.
            pub fn uses_load(&self) -> bool {
                match self {
                    $(Self::$variant(_) => <$ty as PlantConfig>::USES_LOAD,)*
                }
            }

            /// Checks the keys and builds the plant.
            pub fn build(&self, ctx: &PlantContext) -> Result<AnyPlant, (String, String)> {
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

            /// Model `model` with the keys of `table`. The error is the key
            /// path inside `[plant]` and the reason.
            pub fn from_table(model: &str, table: toml::Table) -> Result<Self, (String, String)> {
                let value = toml::Value::Table(table);
                let fail = |e: serde_path_to_error::Error<toml::de::Error>| {
                    let key = super::overrides::clean_path(&e.path().to_string());
                    (key, super::overrides::first_line(&e.into_inner().to_string()))
                };
                $(
                    if model == <$ty as PlantConfig>::MODEL {
                        return serde_path_to_error::deserialize(value)
                            .map(Self::$variant)
                            .map_err(fail);
                    }
                )*
                Err((
                    "model".into(),
                    format!(
                        "unknown plant model `{model}` (known: {})",
                        Self::MODELS.join(", ")
                    ),
                ))
            }

            /// The model's defaults.
            pub fn default_of(model: &str) -> Option<Self> {
                $(
                    if model == <$ty as PlantConfig>::MODEL {
                        return Some(Self::$variant(<$ty>::default()));
                    }
                )*
                None
            }

            /// Every model with the JSON Schema of its keys (`ehservo schema`).
            pub fn model_schemas(
                g: &mut schemars::SchemaGenerator,
            ) -> Vec<(&'static str, schemars::Schema)> {
                vec![$((<$ty as PlantConfig>::MODEL, g.subschema_for::<$ty>())),*]
            }

            fn params_table(&self) -> Result<toml::Table, toml::ser::Error> {
                match self {
                    $(Self::$variant(c) => toml::Table::try_from(c),)*
                }
            }
        }

        impl AnyPlant {
            /// The model's name (`plant.model`).
            pub fn model(&self) -> &'static str {
                match self {
                    $(Self::$variant(_) => <$ty as PlantConfig>::MODEL,)*
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
                    $(Self::$variant(_) => <<$ty as PlantConfig>::Plant as Plant>::STATES,)*
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

plants! {
    ThirdOrder => ThirdOrderCfg,
    Physical => PhysicalCfg,
    Cylinder => ehservo_sim::cylinder::CylinderCfg,
}

impl Default for PlantCfg {
    fn default() -> Self {
        Self::default_of(DEFAULT_MODEL).expect("the default model is registered")
    }
}

impl PlantCfg {
    /// The `[plant]` table: `model` and every key.
    pub fn to_table(&self) -> toml::Table {
        let mut t = toml::Table::new();
        t.insert("model".into(), toml::Value::String(self.model().into()));
        // A configuration type that serde can derive serialises to a table.
        t.extend(self.params_table().unwrap_or_default());
        t
    }

    /// Reads a `[plant]` table (its `model` defaults to [`DEFAULT_MODEL`]).
    pub fn from_toml(mut table: toml::Table) -> Result<Self, (String, String)> {
        let model = match table.remove("model") {
            None => DEFAULT_MODEL.to_string(),
            Some(toml::Value::String(k)) => k,
            Some(other) => {
                return Err((
                    "model".into(),
                    format!("expected a string naming the plant model, found {other}"),
                ))
            }
        };
        Self::from_table(&model, table)
    }
}

impl Serialize for PlantCfg {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.to_table().serialize(s)
    }
}

impl<'de> Deserialize<'de> for PlantCfg {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let table = toml::Table::deserialize(d)?;
        Self::from_toml(table).map_err(|(k, r)| serde::de::Error::custom(format!("`{k}`: {r}")))
    }
}

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
        let (k, r) = PlantCfg::from_toml(t).unwrap_err();
        assert_eq!(k, "model");
        assert!(
            r.contains("fourth-order") && r.contains("third-order"),
            "{r}"
        );
        let mut t = toml::Table::new();
        t.insert("mass".into(), toml::Value::Float(3.0));
        let (k, r) = PlantCfg::from_toml(t).unwrap_err();
        assert_eq!(k, "mass");
        assert!(r.contains("unknown field"), "{r}");
    }
}
