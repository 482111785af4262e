//! Writing packs (`engine::pack`): the blobs of one stage run, packed once there are enough.

use super::atomic::{unique_name, write_atomic};
use super::error::{EngineError, IoContext};
use super::hashing::sha256_hex;
use super::pack::{object_packs, read_idx, PACK_MIN};
use super::store::Store;
use std::collections::HashSet;
use std::io::Write;
use std::path::PathBuf;
use std::sync::Mutex;

/// Blobs put during a stage run, packed once there are `PACK_MIN` new ones (fewer are written
/// loose at `finish`). Blobs the store already holds are not written again. Dropped without
/// `finish` (the stage failed), it leaves nothing: its pack was only ever a file in `tmp/`.
pub struct PackWriter<'a> {
    store: &'a Store,
    state: Mutex<Writing>,
    /// Write every blob, even one a pack already holds (`rewrite` copies blobs out of a pack).
    fresh: bool,
}

#[derive(Default)]
struct Writing {
    /// The first new blobs, held until there are enough for a pack.
    held: Vec<(String, Vec<u8>)>,
    /// The pack being written (in `tmp/`) once there are.
    file: Option<(std::io::BufWriter<std::fs::File>, PathBuf)>,
    offset: u64,
    index: Vec<(String, u64, u64)>,
    seen: HashSet<String>,
}

impl<'a> PackWriter<'a> {
    pub fn new(store: &'a Store) -> Self {
        PackWriter {
            store,
            state: Mutex::new(Writing::default()),
            fresh: false,
        }
    }

    /// Put a blob; returns its hash. Callable from many threads.
    pub fn add(&self, bytes: &[u8]) -> Result<String, EngineError> {
        let h = sha256_hex(bytes);
        if !self.fresh && self.store.holds_sound(&h, bytes) {
            return Ok(h);
        }
        let mut st = self.state.lock().expect("pack writer lock");
        if !st.seen.insert(h.clone()) {
            return Ok(h);
        }
        if st.file.is_none() {
            st.held.push((h.clone(), bytes.to_vec()));
            if st.held.len() < PACK_MIN {
                return Ok(h);
            }
            let tmp = self.store.tmp_root();
            std::fs::create_dir_all(&tmp).at(&tmp)?;
            let path = tmp.join(unique_name("pack"));
            let f = std::fs::File::create(&path).at(&path)?;
            st.file = Some((std::io::BufWriter::with_capacity(1 << 20, f), path));
            for (h, b) in std::mem::take(&mut st.held) {
                append(&mut st, h, &b)?;
            }
            return Ok(h);
        }
        append(&mut st, h.clone(), bytes)?;
        Ok(h)
    }

    /// Make every blob put so far readable: the pack and its idx renamed into place (or the few
    /// held blobs written loose).
    pub fn finish(self) -> Result<(), EngineError> {
        let mut st = std::mem::take(&mut *self.state.lock().expect("pack writer lock"));
        let Some((file, tmp)) = st.file.take() else {
            for (_, bytes) in &st.held {
                self.store.put_object(bytes)?;
            }
            return Ok(());
        };
        let done = (|| {
            file.into_inner().map_err(|e| e.into_error()).at(&tmp)?;
            st.index.sort();
            let mut idx = String::with_capacity(st.index.len() * 90);
            for (h, off, len) in &st.index {
                idx.push_str(&format!("{h} {off} {len}\n"));
            }
            let dir = object_packs(&self.store.dir);
            std::fs::create_dir_all(&dir).at(&dir)?;
            let id = sha256_hex(idx.as_bytes());
            let (pack_path, idx_path) = (
                dir.join(format!("{id}.pack")),
                dir.join(format!("{id}.idx")),
            );
            std::fs::rename(&tmp, &pack_path).at(&pack_path)?;
            write_atomic(&idx_path, idx.as_bytes())?;
            let blobs = read_idx(&idx_path).ok_or_else(|| {
                EngineError::io(
                    &idx_path,
                    std::io::Error::other("the pack just written could not be read back"),
                )
            })?;
            self.store.packs_written(idx_path, blobs);
            Ok(())
        })();
        if done.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        done
    }
}

impl Drop for PackWriter<'_> {
    fn drop(&mut self) {
        if let Ok(st) = self.state.get_mut() {
            if let Some((_, tmp)) = &st.file {
                let _ = std::fs::remove_file(tmp);
            }
        }
    }
}

fn append(st: &mut Writing, h: String, bytes: &[u8]) -> Result<(), EngineError> {
    let (f, path) = st.file.as_mut().expect("a pack is open");
    f.write_all(bytes).at(path)?;
    let len = bytes.len() as u64;
    st.index.push((h, st.offset, len));
    st.offset += len;
    Ok(())
}

/// Copy the still referenced blobs of mostly unreferenced packs (`Store::gc`) into a new pack
/// (or loose, if few), then remove the old packs: a blob is in place again before its old copy
/// goes. Returns how many blobs were copied.
pub fn rewrite(store: &Store, sparse: &[(PathBuf, Vec<String>)]) -> Result<usize, EngineError> {
    if sparse.is_empty() {
        return Ok(0);
    }
    let mut writer = PackWriter::new(store);
    writer.fresh = true;
    let mut copied = 0;
    for (_, held) in sparse {
        for h in held {
            writer.add(&store.read_object(h)?)?;
            copied += 1;
        }
    }
    writer.finish()?;
    for (idx, _) in sparse {
        super::pack::remove_pack(idx)?;
    }
    store.forget_packs();
    Ok(copied)
}
