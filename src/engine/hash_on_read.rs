//! The first run over a streamed input reads it once: the stage hashes the files as it reads
//! them, and the key is made afterwards from those digests, where the engine would otherwise
//! hash a dataset it has never seen before the stage reads (and hashes) it again.
//!
//! Only for a path input the kind streams (`StageKind::streamed_inputs`) of a whole-stage key
//! that `pipeline.lock` has no record of (the stage never ran in this project), run in this
//! process with no remote cache, and only when a file of it is new to the hash cache. A stage
//! that ran before may find its result in the store (a copied project, a touched file, an edit
//! undone), so its inputs are hashed first as always, and a touch still reruns nothing.
//!
//! A file read and hashed by the stage must have the stat it had before the stage ran, and every
//! read of it the same digest; a file the stage did not read to its end is hashed after the run
//! under the same stat check. Either way the key names the content read.

use super::context::Context;
use super::error::{EngineError, IoContext};
use super::execute::{load_shared, run_key, store_outputs, Bound, Source};
use super::hashing::{hash_reader, stat_of, FileStamp};
use super::inputs::{dir_files, file_name};
use super::pack_writer::PackWriter;
use super::pipeline::StageSpec;
use super::stage::{Artifact, InputFile, Seen};
use super::store::Stored;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Whether `spec`'s streamed inputs may be hashed by its run (see the module doc), when it is
/// to be run (not only checked).
pub fn allowed(ctx: &Context, spec: &StageSpec) -> bool {
    let local = spec.foreach.is_none()
        && ctx.remote.is_none()
        && ctx.pusher.is_none()
        && ctx.steps.is_none()
        && ctx
            .catalog
            .kind(&spec.kind)
            .is_some_and(|k| !k.streamed_inputs().is_empty());
    // (the lock is read only when its digests are not at hand)
    local
        && !match &ctx.lock_digests {
            Some(digests) => digests.contains_key(&spec.name),
            None => ctx.lock().stages.contains_key(&spec.name),
        }
}

/// Whether the kind of `spec` reads input `name` itself.
pub fn streamed(ctx: &Context, spec: &StageSpec, name: &str) -> bool {
    ctx.catalog
        .kind(&spec.kind)
        .is_some_and(|k| k.streamed_inputs().contains(&name))
}

/// A path input with a file the hash cache has never seen: its files, hashed as the stage reads
/// them (or, when the cache holds their current stat, known).
pub struct Unhashed {
    name: String,
    path: PathBuf,
    is_dir: bool,
    files: Vec<File>,
}

struct File {
    name: String,
    path: PathBuf,
    stat: FileStamp,
    known: Option<String>,
    seen: Seen,
}

/// Input `name` at `path`, if a file of it is new to the hash cache (`None`: hash it as usual).
pub fn unhashed(ctx: &Context, name: &str, path: &Path) -> Result<Option<Unhashed>, EngineError> {
    let is_dir = path.is_dir();
    let listed = match is_dir {
        true => dir_files(path)?,
        false => vec![(file_name(path), path.to_path_buf())],
    };
    if listed.iter().all(|(_, p)| ctx.hashes.knows(p)) {
        return Ok(None);
    }
    let files = listed
        .into_iter()
        .map(|(name, path)| {
            let stat = stat_of(&path)?;
            let known = ctx.hashes.cached(&path, stat);
            Ok(File {
                name,
                path,
                stat,
                known,
                seen: Seen::default(),
            })
        })
        .collect::<Result<_, EngineError>>()?;
    Ok(Some(Unhashed {
        name: name.to_string(),
        path: path.to_path_buf(),
        is_dir,
        files,
    }))
}

impl Unhashed {
    /// The input as the stage gets it: files left on disk, each vouched for by the stat the hash
    /// cache knows it under, or recorded as read.
    fn artifact(&self) -> Artifact {
        Artifact::OnDisk(
            self.files
                .iter()
                .map(|f| {
                    let file = match &f.known {
                        Some(_) => InputFile::vouched(f.path.clone(), f.stat),
                        None => InputFile::recorded(f.path.clone(), f.seen.clone()),
                    };
                    (f.name.clone(), file)
                })
                .collect(),
        )
    }

    /// The input bound by the digests of what the stage read (files it did not read to the
    /// end hashed now), each remembered in the hash cache under the stat it had before the run.
    fn bind(self, ctx: &Context) -> Result<Bound, EngineError> {
        let mut items = BTreeMap::new();
        for f in self.files {
            let sha256 = match f.known {
                Some(sha256) => sha256,
                None => digest_of(&f)?,
            };
            ctx.hashes.remember(&f.path, f.stat, sha256.clone());
            items.insert(f.name, sha256);
        }
        let stored = match self.is_dir {
            true => Stored::Collection { items },
            false => Stored::File {
                sha256: items.into_values().next().unwrap_or_default(),
            },
        };
        Ok(Bound {
            stored,
            source: Source::Path(self.path),
        })
    }
}

/// The sha256 of a file not hashed before the run: the digest its reads recorded, or its hash
/// now; the file must still have the stat it had before the run, and its reads one digest.
fn digest_of(f: &File) -> Result<String, EngineError> {
    let changed = || {
        EngineError::Usage(format!(
            "{} changed while groove was running; run again",
            f.path.display()
        ))
    };
    let seen = f.seen.digests();
    let sha256 = match seen.first() {
        Some(first) if seen.iter().any(|d| d != first) => return Err(changed()),
        Some(first) => first.clone(),
        None => hash_reader(std::fs::File::open(&f.path).at(&f.path)?).at(&f.path)?,
    };
    if stat_of(&f.path)? != f.stat {
        return Err(changed());
    }
    Ok(sha256)
}

/// Run the stage with its `unhashed` inputs hashed as it reads them, store its outputs, and bind
/// those inputs into `bound`; the caller makes the key from `bound` and commits the outputs
/// returned under it.
pub fn run_first(
    ctx: &Context,
    spec: &StageSpec,
    bound: &mut BTreeMap<String, Bound>,
    unhashed: Vec<Unhashed>,
    seed: u64,
) -> Result<BTreeMap<String, Stored>, EngineError> {
    ctx.progress.started(&spec.name, 1);
    let mut shared = load_shared(ctx, spec, bound)?;
    for u in &unhashed {
        shared.insert(u.name.clone(), u.artifact());
    }
    let writer = PackWriter::new(&ctx.store);
    let outputs = run_key(ctx, spec, bound, &shared, None, seed, &writer)?;
    let stored = store_outputs(&writer, &outputs)?;
    writer.finish()?;
    for u in unhashed {
        let name = u.name.clone();
        bound.insert(name, u.bind(ctx)?);
    }
    Ok(stored)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(path: &Path) -> File {
        File {
            name: "a.csv".into(),
            path: path.to_path_buf(),
            stat: stat_of(path).unwrap(),
            known: None,
            seen: Seen::default(),
        }
    }

    #[test]
    fn a_file_is_bound_by_what_was_read_and_a_change_during_the_run_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.csv");
        std::fs::write(&path, "t,z\n0,1\n").unwrap();
        let sha256 = super::super::hashing::sha256_hex(b"t,z\n0,1\n");
        // read to the end by the stage: its recorded digest
        let f = file(&path);
        let read = InputFile::recorded(path.clone(), f.seen.clone());
        assert_eq!(read.read().unwrap(), b"t,z\n0,1\n");
        assert_eq!(digest_of(&f).unwrap(), sha256);
        // not read: hashed after the run
        assert_eq!(digest_of(&file(&path)).unwrap(), sha256);
        // two reads that saw different content
        let f = file(&path);
        let read = InputFile::recorded(path.clone(), f.seen.clone());
        read.read().unwrap();
        std::fs::write(&path, "t,z\n0,2\n").unwrap();
        read.read().unwrap();
        let err = digest_of(&f).unwrap_err().to_string();
        assert!(err.contains("changed while groove was running"), "{err}");
        // read once, then changed (another size) before the key was made
        let f = file(&path);
        InputFile::recorded(path.clone(), f.seen.clone())
            .read()
            .unwrap();
        std::fs::write(&path, "t,z\n0,22\n").unwrap();
        let err = digest_of(&f).unwrap_err().to_string();
        assert!(err.contains("changed while groove was running"), "{err}");
        assert!(err.contains("a.csv"), "{err}");
    }
}
