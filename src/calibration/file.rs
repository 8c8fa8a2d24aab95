//! The tables naocalib's own calibration file and the result JSON of `naocalib solve
//! --json` share: a standing leg offset as written and as read ([`StandingFile`],
//! [`StandingIn`]) and the `parameters` table whose names must be unique ([`UniqueMap`]).
//! The file itself is one of the export formats, naocalib's own.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// One standing leg offset as written (`[standing.<offset>]`): its value (derived from the
/// parameters, deg), one-sigma (deg), the stand's torque and the largest lying torque its
/// compliance was estimated from (N·m).
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StandingFile {
    /// The standing offset (deg).
    pub value: f64,
    /// Its one-sigma (deg).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std: Option<f64>,
    /// The stand's gravity torque about the joint (N·m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tau_stand: Option<f64>,
    /// The largest lying torque the compliance was estimated from (N·m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tau_lying_max: Option<f64>,
}

/// A standing offset as read: a table, or a bare value (files of earlier versions).
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
#[serde(untagged)]
pub enum StandingIn {
    /// `{value, std, tau_stand, tau_lying_max}`.
    Table(StandingFile),
    /// A bare value (deg), as earlier versions wrote.
    Value(f64),
}

/// The `parameters` table of a calibration or result file, by name: read, its keys must be
/// unique (serde's maps keep the last of a repeated key, so a parameter given twice would
/// pass unnoticed); written, in alphabetical order.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(transparent)]
pub struct UniqueMap<V>(pub BTreeMap<String, V>);

impl<'de, V: Deserialize<'de>> Deserialize<'de> for UniqueMap<V> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visit<V>(std::marker::PhantomData<V>);
        impl<'de, V: Deserialize<'de>> serde::de::Visitor<'de> for Visit<V> {
            type Value = UniqueMap<V>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a table of parameters")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<Self::Value, A::Error> {
                let mut out = BTreeMap::new();
                while let Some(key) = map.next_key::<String>()? {
                    if out.contains_key(&key) {
                        return Err(serde::de::Error::custom(format!(
                            "parameters.{key} is given twice"
                        )));
                    }
                    let value = map.next_value()?;
                    out.insert(key, value);
                }
                Ok(UniqueMap(out))
            }
        }
        d.deserialize_map(Visit(std::marker::PhantomData))
    }
}
