//! The stat of each loose store object at which its bytes last matched its name
//! (`.groove/objects.stamps`), so that `run` takes an object as sound at lookup only when it is
//! unchanged since it was last hashed: one `stat` each, and a read only for an object not seen
//! at this stat (the first run after a store was copied, or an object changed on disk).
//!
//! One line per object: `sha256 size mtime_ns inode ctime_ns`. Best-effort both ways: an
//! unreadable file or line is forgotten (its objects are hashed again), one that cannot be
//! written (a full or read-only disk) costs the next run the hashing, never a result.

use super::hashing::sha256_hex;
use super::stage::FileStamp;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

pub struct ObjectStamps {
    path: PathBuf,
    stamps: Mutex<(HashMap<String, FileStamp>, bool)>,
}

/// The file's name in the store folder.
pub const FILE: &str = "objects.stamps";

impl ObjectStamps {
    /// The stamps of the store in `store_dir` (none if the file is missing or unreadable).
    pub fn load(store_dir: &Path) -> ObjectStamps {
        let path = store_dir.join(FILE);
        let text = std::fs::read_to_string(&path).unwrap_or_default();
        let stamps = text.lines().filter_map(parse).collect();
        ObjectStamps {
            path,
            stamps: Mutex::new((stamps, false)),
        }
    }

    /// Whether the loose object at `path` holds the bytes named `sha256`: its stamp is the one
    /// recorded, or its bytes are read and hash to the name (then the stamp is recorded).
    pub fn sound(&self, sha256: &str, path: &Path) -> bool {
        let Ok(meta) = std::fs::metadata(path) else {
            return false;
        };
        let stat = FileStamp::of(&meta);
        let known = |s: &Self| s.stamps.lock().expect("stamps lock").0.get(sha256) == Some(&stat);
        if known(self) {
            return true;
        }
        let sound = std::fs::read(path).is_ok_and(|b| sha256_hex(&b) == sha256);
        if sound {
            let mut guard = self.stamps.lock().expect("stamps lock");
            guard.0.insert(sha256.to_string(), stat);
            guard.1 = true;
        }
        sound
    }

    /// Write the stamps when some were added (best-effort, see the module docs).
    pub fn save(&self) {
        let guard = self.stamps.lock().expect("stamps lock");
        if !guard.1 {
            return;
        }
        let mut lines: Vec<String> = guard
            .0
            .iter()
            .map(|(h, s)| format!("{h} {} {} {} {}\n", s.size, s.mtime_ns, s.inode, s.ctime_ns))
            .collect();
        lines.sort();
        let _ = super::atomic::write_atomic(&self.path, lines.concat().as_bytes());
    }
}

/// One line of the file, or `None` for a line that is not one.
fn parse(line: &str) -> Option<(String, FileStamp)> {
    let mut f = line.split(' ');
    let sha256 = f
        .next()
        .filter(|h| super::hashing::is_sha256(h))?
        .to_string();
    let stamp = FileStamp {
        size: f.next()?.parse().ok()?,
        mtime_ns: f.next()?.parse().ok()?,
        inode: f.next()?.parse().ok()?,
        ctime_ns: f.next()?.parse().ok()?,
    };
    f.next().is_none().then_some((sha256, stamp))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_object_changed_after_it_was_stamped_is_not_sound() {
        let dir = tempfile::tempdir().unwrap();
        let bytes = b"an object";
        let sha = sha256_hex(bytes);
        let object = dir.path().join("obj");
        std::fs::write(&object, bytes).unwrap();
        let stamps = ObjectStamps::load(dir.path());
        assert!(stamps.sound(&sha, &object));
        stamps.save();
        // read back, the stamp vouches for the object without a read
        let again = ObjectStamps::load(dir.path());
        assert_eq!(again.stamps.lock().unwrap().0.len(), 1);
        assert!(again.sound(&sha, &object));
        // the same size, other bytes: the stat changed, the bytes are read and refused
        std::thread::sleep(std::time::Duration::from_millis(5));
        std::fs::write(&object, b"an abject").unwrap();
        assert!(!again.sound(&sha, &object));
        assert!(!again.sound(&sha, &dir.path().join("missing")));
        // a damaged line is forgotten, not an error
        std::fs::write(dir.path().join(FILE), "zz 1 2 3\n").unwrap();
        assert!(ObjectStamps::load(dir.path())
            .stamps
            .lock()
            .unwrap()
            .0
            .is_empty());
    }
}
