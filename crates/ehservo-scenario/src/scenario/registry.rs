//! The registry: the one place that maps `controller.kind` to a
//! controller's parameter type.
//!
//! A kind is a type implementing [`ehservo_core::control::Config`] (its
//! kind name, whether it uses the surface, how to build the controller) with
//! serde's derive (its `[controller]` keys, `deny_unknown_fields`). The kinds
//! are the one list [`ehservo_core::controller_kinds!`]: the registry below,
//! its JSON Schema, the wire's enum and the board's `AnyLaw` are all
//! generated from it, so adding a controller kind is its file in the core
//! and one line there; every command, study and output then knows it. Code that is generic over the
//! kind implements [`Visit`] and calls [`ControllerCfg::visit`]; code that
//! needs one kind's parameters asks [`ControllerCfg::get`].

use super::tagged::{tagged_serde, Tagged};
use ehservo_core::control::{Config, Design};
use ehservo_core::error::ParamError;
use ehservo_sim::error::KeyError;
use ehservo_wire::config::WireController;
use serde::de::DeserializeOwned;
use serde::Serialize;
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
    ($($variant:ident $name:literal => $ty:ty),* $(,)?) => {
        /// A scenario's `[controller]` table: one of the registered kinds
        /// with its parameters.
        #[derive(Debug, Clone, PartialEq)]
        pub enum ControllerCfg {
            $(
                #[doc = concat!("`kind = \"", $name, "\"`.")]
                $variant($ty),
            )*
        }

        /// A built controller of one of the registered kinds, with the
        /// parameters it was built from: what a [`crate::Loop`] holds.
        #[derive(Debug, Clone)]
        pub(crate) enum Built {
            $(
                #[doc = concat!("`kind = \"", $name, "\"`, built.")]
                $variant($ty, <$ty as Config>::Controller),
            )*
        }

        impl Built {
            /// Calls `v` with the parameters and the controller, typed.
            pub(crate) fn visit<V: BuiltVisit>(&self, v: V) -> V::Out {
                match self {
                    $(Self::$variant(cfg, ctrl) => v.visit(cfg, ctrl),)*
                }
            }
        }

        impl ControllerCfg {
            /// Every registered kind, in registry order.
            pub const KINDS: &'static [&'static str] = &[$($name),*];

            /// The kind's name.
            pub fn kind(&self) -> &'static str {
                match self {
                    $(Self::$variant(_) => $name,)*
                }
            }

            /// Whether the kind's law uses the switching surface.
            pub fn uses_surface(&self) -> bool {
                match self {
                    $(Self::$variant(_) => <$ty as Config>::USES_SURFACE,)*
                }
            }

            /// Whether the kind's law closes a force or pressure loop
            /// ([`Config::CLOSES_ON_FORCE`]).
            pub fn closes_on_force(&self) -> bool {
                match self {
                    $(Self::$variant(_) => <$ty as Config>::CLOSES_ON_FORCE,)*
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

            /// The kind's defaults.
            pub fn default_of(kind: &str) -> Option<Self> {
                match kind {
                    $($name => Some(Self::$variant(<$ty>::default())),)*
                    _ => None,
                }
            }

            /// Every kind with the JSON Schema of its keys (`ehservo schema`).
            pub fn kind_schemas(
                g: &mut schemars::SchemaGenerator,
            ) -> Vec<(&'static str, schemars::Schema)> {
                vec![$(($name, g.subschema_for::<$ty>())),*]
            }

            /// The controller built on `design`: the parameters checked,
            /// and the law made once. The error names the parameter.
            pub(crate) fn build(&self, design: &Design) -> Result<Built, ParamError> {
                Ok(match self {
                    $(Self::$variant(c) => Built::$variant(c.clone(), c.build(design)?),)*
                })
            }

            /// The parameters as the processor-in-the-loop wire carries
            /// them (the same type, kind for kind).
            pub fn wire(&self) -> WireController {
                match self {
                    $(Self::$variant(c) => WireController::$variant(c.clone()),)*
                }
            }
        }

        impl Tagged for ControllerCfg {
            const SECTION: &'static str = "controller";
            const TAG: &'static str = "kind";
            const WHAT: &'static str = "controller kind";
            const DEFAULT: &'static str = DEFAULT_KIND;
            const NAMES: &'static [&'static str] = Self::KINDS;

            fn name(&self) -> &'static str {
                self.kind()
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
        }
    };
}

ehservo_core::controller_kinds!(registry);

/// Code generic over a built controller's kind: its parameters and the
/// controller they built.
pub(crate) trait BuiltVisit {
    /// What the visit returns.
    type Out;
    /// Called with the parameters and the built controller, typed.
    fn visit<K: ControllerConfig>(self, cfg: &K, ctrl: &K::Controller) -> Self::Out;
}

impl Default for ControllerCfg {
    fn default() -> Self {
        Self::default_of(DEFAULT_KIND).expect("the default kind is registered")
    }
}

impl ControllerCfg {
    /// The `[controller]` table: `kind` and every parameter.
    pub fn to_table(&self) -> toml::Table {
        Tagged::to_table(self)
    }

    /// Reads a `[controller]` table (its `kind` defaults to
    /// [`DEFAULT_KIND`]). The error's key is the key inside `[controller]`.
    pub fn from_toml(table: toml::Table) -> Result<Self, KeyError> {
        <Self as Tagged>::from_toml(table)
    }
}

tagged_serde!(ControllerCfg);

#[cfg(test)]
mod tests {
    use super::*;
    use ehservo_core::control::sliding::{NnVscConfig, SlidingConfig, VscConfig};

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
        let e = ControllerCfg::from_toml(t).unwrap_err();
        assert_eq!(e.key, "kind");
        let r = e.reason.to_string();
        assert!(r.contains("lqr") && r.contains("nnvsc"), "{r}");
        let mut t = toml::Table::new();
        t.insert("gama1".into(), toml::Value::Float(3.0));
        let e = ControllerCfg::from_toml(t).unwrap_err();
        assert_eq!(e.key, "gama1");
        assert!(e.reason.to_string().contains("unknown field"), "{e}");
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
