//! Writing an artifact's JSON only when it reads back as its own type: serde writes a NaN or
//! infinite `f64` as `null`, which a plain `f64` field cannot read, so such a number would pass
//! the writing stage and stop a later one. Refused here instead, named by its key and line.

use serde::de::DeserializeOwned;
use serde::Serialize;

/// `value` as indented JSON with a final newline, or why it cannot be read back as `T` (`name`
/// is the artifact's file name, e.g. `diagnosis.json`).
pub fn to_json_pretty_checked<T: Serialize + DeserializeOwned>(
    name: &str,
    value: &T,
) -> Result<Vec<u8>, String> {
    let mut bytes = serde_json::to_vec_pretty(value)
        .map_err(|e| format!("{name} could not be serialized: {e}"))?;
    bytes.push(b'\n');
    if let Err(e) = serde_json::from_slice::<T>(&bytes) {
        let text = String::from_utf8_lossy(&bytes);
        let line = text.lines().nth(e.line().saturating_sub(1)).unwrap_or("");
        let key = line
            .trim()
            .strip_prefix('"')
            .and_then(|l| l.split_once('"'))
            .map_or("a value", |(k, _)| k);
        let what = if line.contains("null") {
            format!("`{key}` is not a finite number (NaN or infinite, which JSON writes as null)")
        } else {
            format!("`{key}` does not read back ({e})")
        };
        return Err(format!(
            "{name} was not written: {what} at line {} of what would have been written; the stage computed a number it cannot report: this is a bug, please report it with the dataset",
            e.line()
        ));
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Serialize, Deserialize)]
    struct Inner {
        mu: f64,
    }

    #[derive(Serialize, Deserialize)]
    struct Outer {
        name: String,
        inner: Inner,
    }

    #[test]
    fn a_finite_value_is_written_and_a_nan_is_refused_by_its_key() {
        let ok = Outer {
            name: "a".into(),
            inner: Inner { mu: 0.25 },
        };
        let bytes = to_json_pretty_checked("x.json", &ok).unwrap();
        assert!(bytes.ends_with(b"}\n"));
        let bad = Outer {
            name: "a".into(),
            inner: Inner { mu: f64::NAN },
        };
        let err = to_json_pretty_checked("x.json", &bad).unwrap_err();
        assert!(err.contains("x.json was not written"), "{err}");
        assert!(err.contains("`mu` is not a finite number"), "{err}");
        assert!(err.contains("line 4"), "{err}");
    }
}
