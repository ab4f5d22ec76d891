//! The controller's configuration on the wire: the core's own `Config`
//! types (a scenario's `[controller]` table), one variant per kind.
//!
//! postcard round-trips them through [`crate::noskip`] (their optional keys
//! are `skip_serializing_if`), so no mirror type has to follow their
//! fields. The enum is generated from the one list of kinds
//! ([`ehservo_core::controller_kinds!`]), as the scenario's registry is: a
//! new kind needs no line here.

use serde::{Deserialize, Serialize};

macro_rules! wire_controller {
    ($($variant:ident $name:literal => $ty:ty),* $(,)?) => {
        /// A controller kind with its parameters: one variant per line of
        /// [`ehservo_core::controller_kinds!`], in its order (postcard
        /// writes the variant's index).
        #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
        pub enum WireController {
            $(
                #[doc = concat!("`kind = \"", $name, "\"`.")]
                $variant($ty),
            )*
        }

        impl WireController {
            /// The kind's name (`controller.kind`).
            pub fn kind(&self) -> &'static str {
                match self {
                    $(Self::$variant(_) => $name,)*
                }
            }
        }
    };
}

ehservo_core::controller_kinds!(wire_controller);
