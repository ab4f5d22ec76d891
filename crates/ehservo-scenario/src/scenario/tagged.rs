//! What the two registries share: a table of a scenario whose keys depend
//! on one of them, its tag (`[controller] kind`, `[plant] model`). The
//! registries generate the per-variant parts (`from_named`,
//! `params_table`); reading and writing the table, its serde, and the
//! precise error of a table that did not read are written once, here.

use super::overrides::{clean_path, first_line, locate};
use super::ScenarioError;
use ehservo_sim::error::{KeyError, Reason, Unknown};

/// A table tagged by one of its keys.
pub trait Tagged: Sized {
    /// The section (`controller`, `plant`).
    const SECTION: &'static str;
    /// The tag's key (`kind`, `model`).
    const TAG: &'static str;
    /// What a tag names, for messages (`controller kind`, `plant model`).
    const WHAT: &'static str;
    /// The tag when a table names none.
    const DEFAULT: &'static str;
    /// Every registered name, in registry order.
    const NAMES: &'static [&'static str];

    /// This variant's name.
    fn name(&self) -> &'static str;

    /// Variant `name` with the keys of `value`; `None` for an unknown name.
    fn from_named(
        name: &str,
        value: toml::Value,
    ) -> Option<Result<Self, serde_path_to_error::Error<toml::de::Error>>>;

    /// The variant's keys as a table (without the tag).
    fn params_table(&self) -> Result<toml::Table, toml::ser::Error>;

    /// A key that variant `name` refuses with a reason of its own, before
    /// serde's "unknown field" (nothing, the default).
    fn check_keys(_name: &str, _table: &toml::Table) -> Result<(), KeyError> {
        Ok(())
    }

    /// Variant `name` with the keys of `table`. The error's key is the key
    /// inside the section.
    fn from_table(name: &str, table: toml::Table) -> Result<Self, KeyError> {
        Self::check_keys(name, &table)?;
        match Self::from_named(name, toml::Value::Table(table)) {
            Some(r) => r.map_err(|e| {
                let key = clean_path(&e.path().to_string());
                KeyError::new(key, Reason::Serde(first_line(&e.into_inner().to_string())))
            }),
            None => Err(KeyError::new(
                Self::TAG,
                Reason::Unknown(Box::new(Unknown {
                    what: Self::WHAT,
                    name: name.to_string(),
                    known: Self::NAMES,
                })),
            )),
        }
    }

    /// Reads the section's table (its tag defaults to [`Tagged::DEFAULT`]).
    fn from_toml(mut table: toml::Table) -> Result<Self, KeyError> {
        let name = match table.remove(Self::TAG) {
            None => Self::DEFAULT.to_string(),
            Some(toml::Value::String(k)) => k,
            Some(other) => {
                return Err(KeyError::new(
                    Self::TAG,
                    format!("expected a string naming the {}, found {other}", Self::WHAT),
                ))
            }
        };
        Self::from_table(&name, table)
    }

    /// The section's table: the tag and every key.
    fn to_table(&self) -> toml::Table {
        let mut t = toml::Table::new();
        t.insert(Self::TAG.into(), toml::Value::String(self.name().into()));
        // A type that serde can derive always serialises to a table.
        t.extend(self.params_table().unwrap_or_default());
        t
    }
}

/// Serialize and Deserialize of a [`Tagged`] table, through its TOML table.
macro_rules! tagged_serde {
    ($t:ty) => {
        impl serde::Serialize for $t {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                $crate::scenario::tagged::Tagged::to_table(self).serialize(s)
            }
        }

        impl<'de> serde::Deserialize<'de> for $t {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let table = toml::Table::deserialize(d)?;
                <$t as $crate::scenario::tagged::Tagged>::from_toml(table)
                    .map_err(|e| serde::de::Error::custom(e.to_string()))
            }
        }
    };
}
pub(crate) use tagged_serde;

/// The precise error of a section's table that did not deserialise: the
/// key inside it, with its position in `text` when there is one.
pub(crate) fn table_error<T: Tagged>(
    table: toml::Table,
    file: &str,
    text: Option<&str>,
) -> ScenarioError {
    let e = match T::from_toml(table) {
        Err(e) => e,
        Ok(_) => KeyError::new("", format!("invalid {} table", T::SECTION)),
    };
    let key = if e.key.is_empty() {
        T::SECTION.to_string()
    } else {
        format!("{}.{}", T::SECTION, e.key)
    };
    let line_col = text.and_then(|t| locate(t, &key).or_else(|| locate(t, T::SECTION)));
    ScenarioError {
        file: file.to_string(),
        key,
        line_col,
        reason: e.reason,
    }
}

/// [`table_error`] of the section as `text` has it (or "must be a table").
pub(crate) fn section_error<T: Tagged>(text: &str, file: &str) -> ScenarioError {
    let table = toml::from_str::<toml::Table>(text)
        .ok()
        .and_then(|mut t| t.remove(T::SECTION));
    match table {
        Some(toml::Value::Table(t)) => table_error::<T>(t, file, Some(text)),
        _ => ScenarioError {
            file: file.to_string(),
            key: T::SECTION.into(),
            line_col: locate(text, T::SECTION),
            reason: "must be a table".into(),
        },
    }
}
