//! The controller's configuration on the wire: the core's own `Config`
//! types (a scenario's `[controller]` table), one variant per kind.
//!
//! postcard round-trips them through [`crate::noskip`] (their optional keys
//! are `skip_serializing_if`), so no mirror type has to follow their
//! fields. A new kind in the registry is one variant here and one arm in
//! [`crate::law::AnyLaw::build`]; the host's conversion from the registry
//! (`ehservo::pil::wire_controller`) is an exhaustive match, so a kind
//! missing here does not compile.

use ehservo_core::control::adrc::AdrcConfig;
use ehservo_core::control::arc::ArcConfig;
use ehservo_core::control::backstepping::BacksteppingConfig;
use ehservo_core::control::nn_robust::NnRobustConfig;
use ehservo_core::control::open_loop::OpenLoopConfig;
use ehservo_core::control::pid::PidConfig;
use ehservo_core::control::sliding::{NnVscConfig, VscConfig, VscSatConfig};
use ehservo_core::control::sta::StaConfig;
use ehservo_core::control::Config;
use serde::{Deserialize, Serialize};

/// A controller kind with its parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[allow(missing_docs)] // each variant is the kind of the same name
pub enum WireController {
    Nnvsc(NnVscConfig),
    Vsc(VscConfig),
    VscSat(VscSatConfig),
    Pid(PidConfig),
    NnRobust(NnRobustConfig),
    Adrc(AdrcConfig),
    Sta(StaConfig),
    Arc(ArcConfig),
    Backstepping(BacksteppingConfig),
    /// `open-loop`.
    OpenLoop(OpenLoopConfig),
}

impl WireController {
    /// The kind's name (`controller.kind`).
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Nnvsc(_) => NnVscConfig::KIND,
            Self::Vsc(_) => VscConfig::KIND,
            Self::VscSat(_) => VscSatConfig::KIND,
            Self::Pid(_) => PidConfig::KIND,
            Self::NnRobust(_) => NnRobustConfig::KIND,
            Self::Adrc(_) => AdrcConfig::KIND,
            Self::Sta(_) => StaConfig::KIND,
            Self::Arc(_) => ArcConfig::KIND,
            Self::Backstepping(_) => BacksteppingConfig::KIND,
            Self::OpenLoop(_) => OpenLoopConfig::KIND,
        }
    }
}
