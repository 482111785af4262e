//! What the engine runs with: the stage kinds, their code fingerprints, and the code identity.
//!
//! The engine knows no kind by name: the caller (the command line, or a test) assembles the
//! catalog from its kinds and hands it in.
//!
//! The fingerprint map is data, not a compile-time lookup, so a test can change one kind's
//! fingerprint and watch exactly that stage and its descendants go stale.

use super::identity;
use super::stage::StageKind;
use std::collections::BTreeMap;

pub struct Catalog {
    pub kinds: Vec<Box<dyn StageKind>>,
    /// kind → hex fingerprint; `"*"` is the fallback (a hash of all of `src/`).
    pub fingerprints: BTreeMap<String, String>,
    pub code_commit: String,
    pub version: String,
}

impl Catalog {
    /// `kinds` with the code fingerprints that build.rs computed for this binary.
    pub fn with_kinds(kinds: Vec<Box<dyn StageKind>>) -> Catalog {
        Catalog {
            kinds,
            fingerprints: identity::FINGERPRINTS
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect(),
            code_commit: identity::CODE_COMMIT.to_string(),
            version: identity::GROOVE_VERSION.to_string(),
        }
    }

    pub fn kind(&self, name: &str) -> Option<&dyn StageKind> {
        self.kinds
            .iter()
            .find(|k| k.kind() == name)
            .map(|k| k.as_ref())
    }

    /// Every kind name a pipeline may use, sorted (includes the engine's own `command`).
    pub fn kind_names(&self) -> Vec<&str> {
        let mut names: Vec<&str> = self.kinds.iter().map(|k| k.kind()).collect();
        names.push("command");
        names.sort_unstable();
        names
    }

    /// The code fingerprint of a kind (falls back to the whole-source fingerprint).
    pub fn fingerprint(&self, kind: &str) -> &str {
        self.fingerprints
            .get(kind)
            .or_else(|| self.fingerprints.get("*"))
            .map(String::as_str)
            .unwrap_or("unknown")
    }

    /// Fingerprints of every kind, for the provenance record (sorted, without the fallback).
    pub fn all_fingerprints(&self) -> BTreeMap<String, String> {
        self.kind_names()
            .into_iter()
            .map(|k| (k.to_string(), self.fingerprint(k).to_string()))
            .collect()
    }
}
