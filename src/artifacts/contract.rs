//! The documented contract of the published files (fits.csv, summary.json, diagnosis.json),
//! generated from the artifact types: the field names are read from the serde derives, so the
//! README block (`markdown`, checked by `tests/contracts.rs`) cannot drift from the code.

use super::estimate::shape;
use super::{diagnosis, fits_table, summary};
use serde::de::{self, Deserialize, Deserializer, Visitor};
use std::fmt;

/// Where the README's generated block starts and ends.
pub const BEGIN: &str = "<!-- contract:begin (generated from src/artifacts by `groove::artifacts::contract::markdown`; tests/contracts.rs checks it) -->";
pub const END: &str = "<!-- contract:end -->";

/// The error that stops a trace once the field names are known.
#[derive(Debug)]
struct Stop;

impl fmt::Display for Stop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("field names traced")
    }
}

impl std::error::Error for Stop {}

impl de::Error for Stop {
    fn custom<T: fmt::Display>(_: T) -> Self {
        Stop
    }
}

/// A deserializer that records the field names a struct's `Deserialize` asks for, then stops.
struct FieldNames(Option<&'static [&'static str]>);

impl<'de> Deserializer<'de> for &mut FieldNames {
    type Error = Stop;

    fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, Stop> {
        Err(Stop)
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        fields: &'static [&'static str],
        _visitor: V,
    ) -> Result<V::Value, Stop> {
        self.0 = Some(fields);
        Err(Stop)
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
        option unit unit_struct newtype_struct seq tuple tuple_struct map enum identifier
        ignored_any
    }
}

/// The serialized field names of a struct type, in order.
pub fn fields_of<T: Deserialize<'static>>() -> &'static [&'static str] {
    let mut names = FieldNames(None);
    let _ = T::deserialize(&mut names);
    names.0.unwrap_or(&[])
}

fn line(what: &str, fields: &[&str]) -> String {
    let list: Vec<String> = fields.iter().map(|f| format!("`{f}`")).collect();
    format!("- {what}: {}\n", list.join(", "))
}

/// The contract of fits.csv, summary.json and diagnosis.json as a Markdown list (between `BEGIN`
/// and `END` in the README).
pub fn markdown() -> String {
    let mut s = String::new();
    s.push_str(BEGIN);
    s.push('\n');
    s.push_str(&line("`fits.csv` columns", &fits_table::COLUMNS));
    s.push_str(&line("`summary.json`", fields_of::<summary::Summary>()));
    s.push_str(&line(
        "`summary.json` `single`",
        fields_of::<summary::SingleSummary>(),
    ));
    s.push_str(&line(
        "`summary.json` `single.materials.<material>` and `single.pooled`",
        fields_of::<summary::MaterialSummary>(),
    ));
    s.push_str(&line(
        "`summary.json` `t_vs_v0`",
        fields_of::<summary::DragLine>(),
    ));
    s.push_str(&line(
        "`summary.json` `mu_vs_v0`",
        fields_of::<summary::FrictionLine>(),
    ));
    s.push_str(&line(
        "`summary.json` an estimate (`interval`: `lo`, `hi`)",
        fields_of::<shape::ValueInterval>(),
    ));
    s.push_str(&line(
        "`summary.json` `collisions`",
        fields_of::<summary::CollisionSummary>(),
    ));
    s.push_str(&line(
        "`summary.json` `collisions.mu_pp`",
        fields_of::<summary::MuPp>(),
    ));
    s.push_str(&line(
        "`summary.json` `collisions.restitution[]`",
        fields_of::<summary::RestitutionCurve>(),
    ));
    s.push_str(&line(
        "`diagnosis.json`",
        fields_of::<diagnosis::Diagnosis>(),
    ));
    s.push_str(&line(
        "`diagnosis.json` `findings[]`",
        fields_of::<diagnosis::Finding>(),
    ));
    s.push_str(&line(
        "`diagnosis.json` `findings[].evidence`",
        fields_of::<diagnosis::Evidence>(),
    ));
    s.push_str(&line(
        "`diagnosis.json` a parameter",
        fields_of::<shape::ValueStderr>(),
    ));
    s.push_str(&line(
        "`diagnosis.json` `candidates[]`",
        fields_of::<diagnosis::CandidateRow>(),
    ));
    s.push_str(&line(
        "`diagnosis.json` `baseline_model`, `model`, `findings[].baseline`/`extended`",
        fields_of::<diagnosis::ModelScore>(),
    ));
    s.push_str(END);
    s.push('\n');
    s
}

#[cfg(test)]
mod tests {
    use super::super::collision_fit;
    use super::*;

    #[test]
    fn traces_the_serialized_names_in_order() {
        assert_eq!(fields_of::<shape::ValueInterval>(), ["value", "interval"]);
        assert_eq!(fields_of::<collision_fit::Estimate>(), ["value", "se"]);
        assert_eq!(fields_of::<shape::ValueBounds>(), ["value", "lo", "hi"]);
        assert!(fields_of::<diagnosis::Finding>().contains(&"where"));
        let md = markdown();
        assert!(md.starts_with(BEGIN) && md.ends_with(&format!("{END}\n")));
        assert!(md.contains("`mu_weighted`"), "{md}");
    }
}
