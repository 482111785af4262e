//! One `Estimate` for every artifact (a value, its standard error, an optional interval) and the
//! serde adapters that keep each artifact's established on-disk shape:
//!
//! | shape | written as | where |
//! | --- | --- | --- |
//! | the default | `{value, se}` | the fits of a collision run, the whole-run pair fits |
//! | `stderr` | `{value, stderr}` | diagnosis.json's parameters |
//! | `interval` | `{value, interval: {lo, hi}}` | summary.json's single-run aggregates |
//! | `bounds` | `{value, lo, hi}` | summary.json's collision aggregates |
//!
//! A field picks its shape with `#[serde(with = "…::estimate::stderr")]` (`…::option` for an
//! `Option<Estimate>`, `…::map` for named estimates); a number that could not be computed is NaN
//! in memory and `null` in JSON, in every shape.

use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// An interval `[lo, hi]` (a bootstrap percentile interval, a profile interval).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Interval {
    #[serde(with = "super::nan_null")]
    pub lo: f64,
    #[serde(with = "super::nan_null")]
    pub hi: f64,
}

impl Interval {
    pub fn contains(&self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
    }
}

/// A value (NaN if it could not be computed), its standard error (None when the data do not
/// constrain it or none was computed) and an interval (None when none was made).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    pub value: f64,
    pub se: Option<f64>,
    pub interval: Option<Interval>,
}

impl Estimate {
    /// A value and its standard error (a non-finite one is no standard error).
    pub fn new(value: f64, se: f64) -> Estimate {
        Estimate {
            value,
            se: se.is_finite().then_some(se),
            interval: None,
        }
    }

    /// A value and its interval, no standard error.
    pub fn with_interval(value: f64, interval: Option<Interval>) -> Estimate {
        Estimate {
            value,
            se: None,
            interval,
        }
    }

    /// The standard error, NaN when there is none.
    pub fn se_or_nan(&self) -> f64 {
        self.se.unwrap_or(f64::NAN)
    }

    /// The interval's ends, NaN when there is none.
    pub fn lo(&self) -> f64 {
        self.interval.map_or(f64::NAN, |i| i.lo)
    }

    pub fn hi(&self) -> f64 {
        self.interval.map_or(f64::NAN, |i| i.hi)
    }
}

/// The on-disk shapes, one serde struct each (their field names are the documented contract,
/// traced by `contract`).
pub mod shape {
    // paths from the crate root: the fingerprints follow paths file by file (`build/code_deps.rs`)
    use crate::artifacts::estimate::{Estimate, Interval};
    use serde::{Deserialize, Serialize};

    /// `{value, se}`: a fitted value and its standard error.
    #[derive(Serialize, Deserialize)]
    pub struct ValueSe {
        #[serde(with = "crate::artifacts::nan_null")]
        pub value: f64,
        pub se: Option<f64>,
    }

    /// `{value, stderr}`: both numbers, `null` when not computed.
    #[derive(Serialize, Deserialize)]
    pub struct ValueStderr {
        #[serde(with = "crate::artifacts::nan_null")]
        pub value: f64,
        #[serde(with = "crate::artifacts::nan_null")]
        pub stderr: f64,
    }

    /// `{value, interval: {lo, hi} | null}`.
    #[derive(Serialize, Deserialize)]
    pub struct ValueInterval {
        #[serde(with = "crate::artifacts::nan_null")]
        pub value: f64,
        pub interval: Option<Interval>,
    }

    /// `{value, lo, hi}`: the interval's ends beside the value, `null` when there is none.
    #[derive(Serialize, Deserialize)]
    pub struct ValueBounds {
        #[serde(with = "crate::artifacts::nan_null")]
        pub value: f64,
        #[serde(with = "crate::artifacts::nan_null")]
        pub lo: f64,
        #[serde(with = "crate::artifacts::nan_null")]
        pub hi: f64,
    }

    impl From<&Estimate> for ValueSe {
        fn from(e: &Estimate) -> Self {
            ValueSe {
                value: e.value,
                se: e.se,
            }
        }
    }

    impl From<ValueSe> for Estimate {
        fn from(s: ValueSe) -> Self {
            Estimate {
                value: s.value,
                se: s.se,
                interval: None,
            }
        }
    }

    impl From<&Estimate> for ValueStderr {
        fn from(e: &Estimate) -> Self {
            ValueStderr {
                value: e.value,
                stderr: e.se_or_nan(),
            }
        }
    }

    impl From<ValueStderr> for Estimate {
        fn from(s: ValueStderr) -> Self {
            Estimate::new(s.value, s.stderr)
        }
    }

    impl From<&Estimate> for ValueInterval {
        fn from(e: &Estimate) -> Self {
            ValueInterval {
                value: e.value,
                interval: e.interval,
            }
        }
    }

    impl From<ValueInterval> for Estimate {
        fn from(s: ValueInterval) -> Self {
            Estimate::with_interval(s.value, s.interval)
        }
    }

    impl From<&Estimate> for ValueBounds {
        fn from(e: &Estimate) -> Self {
            ValueBounds {
                value: e.value,
                lo: e.lo(),
                hi: e.hi(),
            }
        }
    }

    impl From<ValueBounds> for Estimate {
        fn from(s: ValueBounds) -> Self {
            let interval =
                (s.lo.is_finite() || s.hi.is_finite()).then_some(Interval { lo: s.lo, hi: s.hi });
            Estimate::with_interval(s.value, interval)
        }
    }
}

impl Serialize for Estimate {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        shape::ValueSe::from(self).serialize(s)
    }
}

impl<'de> Deserialize<'de> for Estimate {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        shape::ValueSe::deserialize(d).map(Estimate::from)
    }
}

/// The serde adapter module of one shape: `serialize`/`deserialize` for an `Estimate`, and
/// `option` and `map` for an `Option<Estimate>` and a `BTreeMap<String, Estimate>`.
macro_rules! adapter {
    ($(#[$doc:meta])* $name:ident => $shape:ident) => {
        $(#[$doc])*
        pub mod $name {
            use crate::artifacts::estimate::shape::$shape as Shape;
            use crate::artifacts::estimate::Estimate;
            use serde::{Deserialize, Deserializer, Serialize, Serializer};

            pub fn serialize<S: Serializer>(e: &Estimate, s: S) -> Result<S::Ok, S::Error> {
                Shape::from(e).serialize(s)
            }

            pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Estimate, D::Error> {
                Shape::deserialize(d).map(Estimate::from)
            }

            /// An optional estimate in this shape (`null` when absent).
            pub mod option {
                use crate::artifacts::estimate::shape::$shape as Shape;
                use crate::artifacts::estimate::Estimate;
                use serde::{Deserialize, Deserializer, Serialize, Serializer};

                pub fn serialize<S: Serializer>(
                    e: &Option<Estimate>,
                    s: S,
                ) -> Result<S::Ok, S::Error> {
                    e.as_ref().map(Shape::from).serialize(s)
                }

                pub fn deserialize<'de, D: Deserializer<'de>>(
                    d: D,
                ) -> Result<Option<Estimate>, D::Error> {
                    Ok(Option::<Shape>::deserialize(d)?.map(Estimate::from))
                }
            }

            /// Named estimates in this shape (a JSON object, sorted by name).
            pub mod map {
                use crate::artifacts::estimate::shape::$shape as Shape;
                use crate::artifacts::estimate::Estimate;
                use serde::{Deserialize, Deserializer, Serialize, Serializer};
                use std::collections::BTreeMap;

                /// The estimates in this shape, for a value built by hand (`serde_json::json!`).
                pub fn shaped(m: &BTreeMap<String, Estimate>) -> BTreeMap<&str, Shape> {
                    m.iter().map(|(k, e)| (k.as_str(), Shape::from(e))).collect()
                }

                pub fn serialize<S: Serializer>(
                    m: &BTreeMap<String, Estimate>,
                    s: S,
                ) -> Result<S::Ok, S::Error> {
                    shaped(m).serialize(s)
                }

                pub fn deserialize<'de, D: Deserializer<'de>>(
                    d: D,
                ) -> Result<BTreeMap<String, Estimate>, D::Error> {
                    Ok(BTreeMap::<String, Shape>::deserialize(d)?
                        .into_iter()
                        .map(|(k, s)| (k, Estimate::from(s)))
                        .collect())
                }
            }
        }
    };
}

adapter!(
    /// `{value, stderr}` (diagnosis.json).
    stderr => ValueStderr
);
adapter!(
    /// `{value, interval}` (summary.json, single runs).
    interval => ValueInterval
);
adapter!(
    /// `{value, lo, hi}` (summary.json, collision runs).
    bounds => ValueBounds
);

#[cfg(test)]
mod tests {
    use super::*;
    use serde::{Deserialize, Serialize};
    use std::collections::BTreeMap;

    #[derive(Serialize, Deserialize)]
    struct Shapes {
        se: Estimate,
        #[serde(with = "stderr")]
        stderr: Estimate,
        #[serde(with = "interval")]
        interval: Estimate,
        #[serde(with = "bounds")]
        bounds: Estimate,
        #[serde(with = "bounds::option")]
        absent: Option<Estimate>,
        #[serde(with = "stderr::map")]
        named: BTreeMap<String, Estimate>,
    }

    #[test]
    fn every_shape_reads_and_writes_its_own_bytes() {
        let text = r#"{"se":{"value":1.5,"se":0.25},"stderr":{"value":2.0,"stderr":null},"interval":{"value":null,"interval":{"lo":0.5,"hi":0.75}},"bounds":{"value":3.0,"lo":null,"hi":null},"absent":null,"named":{"a":{"value":1.0,"stderr":0.0},"b":{"value":null,"stderr":0.5}}}"#;
        let s: Shapes = serde_json::from_str(text).unwrap();
        assert_eq!(s.se, Estimate::new(1.5, 0.25));
        assert_eq!(s.stderr.se, None);
        assert!(s.interval.value.is_nan());
        assert_eq!(s.interval.interval, Some(Interval { lo: 0.5, hi: 0.75 }));
        assert_eq!(s.bounds, Estimate::with_interval(3.0, None));
        assert!(s.absent.is_none());
        assert_eq!(s.named["a"].se, Some(0.0));
        assert_eq!(serde_json::to_string(&s).unwrap(), text);
        // a value built by hand keeps the shape too
        let by_hand = serde_json::json!({ "named": stderr::map::shaped(&s.named) });
        assert_eq!(
            by_hand.to_string(),
            r#"{"named":{"a":{"stderr":0.0,"value":1.0},"b":{"stderr":0.5,"value":null}}}"#
        );
    }

    #[test]
    fn a_number_that_could_not_be_computed_is_null_in_every_shape() {
        let nan = Estimate {
            value: f64::NAN,
            se: Some(f64::NAN),
            interval: Some(Interval {
                lo: f64::NAN,
                hi: 1.0,
            }),
        };
        let s = Shapes {
            se: nan,
            stderr: nan,
            interval: nan,
            bounds: nan,
            absent: Some(nan),
            named: BTreeMap::from([("x".to_string(), nan)]),
        };
        assert_eq!(
            serde_json::to_string(&s).unwrap(),
            r#"{"se":{"value":null,"se":null},"stderr":{"value":null,"stderr":null},"interval":{"value":null,"interval":{"lo":null,"hi":1.0}},"bounds":{"value":null,"lo":null,"hi":1.0},"absent":{"value":null,"lo":null,"hi":1.0},"named":{"x":{"value":null,"stderr":null}}}"#
        );
    }
}
