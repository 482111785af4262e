//! The pusher: uploads committed entries with bounded concurrency, blobs first, entry last.
//!
//! Per key: one HEAD of the remote entry (present → nothing to do, so a re-push uploads no
//! body); otherwise one task per blob (HEAD, then a create-if-absent PUT of the body only if
//! absent), and when every blob task of the key succeeded, a create-if-absent PUT of the entry.
//! A kill at any moment therefore leaves at most blobs without an entry, never an entry
//! without its blobs. A fixed number of worker threads take tasks from one queue.

use super::backend::{blob_name, entry_name};
use super::cache::RemoteCache;
use crate::engine::store::{Entry, Store, Stored};
use std::collections::{BTreeSet, VecDeque};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex};

struct KeyJob {
    key: String,
    entry: Entry,
    blobs_left: AtomicUsize,
    failed: AtomicBool,
}

enum Task {
    /// HEAD the entry; if absent, queue the blobs.
    Check(Arc<KeyJob>),
    Blob(Arc<KeyJob>, String),
    Entry(Arc<KeyJob>),
}

struct Queue {
    tasks: VecDeque<Task>,
    /// Tasks taken but not finished.
    busy: usize,
    closed: bool,
}

struct Shared {
    cache: Arc<RemoteCache>,
    store: Store,
    queue: Mutex<Queue>,
    ready: Condvar,
    idle: Condvar,
    /// Blobs known to be on the remote (pushed or seen) this run: no second HEAD.
    present: Mutex<BTreeSet<String>>,
}

pub struct Pusher {
    shared: Arc<Shared>,
    workers: Vec<std::thread::JoinHandle<()>>,
}

impl Pusher {
    /// Start `concurrency` worker threads pushing from `store` to `cache`'s remote.
    pub fn start(cache: Arc<RemoteCache>, store: &Store, concurrency: usize) -> Pusher {
        let shared = Arc::new(Shared {
            cache,
            store: Store::in_dir(store.dir.clone()),
            queue: Mutex::new(Queue {
                tasks: VecDeque::new(),
                busy: 0,
                closed: false,
            }),
            ready: Condvar::new(),
            idle: Condvar::new(),
            present: Mutex::new(BTreeSet::new()),
        });
        let workers = (0..concurrency.max(1))
            .map(|_| {
                let s = Arc::clone(&shared);
                std::thread::spawn(move || work(&s))
            })
            .collect();
        Pusher { shared, workers }
    }

    /// Queue a committed entry for upload (returns at once).
    pub fn submit(&self, key: &str, entry: &Entry) {
        if self.shared.cache.is_disabled() || self.shared.cache.mode.read_only {
            return;
        }
        let job = Arc::new(KeyJob {
            key: key.to_string(),
            entry: entry.clone(),
            blobs_left: AtomicUsize::new(0),
            failed: AtomicBool::new(false),
        });
        push_task(&self.shared, Task::Check(job));
    }

    /// Wait until every queued upload is done.
    pub fn wait(&self) {
        let mut q = self.shared.queue.lock().expect("push queue");
        while !q.tasks.is_empty() || q.busy > 0 {
            q = self.shared.idle.wait(q).expect("push queue");
        }
    }

    /// Wait for the queue, then stop the workers.
    pub fn finish(mut self) {
        self.wait();
        self.shared.queue.lock().expect("push queue").closed = true;
        self.shared.ready.notify_all();
        for w in self.workers.drain(..) {
            let _ = w.join();
        }
    }
}

fn push_task(shared: &Shared, task: Task) {
    shared
        .queue
        .lock()
        .expect("push queue")
        .tasks
        .push_back(task);
    shared.ready.notify_one();
}

fn work(shared: &Shared) {
    loop {
        let task = {
            let mut q = shared.queue.lock().expect("push queue");
            loop {
                if let Some(t) = q.tasks.pop_front() {
                    q.busy += 1;
                    break t;
                }
                if q.closed {
                    return;
                }
                q = shared.ready.wait(q).expect("push queue");
            }
        };
        run_task(shared, task);
        let mut q = shared.queue.lock().expect("push queue");
        q.busy -= 1;
        if q.tasks.is_empty() && q.busy == 0 {
            shared.idle.notify_all();
        }
    }
}

fn blobs_of(entry: &Entry) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for stored in entry.outputs.values() {
        match stored {
            Stored::File { sha256 } => {
                out.insert(sha256.clone());
            }
            Stored::Collection { items } => out.extend(items.values().cloned()),
        }
    }
    out
}

fn run_task(shared: &Shared, task: Task) {
    let cache = &shared.cache;
    if cache.is_disabled() {
        return;
    }
    match task {
        Task::Check(job) => {
            let blobs = blobs_of(&job.entry);
            let repair: Vec<String> = {
                let r = cache.repair.lock().expect("repair lock");
                blobs.iter().filter(|b| r.contains(*b)).cloned().collect()
            };
            if repair.is_empty() {
                match cache.backend.exists(&entry_name(&job.key)) {
                    Ok(true) => return,
                    Ok(false) => {}
                    Err(e) => return cache.failed(&e),
                }
            }
            if blobs.is_empty() {
                return push_task(shared, Task::Entry(job));
            }
            job.blobs_left.store(blobs.len(), Ordering::SeqCst);
            for b in blobs {
                push_task(shared, Task::Blob(Arc::clone(&job), b));
            }
        }
        Task::Blob(job, sha) => {
            let ok = push_blob(shared, &sha);
            if !ok {
                job.failed.store(true, Ordering::SeqCst);
            }
            if job.blobs_left.fetch_sub(1, Ordering::SeqCst) == 1
                && !job.failed.load(Ordering::SeqCst)
            {
                push_task(shared, Task::Entry(job));
            }
        }
        Task::Entry(job) => {
            let bytes = serde_json::to_vec_pretty(&job.entry).expect("an entry serializes");
            match cache.backend.put_if_absent(&entry_name(&job.key), &bytes) {
                Ok(true) => {
                    cache.pushed.fetch_add(1, Ordering::Relaxed);
                }
                Ok(false) => {}
                Err(e) => cache.failed(&e),
            }
        }
    }
}

/// Make sure one blob is on the remote. False when it could not be.
fn push_blob(shared: &Shared, sha: &str) -> bool {
    let cache = &shared.cache;
    let repair = cache.repair.lock().expect("repair lock").contains(sha);
    if !repair && shared.present.lock().expect("present set").contains(sha) {
        return true;
    }
    let name = blob_name(sha);
    if !repair {
        match cache.backend.exists(&name) {
            Ok(true) => {
                shared
                    .present
                    .lock()
                    .expect("present set")
                    .insert(sha.to_string());
                return true;
            }
            Ok(false) => {}
            Err(e) => {
                cache.failed(&e);
                return false;
            }
        }
    }
    let bytes = match shared.store.read_object(sha) {
        Ok(b) => b,
        Err(e) => {
            cache.failed(&super::backend::RemoteError::Other(e.to_string()));
            return false;
        }
    };
    let put = if repair {
        cache.backend.put_overwrite(&name, &bytes).map(|()| true)
    } else {
        cache.backend.put_if_absent(&name, &bytes)
    };
    match put {
        Ok(created) => {
            if created {
                cache.blobs_uploaded.fetch_add(1, Ordering::Relaxed);
            }
            if repair {
                cache.repair.lock().expect("repair lock").remove(sha);
            }
            shared
                .present
                .lock()
                .expect("present set")
                .insert(sha.to_string());
            true
        }
        Err(e) => {
            cache.failed(&e);
            false
        }
    }
}
