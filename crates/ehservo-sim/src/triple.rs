//! Serde for the `[f64; 3]` keys of scenarios (x0, poles, a sensor's
//! bias, …) that names the length a key takes: for a longer array, toml's
//! own message is "invalid length 4, expected fewer elements in array".
//! Use as `#[serde(with = "triple")]`, or `triple::option` on an
//! `Option<[f64; 3]>`: a missing key is then not `None` by itself, so the
//! struct needs `#[serde(default)]` (as every scenario section has) or the
//! field its own `default`.
//!
//! ```
//! #[derive(Debug, serde::Deserialize)]
//! struct Section {
//!     #[serde(with = "ehservo_sim::triple")]
//!     x0: [f64; 3],
//! }
//!
//! let s: Section = toml::from_str("x0 = [0.1, 0.0, 0.0]").unwrap();
//! assert_eq!(s.x0, [0.1, 0.0, 0.0]);
//! // Four numbers: the message says how many the key takes.
//! let err = toml::from_str::<Section>("x0 = [0.1, 0.0, 0.0, 0.0]").unwrap_err();
//! assert!(err.to_string().contains("invalid length 4, expected an array of 3 numbers"), "{err}");
//! ```

use serde::{de::Error, Deserialize, Deserializer, Serialize, Serializer};

const EXPECTED: &str = "an array of 3 numbers";

/// Serializes as the array it is.
pub fn serialize<S: Serializer>(v: &[f64; 3], s: S) -> Result<S::Ok, S::Error> {
    v.serialize(s)
}

/// Any length other than 3 is an error that says 3.
pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 3], D::Error> {
    let v = Vec::<f64>::deserialize(d)?;
    <[f64; 3]>::try_from(v.as_slice()).map_err(|_| D::Error::invalid_length(v.len(), &EXPECTED))
}

/// The same for `Option<[f64; 3]>`.
pub mod option {
    use super::*;

    /// Serializes as the array it is (or as none).
    pub fn serialize<S: Serializer>(v: &Option<[f64; 3]>, s: S) -> Result<S::Ok, S::Error> {
        v.serialize(s)
    }

    /// Any length other than 3 is an error that says 3.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[f64; 3]>, D::Error> {
        super::deserialize(d).map(Some)
    }
}

#[cfg(test)]
mod tests {
    use serde::Deserialize;

    #[derive(Deserialize, Debug)]
    struct T {
        #[serde(with = "super")]
        x: [f64; 3],
        #[serde(default, with = "super::option")]
        y: Option<[f64; 3]>,
    }

    #[test]
    fn three_is_read_and_any_other_length_names_three() {
        let t: T = toml::from_str("x = [1, 2.5, -3]").unwrap();
        assert_eq!((t.x, t.y), ([1.0, 2.5, -3.0], None));
        let t: T = toml::from_str("x = [0, 0, 0]\ny = [4, 5, 6]").unwrap();
        assert_eq!(t.y, Some([4.0, 5.0, 6.0]));
        for bad in ["x = [1, 2, 3, 4]", "x = [1, 2]", "x = [0, 0, 0]\ny = []"] {
            let e = toml::from_str::<T>(bad).unwrap_err().to_string();
            assert!(e.contains("an array of 3 numbers"), "{bad}: {e}");
        }
        let e = toml::from_str::<T>("x = [1, \"a\", 3]")
            .unwrap_err()
            .to_string();
        assert!(e.contains("invalid type"), "{e}");
    }
}
