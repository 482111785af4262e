//! The engine: config, DAG, content-addressed store, scheduler. It knows no physics.
//!
//! Files of this folder:
//!
//! - `atomic.rs`: Atomic file writes: a name no other writer uses, and write-then-rename
//! - `catalog.rs`: What the engine runs with
//! - `command.rs`: The `command` kind
//! - `context.rs`: What one evaluation works with
//! - `dag.rs`: The stage graph
//! - `error.rs`: The engine's error: a bad config (with its TOML line), IO, or a failed stage
//! - `evaluate.rs`: Walking the DAG
//! - `execute.rs`: Running one key of a stage
//! - `hash_on_read.rs`: The first run over a streamed input reads it once
//! - `hashing.rs`: sha256 hex digests
//! - `identity.rs`: The code identity compiled into this binary
//! - `inputs.rs`: path inputs: a file or a folder, read whole or left on disk
//! - `key.rs`: The cache key of a stage
//! - `lock_digests.rs`: `.groove/lock-digests.json`
//! - `lockfile.rs`: `pipeline.lock`
//! - `maintenance.rs`: `groove clean` and `groove gc`
//! - `materialize.rs`: Writing stored outputs to their paths in the project
//! - `memo.rs`: A stage's object memo
//! - `object_stamps.rs`: The stat of each loose store object at which its bytes last matched its name
//! - `pack.rs`: Packs: the many small blobs and entries of one stage run in a few files
//! - `pack_writer.rs`: Writing packs (`engine::pack`)
//! - `pipeline.rs`: The validated pipeline
//! - `progress.rs`: Progress on the console: a bar on a terminal, plain lines otherwise
//! - `project_lock.rs`: The project lock: one `groove run` (or `gc`, `clean`) at a time per project
//! - `provenance.rs`: The `engine:provenance` input
//! - `publish.rs`: `groove publish --to DIR`: the report bundle, only when every stage is fresh
//! - `reasons.rs`: Why a stage is stale
//! - `run.rs`: `groove run`: take the project lock
//! - `stage.rs`: The contract between the engine and a stage kind
//! - `status.rs`: `groove status`: every stage fresh or stale, with the reasons
//! - `store.rs`: The content-addressed store under `.groove/` beside `pipeline.toml`
//! - `store_upkeep.rs`: Keeping the store sound and small
//! - `config/`: Reading `pipeline.toml` in two layers
//! - `remote/`: A shared remote cache
//! - `slurm/`: The Slurm executor
//!
//! # Invariants
//!
//! Each is checked by the tests that name it (`tests/hostile_store.rs`, `tests/fuzz_store.rs`,
//! `tests/hostile_project.rs`, `tests/soak.sh`):
//!
//! - No store or remote entry can make groove write, read or delete outside the project and its
//!   store: hashes are 64 lowercase hex digits, item and output names plain file names.
//! - Anything else read from a store or a remote is damage: dropped, and the stage runs again;
//!   never a panic.
//! - An entry holds exactly the outputs its stage declares; a remote entry of another shape is
//!   never committed locally.
//! - `verify` and `gc` never follow a link out of the store.
//! - Groove never deletes a file it did not write: a folder output replaces only what groove
//!   wrote there, and anything else in the way stops the run (exit 2) naming it.
//! - Staged outputs a killed run left (`.NAME.groove-new-*`) are removed by the next run.
//! - `run`, `status`, `publish` and `pull` agree about state: a reused entry's objects are
//!   there and match their names (a loose one unchanged since it was last hashed, see
//!   `engine::object_stamps`), a missing or damaged one makes its stage run again, and `pull`
//!   replaces a damaged local object by the remote's sound one.
//! - A kill at any moment of any verb leaves the store and the reports either as they were or
//!   as they are meant to be; `clean` drops every entry by one rename before anything else.
//! - `publish` copies one snapshot (the lock and the objects it names) under the project lock.
//! - Read-only commands stay read-only: `status`, `publish` and `dag` work on a store that
//!   cannot be written.
//! - Bad input exits 2 naming its file, row, column or line and the fix, and loses nothing;
//!   `push` to or `pull` from a remote that is not there exits 2; a failing input that is a link
//!   out of the project is named, never quoted.
//! - Memory is bounded on hostile data: ingest checks a CSV header's width and the size of a
//!   file it reads whole before reading (`ingest::bounds`).
//!
//! Flow: [`config::load`] turns `pipeline.toml` into a validated [`pipeline::Pipeline`];
//! [`evaluate`] walks the DAG in waves, hashing inputs and looking stage keys up in the
//! [`store::Store`]; [`run`] executes what is missing, [`status`] explains what is stale.
//!
//! # `pipeline.toml` in full
//!
//! ```toml
//! [project]
//! seed = 20261122        # u64; each stage gets it mixed with its name (part of every key)
//! data = "data"          # the dataset folder; ${data} in paths; `--data DIR` replaces it
//! reports = "reports"    # the report folder; ${reports} in paths; `--out DIR` replaces it
//! params = { min_frames = 20, groove_angle_deg = 70.6 }
//!                        # inherited by every stage whose kind takes the param, unless the
//!                        # stage sets its own; one no kind takes is an error. The groove's
//!                        # opening angle (70.6°, the chapter's, when not set) and `k` reach
//!                        # fit, simulate, aggregate, discover, figures and report alike
//!
//! [stages.NAME]          # NAME: letters, digits, `_`, `-`
//! kind = "fit"           # a built-in kind (one file in src/stages/) or "command"
//! foreach = "runs"       # optional: per-item stage over the Collection input `runs`
//!                        # (or ["runs", "fits"]: step through several, item by item)
//! inputs = { runs = "ingest:runs" }              # bindings, see below
//! outputs = { fits_csv = "${reports}/fits.csv" } # optional: paths to materialize outputs to
//! params = { max_iter = 200 }                    # checked by the kind; defaults filled in
//! cmd = "python3 scripts/x.py {in.table} {out.plot}"  # kind = "command" only
//! ```
//!
//! Input bindings:
//!
//! | binding | meaning |
//! | --- | --- |
//! | `"<stage>:<output>"` | another stage's output (this is what makes the graph) |
//! | `"path"` or `"${data}/x.csv"` | a file (File artifact) or a folder: its top-level regular files, dotfiles and subfolders excluded (Collection artifact keyed by file name). So `data/truth/` is no input of a stage reading `${data}` |
//! | `{ path = "...", optional = true }` | as above; when absent the input is simply missing from the stage's inputs |
//! | `"engine:provenance"` | a JSON File from the engine: `groove_version`, `code_commit`, every kind's code `fingerprints`, `seed`, every data input upstream as `{path, sha256}`, every upstream stage's `{stage, kind, key}`; sorted, no times |
//!
//! Outputs: a built-in kind declares its outputs; `outputs` only gives paths to those that should
//! appear in the project (a Collection becomes a folder of its items). A `command` stage declares all
//! its outputs here. Paths are checked: two stages may not write one path (nor one inside another's
//! folder), and an input may not read a path some stage writes (bind `"<stage>:<output>"` instead).
//!
//! Per-item stages (`foreach = "runs"`): the stage runs once per item of that Collection, with one
//! key per item; every other input is passed whole. Each output is one File per item, gathered into a
//! Collection with the same item names. Editing one recording reruns that item and what reads the
//! gathered result, not the whole stage. `foreach = ["runs", "fits"]` steps through several
//! Collections with the same item names together: item `r` gets `runs[r]` and `fits[r]` only, so its
//! key depends on nothing of the other runs (a per-run stage after another per-run stage should use
//! this form, or every item reruns when any one run changes).
//!
//! The `command` kind runs `cmd` with `sh -c` in the project folder. Placeholders: `{in.NAME}` (a
//! copy of the input in a private folder: a file, or a folder for a Collection), `{out.NAME}` (where
//! the program writes that output: a file, or a folder that becomes a Collection), `{params.NAME}`,
//! `{item}` (per-item stages), `{seed}`; values are shell-quoted, an absent optional input is `''`; other braces (`${HOME}`, awk) are
//! left alone. The program's own script should be an input (`script = "scripts/x.py"`) so editing it
//! reruns the stage. A non-zero exit fails the stage (exit 2, with its last stderr lines); an output
//! the program did not write fails it too.
//!
//! Config errors name the line: `pipeline.toml:12: stage `fit`: unknown kind `fitt`; known kinds: …`.
//! Checked: TOML syntax and types, unknown keys, unknown kind, unknown or mistyped param (via the
//! kind's typed params), missing or unknown input names, inputs from unknown stages or outputs,
//! missing input paths, `foreach` naming no input, unknown placeholders, two stages one output, cycles
//! (`the stages form a cycle: a -> b -> a`).
//!
//! # How the engine decides what runs
//!
//! - A stage's key is the sha256 of a `#[derive(Serialize)]` struct (`engine::key::StageKey`): kind,
//!   canonical params, `cmd`, each input's content digest, output names, item, seed, groove version,
//!   and the kind's code fingerprint.
//! - A kind's code fingerprint is the sha256 of every source file its adapter `src/stages/<kind>.rs`
//!   uses, found by following its `crate::…` / `super::…` paths, `mod` declarations,
//!   `include_str!` files and the `impl` blocks beside the types it reaches
//!   (`src/build/code_deps.rs`, run by the build script). Editing a module
//!   reruns exactly the stages whose code reaches it; there is no hand-kept list to drift.
//! - Keys use the content of upstream outputs, so a rerun that reproduces byte-identical output
//!   leaves everything downstream fresh (early cutoff); a key seen before (a reverted param) is found
//!   in the store and restored without running (run-cache). Each stage binds only the inputs it
//!   reads, so it reruns only when those change.
//! - File hashes are cached in `.groove/hashes.json` under (path, size, mtime, inode, ctime): an
//!   unchanged file costs one `stat`, and `touch` reruns nothing. The change time (ctime) is
//!   there because a write moves it even when a tool sets the mtime back (`rsync --inplace
//!   --times`, `touch -r`), so such an edit is hashed, never missed; a `chmod` moves it too, which
//!   costs one rehash and reruns nothing. Store objects are not in it: an object is
//!   named by its sha256, and every read checks its bytes against that name.
//! - A store object is checked when a stage reads it; at lookup a loose one only has to be
//!   unchanged (its stat) since its bytes last matched its name (`.groove/objects.stamps`; read and
//!   hashed once when not), a packed one in a pack read (a no-op reads none). If one is
//!   missing or damaged, `groove run` drops it, checks every object the run names at lookup, and
//!   reruns what made it: only the items whose objects were bad; whatever the first pass committed is
//!   reused. `groove verify` checks them all at any time. With `--executor slurm` (steps read objects
//!   in other processes) every object is checked at lookup as before.
//! - Timings go to the console and to `.groove/run.log`, never into outputs or the lock.
//!   A long stage says what it is doing on the terminal's progress line (`StageInput::report`;
//!   discovery: `round 2: screening 9 candidates against 60 noise replicates`, then each
//!   candidate with the replicates done, `round 1: candidate 8/11 periodic in time: replicates
//!   20/60 done, not yet decided`, and each full fit); those words go nowhere else.
//! - A stage that makes many items can put each in the store as it makes it (`StageInput::put_item`,
//!   the engine's writer; the stage then returns `Artifact::InStore`, item → sha256) so that it
//!   never holds them all: `ingest` does, and a 10,000-run ingest peaks at 325 MB instead of 447 MB.
//! - **A stage's memo** (`StageInput::memo`, `engine::memo`): a whole (not per-item) stage may
//!   name a part of its input by a digest of everything an object is made of, and find the object
//!   an earlier run made of the same part. One file per stage in `.groove/memo/`, salted with the
//!   kind, its code fingerprint, the groove version, the params and the seed (any other salt, or a
//!   damaged file — it ends with a sha256 of itself — reads as empty); it is rewritten atomically
//!   when the stage ends well with exactly the keys this run found or made, so it follows the
//!   current input (≈ 64 bytes per object) and never grows with the history. A key found gives its
//!   object only while the store holds it; a stage that fails, or a stream that stops and reads its
//!   file whole, remembers nothing of that run. The memo never changes a result, only what is made
//!   again: `ingest` keys each whole run of trajectories.csv (`ingest/run_memo.rs`), and a
//!   10,000-run edit's ingest went 0.76–0.84 → 0.49–0.50 s on this host; `aggregate` keys each
//!   material's summary by its options, seed and fits (`fit::aggregate::SummaryMemo`; the summary
//!   kept as an object of its own JSON, which reads back to the same bytes), so after an edit of
//!   one recording only that run's material and the pooled summary are made again (aggregate
//!   0.58–0.79 → 0.42–0.47 s at 10,000 runs in two materials).
//! - **Packs.** The blobs a stage run puts go through one `PackWriter` (`engine::pack_writer`): once
//!   there are 64 new ones they are appended to one file in `tmp/`, which becomes
//!   `objects/packs/<id>.pack` with its index `<id>.idx` (`sha256 offset length` per blob, renamed
//!   into place after the pack) when the stage succeeds; fewer stay loose (`objects/ab/cdef…`). A
//!   per-item stage with 64 items or more runs them in chunks of 4,096: each chunk's blobs go into
//!   one pack and its entries into one entry pack `entries/packs/<id>.json` (key → entry). A
//!   10,000-run cold run then leaves 20 files in the store, not 30,000: the cold run spent 5–8 s of system time
//!   creating files (ext4 inode allocation, slower still right after a store was deleted), and
//!   now spends 0.4 s. Every read still checks a blob against its name; `groove verify` drops a pack
//!   holding a damaged blob whole (and the entries naming its blobs, whose stages then run again);
//!   `groove gc` removes a pack none of whose blobs is referenced, copies the referenced blobs out
//!   of one that is mostly unreferenced (more than half its bytes) before removing it, rewrites
//!   entry packs to the kept keys and removes what a kill left. A stage that fails leaves no blob behind (its pack was only
//!   a file in `tmp/`). The remote cache still holds one object per blob.
//! - A kind may read a path input from disk itself, in pieces (`StageKind::streamed_inputs`): the
//!   engine then gives it `Artifact::OnDisk`, each file with the sha256 its key was made from, and
//!   `InputFile` reads it whole or through a reader that hashes what it gives and fails at the end
//!   of the file if the content is not that one, so a file edited mid-run is an error, never a
//!   result under the wrong key. When the file-hash cache holds that sha256 under the file's stat
//!   (the engine just hashed it, or a no-op trusted it), the reader does not hash again: the file
//!   must have that stat (size, mtime, inode, ctime) when opened, and the same stat at the end —
//!   the trust the no-op already places in the stat, and an edit's ingest no longer hashes 264 MB
//!   on a core the parser needs. `ingest` takes its dataset so and parses trajectories.csv 8 MB at a
//!   time: the engine never holds the file, and the 100,000-run campaign (2.7 GB of CSV) runs
//!   through ingest, fits and aggregate within 1 GB (`tests/ingest_campaign.rs`, ignored). A
//!   dataset the stream cannot take (a run's rows not together, another format, a problem to name)
//!   is still read whole by the stage, so its memory grows with the file. File hashes are read a
//!   megabyte at a time.
//! - The first run of a stage over a streamed input reads the input once, not twice
//!   (`engine/hash_on_read.rs`): when `pipeline.lock` has no record of the stage and a file of the
//!   input is new to the file-hash cache, the stage runs before its key is known, `InputFile`
//!   records the digest of what it read, and the key is made from those digests afterwards — the
//!   key hashing first would give (`tests/e2e.rs`). A file must still have the stat it had before
//!   the run, and every read of it one digest, else the run fails ("changed while groove was
//!   running"); a file the stage did not read to its end is hashed after the run. A stage that ran
//!   before may find its result in the store (a copied project, a touched file, an edit undone), so
//!   its inputs are hashed first as always, and a touch still reruns nothing; with a remote cache or
//!   the Slurm executor every input is hashed first, since the key decides what to fetch. 10,000
//!   runs cold: 2.75–3.00 → 2.56–2.63 s (the 264 MB file hashed once, not twice).
//!
//! # The invariants, in full
//!
//! - **The engine knows no analysis.** No module under `src/engine` names a module outside it (a
//!   test checks this); it moves bytes between pure stage functions. The physics knows no files.
//! - **Stages are pure.** A built-in kind gets params, input bytes, item and seed and returns bytes
//!   (or hands them to the engine's `put_item` as it makes them); only the engine touches the file
//!   system.
//! - **Deterministic.** Seeds come from `pipeline.toml`; no wall clock and no hash-map order reach
//!   any output, the lock or the report, so the same inputs give a byte-identical report. The only
//!   date a report shows is `source_date_epoch` from its params.
//! - **The truth is read only by `validate`.** No analysis stage has `data/truth/` as an input
//!   (`groove dag` shows it); the report shows the truth only through `validate`'s output.
//! - **Crash-safe.** A store entry exists only if the stage succeeded and every declared output was
//!   stored (blobs first, then the entry by one rename; a pack's blobs, then its index, then the
//!   entry pack naming them). A `kill -9` at any moment leaves no partial
//!   entry, no half-written output and no lock to remove; a failed stage leaves the project's last
//!   good outputs in place. `.groove/lock-digests.json` is written after `pipeline.lock` and names
//!   the lock's stamp: a kill between the two leaves digests of another stamp, which are not used.
//! - **A key names the content read.** A path input is hashed before its stage runs, or, the
//!   first run of a stage over a streamed one, by the stage's own read (`hash_on_read.rs`); either
//!   way a file that changes while groove runs fails the run, never leaves a result under a key of
//!   other bytes.
//! - **A memo never changes a result.** A stage's memo (`engine::memo`) only spares work: its
//!   keys are digests of everything an object is made of, salted with the kind's code, version,
//!   params and seed; an object is taken only while the store holds it; a stage that fails, or an
//!   ingest stream that stops and reads its file whole, remembers nothing of that run; the file is
//!   rewritten by rename. Tests check that the items and the summary with a memo are the bytes
//!   made without one, before and after an edit.
//! - **Safe Rust but one call.** `unsafe_code` is denied crate-wide; the one exception is
//!   `src/lsq/wide.rs`, which calls the AVX2 compilation of the normal equations after
//!   `is_x86_feature_detected!` says the CPU has AVX2 (a test checks it gives the baseline's bits).
//! - **One writer.** One `run`, `gc` or `clean` at a time per project (an OS lock on
//!   `.groove/lock`); `status` and `publish` take no lock and never write the store.
//! - **Honest report.** A fit that does not converge is a result, shown with its status; skipped
//!   stages and dropped runs are said in words. `report.html` is self-contained (inline CSS and SVG,
//!   no script, no URL). Bad input and IO are errors: exit code 2, a message naming file, row and
//!   column and the fix, nothing lost.
//!
//! # Errors and what they mean
//!
//! Bad input and a hostile world end with exit code 2 and one message naming the place (file, row
//! and column for data; line for `pipeline.toml`) and the fix, before anything in the project
//! changes: a run's outputs and `pipeline.lock` are written only after every stage succeeded (all
//! outputs staged beside their paths first, then swapped in), so a failed run leaves the last good
//! report whole. Data limits (`src/ingest/sanity.rs`, `src/recording.rs`) are far outside what a real
//! recording holds: fps 50 … 1e8, diameter 1 µm … 10 cm, |z_m| ≤ 10 m, |t_s| ≤ 60 s, and t_s within
//! half a frame plus 1 % of the elapsed time of (frame − first frame)/fps.
//!
//! | message (abridged) | what it means, what to do |
//! | --- | --- |
//! | `runs.csv row 3, column fps: 20 frames per second is below 50 …` | the frame rate is in kHz or wrong; write frames per second (20 kHz → 20000) |
//! | `… column diameter_m: a diameter of 0.3 m is above 0.1 m` | the diameter is in mm or µm; write metres (3e-4) |
//! | `trajectories.csv row 101, column z_m: 1e308 m is farther than 10 m …` | positions in pixels or µm, or a broken export; write metres or delete the row |
//! | `… column t_s: 1e20 s is more than 60 s from the run's first frame` | times not in seconds, or a broken export |
//! | `… column t_s: time goes backwards: t_s = … at frame … is not after …` | t_s must grow with the frame number within a track |
//! | `… column t_s: t_s = … at frame … is … s after frame 0, but … frames at … fps take … s` | t_s disagrees with frame/fps (all zeros, ms instead of s, wrong fps) |
//! | `… run "c1" has 0 frames of particle 1 (the target) …` | a collision run needs both particles (0 striker, 1 target) |
//! | `trajectories.parquet, column t_s: holds numbers stored as text` | store numeric Parquet columns as float64/int64 |
//! | `… row 1, column …: the header row is not UTF-8 text (byte 0xe9)` / `… is not UTF-8 text` | save the CSV as UTF-8 |
//! | `… row 50, field 6: the row has 6 fields but the header names 5 columns` | an extra comma; quote fields holding commas |
//! | `cannot be read as CSV (…)` / `cannot be read as Parquet: it is damaged or not Parquet (…)` | the file is not a table groove can read; the parenthesis says why in groove's words, never the parser's |
//! | `note: data/notes (copy).txt is not read (file names …)` | not an error: files in an input folder whose names hold other characters than letters, digits, `.`, `_`, `-` are skipped and named; symlinked files are followed |
//! | `pipeline.toml:1: defines no stages (is the file empty?)` | an empty config never rewrites `pipeline.lock` |
//! | `pipeline.toml:7: is not UTF-8 text (byte 0xff)` | save the config as UTF-8 |
//! | `pipeline.toml:N: stage `s` output `o` would write …, outside the project folder …` | outputs stay inside the project or the reports folder, never on the config, the lock, the store, the dataset or an input (so `--out data` is refused) |
//! | `… is a folder; a file output never replaces a folder` | move the folder or choose another output path |
//! | `… is a symbolic link; groove does not write through links inside the project` | replace the link with a folder |
//! | `the store's object … is damaged` / `… is missing` | `groove run` repairs it by itself (it checks every object and reruns what made the bad one); from other commands, run `groove verify`, then `groove run` |
//! | `publish: … is a file, not a folder` | `--to` takes a new, empty or earlier-bundle folder; leftovers of a killed publish (`.DIR.groove-new-*`) are removed by the next one |
//! | `pipeline.lock is missing, unreadable or names no stage, so gc cannot tell what to keep` | run `groove run` first; nothing was removed |

pub mod atomic;
pub mod catalog;
pub mod command;
pub mod config;
pub mod context;
pub mod dag;
pub mod error;
pub mod evaluate;
pub mod execute;
pub mod hash_on_read;
pub mod hashing;
pub mod identity;
pub mod inputs;
pub mod key;
pub mod lock_digests;
pub mod lockfile;
pub mod maintenance;
pub mod materialize;
pub mod memo;
pub mod object_stamps;
pub mod pack;
pub mod pack_writer;
pub mod pipeline;
pub mod progress;
pub mod project_lock;
pub mod provenance;
pub mod publish;
pub mod reasons;
pub mod remote;
pub mod run;
pub mod slurm;
pub mod stage;
pub mod status;
pub mod store;
pub mod store_upkeep;

pub use catalog::Catalog;
pub use error::EngineError;
pub use pipeline::Pipeline;
