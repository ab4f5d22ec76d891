//! The registry: the one place that maps `controller.kind` to a
//! controller's parameter type.
//!
//! A kind is a type implementing [`ehservo_core::control::Config`] (its
//! kind name, whether it uses the surface, how to build the controller) with
//! serde's derive (its `[controller]` keys, `deny_unknown_fields`). Adding a
//! controller kind is one line in the [`registry!`] call below; every
//! command, study and output then knows it. Code that is generic over the
//! kind implements [`Visit`] and calls [`ControllerCfg::visit`]; code that
//! needs one kind's parameters asks [`ControllerCfg::get`].

use ehservo_core::control::sliding::{NnVscConfig, VscConfig, VscSatConfig};
use ehservo_core::control::Config;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::any::Any;
use std::fmt::Debug;

/// What a controller kind's parameter type must be.
pub trait ControllerConfig:
    Config + Serialize + DeserializeOwned + Default + Clone + PartialEq + Debug + Send + Sync + 'static
{
}

impl<T> ControllerConfig for T where
    T: Config
        + Serialize
        + DeserializeOwned
        + Default
        + Clone
        + PartialEq
        + Debug
        + Send
        + Sync
        + 'static
{
}

/// Code generic over the controller kind.
pub trait Visit {
    /// What the visit returns.
    type Out;
    /// Called with the scenario's controller parameters, typed.
    fn visit<K: ControllerConfig>(self, cfg: &K) -> Self::Out;
}

/// The default kind when a scenario names none (the paper's Theorem 3).
pub const DEFAULT_KIND: &str = "nnvsc";

macro_rules! registry {
    ($($variant:ident => $ty:ty),* $(,)?) => {
        /// A scenario's `[controller]` table: one of the registered kinds
        /// with its parameters.
        #[derive(Debug, Clone, PartialEq)]
        pub enum ControllerCfg {
            $(
                #[doc = concat!("`kind = \"", stringify!($variant), "\"` (", stringify!($ty), ").")]
                $variant($ty),
            )*
        }

        impl ControllerCfg {
            /// Every registered kind, in registry order.
            pub const KINDS: &'static [&'static str] = &[$(<$ty as Config>::KIND),*];

            /// The kind's name.
            pub fn kind(&self) -> &'static str {
                match self {
                    $(Self::$variant(_) => <$ty as Config>::KIND,)*
                }
            }

            /// Whether the kind's law uses the switching surface.
            pub fn uses_surface(&self) -> bool {
                match self {
                    $(Self::$variant(_) => <$ty as Config>::USES_SURFACE,)*
                }
            }

            /// Calls `v` with the typed parameters.
            pub fn visit<V: Visit>(&self, v: V) -> V::Out {
                match self {
                    $(Self::$variant(c) => v.visit(c),)*
                }
            }

            /// The parameters, if they are of type `T`.
            pub fn get<T: 'static>(&self) -> Option<&T> {
                match self {
                    $(Self::$variant(c) => (c as &dyn Any).downcast_ref::<T>(),)*
                }
            }

            /// Kind `kind` with the keys of `table`. The error is the key
            /// path inside `[controller]` and the reason.
            pub fn from_table(kind: &str, table: toml::Table) -> Result<Self, (String, String)> {
                let value = toml::Value::Table(table);
                let fail = |e: serde_path_to_error::Error<toml::de::Error>| {
                    let key = super::overrides::clean_path(&e.path().to_string());
                    (key, super::overrides::first_line(&e.into_inner().to_string()))
                };
                $(
                    if kind == <$ty as Config>::KIND {
                        return serde_path_to_error::deserialize(value)
                            .map(Self::$variant)
                            .map_err(fail);
                    }
                )*
                Err((
                    "kind".into(),
                    format!(
                        "unknown controller kind `{kind}` (known: {})",
                        Self::KINDS.join(", ")
                    ),
                ))
            }

            /// The kind's defaults.
            pub fn default_of(kind: &str) -> Option<Self> {
                $(
                    if kind == <$ty as Config>::KIND {
                        return Some(Self::$variant(<$ty>::default()));
                    }
                )*
                None
            }

            /// Every kind with the JSON Schema of its keys (`ehservo schema`).
            pub fn kind_schemas(
                g: &mut schemars::SchemaGenerator,
            ) -> Vec<(&'static str, schemars::Schema)> {
                vec![$((<$ty as Config>::KIND, g.subschema_for::<$ty>())),*]
            }

            fn params_table(&self) -> Result<toml::Table, toml::ser::Error> {
                match self {
                    $(Self::$variant(c) => toml::Table::try_from(c),)*
                }
            }
        }
    };
}

registry! {
    Nnvsc => NnVscConfig,
    Vsc => VscConfig,
    VscSat => VscSatConfig,
    Pid => ehservo_core::control::pid::PidConfig,
    NnRobust => ehservo_core::control::nn_robust::NnRobustConfig,
    Adrc => ehservo_core::control::adrc::AdrcConfig,
    Sta => ehservo_core::control::sta::StaConfig,
    Arc => ehservo_core::control::arc::ArcConfig,
    Backstepping => ehservo_core::control::backstepping::BacksteppingConfig,
    OpenLoop => ehservo_core::control::open_loop::OpenLoopConfig,
}

impl Default for ControllerCfg {
    fn default() -> Self {
        Self::default_of(DEFAULT_KIND).expect("the default kind is registered")
    }
}

impl ControllerCfg {
    /// The `[controller]` table: `kind` and every parameter.
    pub fn to_table(&self) -> toml::Table {
        let mut t = toml::Table::new();
        t.insert("kind".into(), toml::Value::String(self.kind().into()));
        // A parameter type that serde can derive always serialises to a table.
        t.extend(self.params_table().unwrap_or_default());
        t
    }

    /// Reads a `[controller]` table (its `kind` defaults to
    /// [`DEFAULT_KIND`]).
    pub fn from_toml(mut table: toml::Table) -> Result<Self, (String, String)> {
        let kind = match table.remove("kind") {
            None => DEFAULT_KIND.to_string(),
            Some(toml::Value::String(k)) => k,
            Some(other) => {
                return Err((
                    "kind".into(),
                    format!("expected a string naming the controller kind, found {other}"),
                ))
            }
        };
        Self::from_table(&kind, table)
    }
}

impl Serialize for ControllerCfg {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.to_table().serialize(s)
    }
}

impl<'de> Deserialize<'de> for ControllerCfg {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let table = toml::Table::deserialize(d)?;
        Self::from_toml(table).map_err(|(k, r)| serde::de::Error::custom(format!("`{k}`: {r}")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ehservo_core::control::sliding::SlidingConfig;

    #[test]
    fn kinds_round_trip_through_their_tables() {
        for &kind in ControllerCfg::KINDS {
            let c = ControllerCfg::default_of(kind).unwrap();
            assert_eq!(c.kind(), kind);
            assert_eq!(ControllerCfg::from_toml(c.to_table()).unwrap(), c);
        }
    }

    #[test]
    fn unknown_kinds_and_keys_are_named() {
        let mut t = toml::Table::new();
        t.insert("kind".into(), toml::Value::String("lqr".into()));
        let (k, r) = ControllerCfg::from_toml(t).unwrap_err();
        assert_eq!(k, "kind");
        assert!(r.contains("lqr") && r.contains("nnvsc"), "{r}");
        let mut t = toml::Table::new();
        t.insert("gama1".into(), toml::Value::Float(3.0));
        let (k, r) = ControllerCfg::from_toml(t).unwrap_err();
        assert_eq!(k, "gama1");
        assert!(r.contains("unknown field"), "{r}");
    }

    #[test]
    fn the_paper_kinds_share_one_table() {
        let mut t = toml::Table::new();
        t.insert("kind".into(), toml::Value::String("vsc".into()));
        t.insert("gamma1".into(), toml::Value::Float(200.0));
        let c = ControllerCfg::from_toml(t).unwrap();
        assert_eq!(c.get::<VscConfig>().map(|v| v.0.gamma1), Some(200.0));
        assert!(c.get::<NnVscConfig>().is_none());
        assert_eq!(
            ControllerCfg::default().get::<NnVscConfig>().map(|v| v.0),
            Some(SlidingConfig::default())
        );
    }
}
