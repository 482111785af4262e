//! Fuzzing of what groove reads from a store or a remote: entry files (loose and packed), pack
//! indexes, and remote entries, mutated from sound ones and stuffed with hostile names and
//! hashes. Invariant checked: no store or remote entry can make groove write, read or delete
//! outside the project and its store, and anything malformed is damage, never a panic.
//!
//! Each property runs 256 cases by default (seconds in CI); set `PROPTEST_CASES` for more, e.g.
//! `PROPTEST_CASES=100000 cargo test --locked --features s3 --release --test fuzz_store`.

use groove::engine::hashing::is_sha256;
use groove::engine::hashing::{sha256_hex, HashCache};
use groove::engine::materialize;
use groove::engine::remote::file::FileRemote;
use groove::engine::remote::{Mode, RemoteCache};
use groove::engine::store::{is_plain_name, Entry, Store, Stored};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use std::path::{Path, PathBuf};

fn config() -> Config {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(256);
    Config {
        cases,
        failure_persistence: None,
        rng_seed: RngSeed::Fixed(20_261_127),
        ..Config::default()
    }
}

/// The key every case's entry is stored under.
const KEY: &str = "3f7a0c6e9b1d2e4f5a6b7c8d9e0f1a2b3c4d5e6f7a8b9c0d1e2f3a4b5c6d7e8f";

/// Names that mean a path: climbing, absolute, separators, control characters.
fn hostile_name() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("../escaped".to_string()),
        Just("../../../../escaped".to_string()),
        Just("/tmp/escaped-absolute".to_string()),
        Just("..".to_string()),
        Just(".".to_string()),
        Just("".to_string()),
        Just("a/b".to_string()),
        Just("a\\b".to_string()),
        Just("nul\0byte".to_string()),
        Just("new\nline".to_string()),
        Just("run_a.csv".to_string()),
        Just("é".to_string()),
        "[a-z./\\\\]{0,12}",
        any::<String>(),
    ]
}

/// Hashes: sound, uppercase, short, path-like of the right length, anything.
fn hostile_hash() -> impl Strategy<Value = String> {
    let sound = sha256_hex(b"blob");
    prop_oneof![
        Just(sound.clone()),
        Just(sound.to_uppercase()),
        Just(sound[..63].to_string()),
        Just(format!("..{}", "/..".repeat(20) + "/escaped")),
        Just(format!("..{:/<62}", "/")),
        Just("a".to_string()),
        Just("é".repeat(32)),
        "[0-9a-f./]{60,66}",
        any::<String>(),
    ]
}

/// An entry's JSON: sound in shape, with hostile output names, item names and hashes.
fn crafted_entry() -> impl Strategy<Value = Vec<u8>> {
    let file = hostile_hash().prop_map(|h| serde_json::json!({"type": "file", "sha256": h}));
    let collection =
        proptest::collection::vec((hostile_name(), hostile_hash()), 0..4).prop_map(|items| {
            let items: serde_json::Map<String, serde_json::Value> =
                items.into_iter().map(|(n, h)| (n, h.into())).collect();
            serde_json::json!({"type": "collection", "items": items})
        });
    let stored = prop_oneof![file, collection];
    proptest::collection::vec((hostile_name(), stored), 0..3).prop_map(|outputs| {
        let outputs: serde_json::Map<String, serde_json::Value> = outputs.into_iter().collect();
        serde_json::to_vec(&serde_json::json!({ "outputs": outputs })).unwrap()
    })
}

/// Crafted entries, then bytes of them flipped, cut or repeated.
fn entry_bytes() -> impl Strategy<Value = Vec<u8>> {
    (
        crafted_entry(),
        proptest::collection::vec((any::<usize>(), any::<u8>()), 0..4),
        any::<Option<usize>>(),
    )
        .prop_map(|(mut bytes, flips, cut)| {
            for (at, b) in flips {
                if !bytes.is_empty() {
                    let n = bytes.len();
                    bytes[at % n] = b;
                }
            }
            if let Some(cut) = cut {
                bytes.truncate(cut % (bytes.len() + 1));
            }
            bytes
        })
}

/// Every file and link below `dir` (relative, sorted), links not followed.
fn listing(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let path = e.path();
            match e.file_type().is_ok_and(|t| t.is_dir()) {
                true => stack.push(path),
                false => out.push(path.strip_prefix(dir).unwrap().to_path_buf()),
            }
        }
    }
    out.sort();
    out
}

/// A sandbox: `project/.groove` the store (with one sound blob), `remote/`, and a `victim`
/// file and `escaped*` names that only an escape could touch.
struct Sandbox {
    dir: tempfile::TempDir,
}

impl Sandbox {
    fn new() -> Sandbox {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("project/reports")).unwrap();
        std::fs::create_dir_all(dir.path().join("remote/entries")).unwrap();
        std::fs::write(dir.path().join("victim"), "keep\n").unwrap();
        let s = Sandbox { dir };
        s.store().put_object(b"blob").unwrap();
        let h = sha256_hex(b"blob");
        let blob = s.remote().join(format!("objects/{}/{}", &h[..2], &h[2..]));
        std::fs::create_dir_all(blob.parent().unwrap()).unwrap();
        std::fs::write(blob, b"blob").unwrap();
        s
    }
    fn project(&self) -> PathBuf {
        self.dir.path().join("project")
    }
    fn remote(&self) -> PathBuf {
        self.dir.path().join("remote")
    }
    fn store(&self) -> Store {
        Store::at(&self.project())
    }
    /// What lies outside the project and the remote.
    fn outside(&self) -> Vec<PathBuf> {
        listing(self.dir.path())
            .into_iter()
            .filter(|p| !p.starts_with("project") && !p.starts_with("remote"))
            .collect()
    }
}

/// Use an entry the way every verb does: look it up, check its objects, write its outputs into
/// the reports folder, verify and gc the store.
fn exercise(store: &Store, entry: Option<Entry>, reports: &Path) {
    let hashes = HashCache::load(&store.dir.join("hashes.json"));
    let _ = store.entry_checked(KEY, &hashes);
    if let Some(entry) = entry {
        for (name, stored) in &entry.outputs {
            assert!(is_plain_name(name), "output {name:?} was taken");
            let objects: Vec<&String> = match stored {
                Stored::File { sha256 } => vec![sha256],
                Stored::Collection { items } => {
                    assert!(items.keys().all(|n| is_plain_name(n)), "{items:?}");
                    items.values().collect()
                }
            };
            assert!(objects.iter().all(|h| is_sha256(h)), "{objects:?}");
            let _ = store.load(stored);
            if let Ok(Some(staged)) =
                materialize::stage(store, &reports.join(name), stored, &|| None, &hashes)
            {
                let _ = staged.commit();
            }
            for h in objects {
                store.remove_object(h);
            }
        }
    }
    let _ = store.verify();
    let _ = store.gc(&Default::default(), &Default::default());
}

/// A loose entry file of any bytes.
#[test]
fn store_entries_never_panic_or_reach_outside() {
    let sandbox = Sandbox::new();
    let before = sandbox.outside();
    proptest!(config(), |(bytes in entry_bytes())| {
        let store = sandbox.store();
        let file = store.dir.join(format!("entries/{KEY}.json"));
        std::fs::create_dir_all(file.parent().unwrap()).unwrap();
        std::fs::write(&file, &bytes).unwrap();
        let parsed = serde_json::from_slice::<Entry>(&bytes).ok();
        let entry = store.entry(KEY);
        prop_assert_eq!(&entry, &parsed);
        exercise(&store, entry, &sandbox.project().join("reports"));
        prop_assert_eq!(sandbox.outside(), before.clone());
        store.put_object(b"blob").unwrap();
    });
}

/// An entry pack holding the entry, and an object pack index of any bytes.
#[test]
fn entry_packs_and_pack_indexes_never_panic_or_reach_outside() {
    let sandbox = Sandbox::new();
    let before = sandbox.outside();
    proptest!(config(), |(bytes in entry_bytes(), idx in entry_bytes())| {
        let store = sandbox.store();
        let packs = store.dir.join("entries/packs");
        std::fs::create_dir_all(&packs).unwrap();
        let mut pack = format!("{{\"{KEY}\": ").into_bytes();
        pack.extend(&bytes);
        pack.push(b'}');
        std::fs::write(packs.join("p.json"), &pack).unwrap();
        let objects = store.dir.join("objects/packs");
        std::fs::create_dir_all(&objects).unwrap();
        // an index whose lines are the crafted bytes (hash-like text, offsets, junk)
        let mut lines = idx.clone();
        lines.extend(format!("\n{} 0 4\n", String::from_utf8_lossy(&idx)).bytes());
        std::fs::write(objects.join("q.idx"), &lines).unwrap();
        std::fs::write(objects.join("q.pack"), b"blob").unwrap();
        let entry = store.entry(KEY);
        exercise(&store, entry, &sandbox.project().join("reports"));
        prop_assert_eq!(sandbox.outside(), before.clone());
        let _ = std::fs::remove_dir_all(&packs);
        let _ = std::fs::remove_dir_all(&objects);
        store.put_object(b"blob").unwrap();
    });
}

/// A remote entry of any bytes, fetched (read-only and not) into the local store.
#[test]
fn remote_entries_never_panic_or_reach_outside() {
    let sandbox = Sandbox::new();
    let before = sandbox.outside();
    proptest!(config(), |(bytes in entry_bytes(), read_only in any::<bool>())| {
        std::fs::write(sandbox.remote().join(format!("entries/{KEY}.json")), &bytes).unwrap();
        let store = sandbox.store();
        let _ = std::fs::remove_dir_all(store.dir.join("entries"));
        let mode = Mode { read_only, required: false };
        let cache = RemoteCache::new(Box::new(FileRemote::new(&sandbox.remote())), mode)
            .with_warn(|_| {});
        let fetched = cache.fetch(&store, KEY, &|_| true);
        if let Some(e) = &fetched {
            let parsed = serde_json::from_slice::<Entry>(&bytes).ok();
            prop_assert_eq!(Some(e), parsed.as_ref());
        }
        exercise(&store, fetched, &sandbox.project().join("reports"));
        prop_assert_eq!(sandbox.outside(), before.clone());
        store.put_object(b"blob").unwrap();
    });
}
