//! Progress on the console: a bar on a terminal, plain lines otherwise. Timings go here and to
//! the run log, never into outputs or `pipeline.lock`.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::Instant;

pub struct Progress {
    bar: Option<ProgressBar>,
    quiet: bool,
    pub start: Instant,
    log: Mutex<Vec<String>>,
}

impl Progress {
    /// `total` stages; `quiet` prints nothing (used by status and tests of the library).
    pub fn new(total: u64, quiet: bool) -> Progress {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = ProgressBar::new(total);
            bar.set_style(
                ProgressStyle::with_template(
                    "{spinner} [{elapsed_precise}] {pos}/{len} stages {wide_msg}",
                )
                .expect("a valid progress template"),
            );
            bar.enable_steady_tick(std::time::Duration::from_millis(120));
            bar
        });
        Progress {
            bar,
            quiet,
            start: Instant::now(),
            log: Mutex::new(Vec::new()),
        }
    }

    /// A stage started work on `items` items.
    pub fn started(&self, stage: &str, items: usize) {
        let msg = if items > 1 {
            format!("{stage}: {items} items")
        } else {
            stage.to_string()
        };
        if let Some(bar) = &self.bar {
            bar.set_message(msg);
        } else if !self.quiet {
            eprintln!("groove: running {msg}");
        }
    }

    /// One item of a per-item stage is done: the bar shows `stage: done/total items`.
    pub fn item_done(&self, stage: &str, done: usize, total: usize) {
        if let Some(bar) = &self.bar {
            bar.set_message(format!("{stage}: {done}/{total} items"));
        }
    }

    /// What a long-running stage is doing now (e.g. `round 2: screening 9 candidates`): shown on
    /// the terminal's bar only; plain output and the run log stay one line per stage.
    pub fn detail(&self, stage: &str, what: &str) {
        if let Some(bar) = &self.bar {
            bar.set_message(format!("{stage}: {what}"));
        }
    }

    /// A stage is done (ran or reused); `what` says how, with its time.
    pub fn finished(&self, stage: &str, what: &str) {
        let line = format!("{stage}: {what}");
        if let Some(bar) = &self.bar {
            bar.inc(1);
            if what.starts_with("ran") {
                bar.println(format!("groove: {line}"));
            }
        } else if !self.quiet && what.starts_with("ran") {
            eprintln!("groove: {line}");
        }
        self.log.lock().expect("progress log").push(line);
    }

    /// A message that must be seen (a failure, a wait).
    pub fn note(&self, message: &str) {
        match &self.bar {
            Some(bar) => bar.println(format!("groove: {message}")),
            None if !self.quiet => eprintln!("groove: {message}"),
            None => {}
        }
        self.log
            .lock()
            .expect("progress log")
            .push(message.to_string());
    }

    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }

    /// The lines for the run log.
    pub fn lines(&self) -> Vec<String> {
        self.log.lock().expect("progress log").clone()
    }
}
