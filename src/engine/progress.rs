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
    /// When each per-item stage started its items, for the estimate of the time left.
    item_starts: Mutex<std::collections::BTreeMap<String, Instant>>,
}

/// Width of the per-item bar, characters.
const ITEM_BAR: usize = 20;
/// Fewest items for which plain output says the quarters of a per-item stage.
const QUARTER_LINES_MIN: usize = 8;

/// `[#####...............] 12/48 items, about 3 s left` (no estimate before the first item).
fn item_line(done: usize, total: usize, elapsed_s: f64) -> String {
    let total = total.max(1);
    let filled = (ITEM_BAR * done.min(total)) / total;
    let bar: String = "#".repeat(filled) + &".".repeat(ITEM_BAR - filled);
    let left = match done {
        0 => String::new(),
        d => {
            let eta = elapsed_s / d as f64 * (total.saturating_sub(d)) as f64;
            format!(", about {} left", seconds(eta))
        }
    };
    format!("[{bar}] {done}/{total} items{left}")
}

/// `3 s`, `2 min 5 s`.
fn seconds(s: f64) -> String {
    let s = s.round().max(0.0) as u64;
    match s {
        0..=59 => format!("{s} s"),
        _ => format!("{} min {} s", s / 60, s % 60),
    }
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
            item_starts: Mutex::new(Default::default()),
        }
    }

    /// A stage started work on `items` items.
    pub fn started(&self, stage: &str, items: usize) {
        if items > 1 {
            self.item_starts
                .lock()
                .expect("item starts")
                .insert(stage.to_string(), Instant::now());
        }
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

    /// One item of a per-item stage is done: the bar shows `stage: [###....] done/total items,
    /// about N s left`; plain output says each quarter of a stage of 8 items or more.
    pub fn item_done(&self, stage: &str, done: usize, total: usize) {
        let elapsed = self
            .item_starts
            .lock()
            .expect("item starts")
            .get(stage)
            .map_or(0.0, |t| t.elapsed().as_secs_f64());
        if let Some(bar) = &self.bar {
            bar.set_message(format!("{stage}: {}", item_line(done, total, elapsed)));
        } else if !self.quiet
            && total >= QUARTER_LINES_MIN
            && done < total
            && (4 * done) / total != (4 * (done - 1)) / total
        {
            eprintln!("groove: {stage}: {}", item_line(done, total, elapsed));
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_item_line_has_a_bar_the_counts_and_the_time_left() {
        assert_eq!(item_line(0, 48, 0.0), "[....................] 0/48 items");
        // 12 of 48 in 3 s: 36 more at 0.25 s each
        assert_eq!(
            item_line(12, 48, 3.0),
            "[#####...............] 12/48 items, about 9 s left"
        );
        assert_eq!(
            item_line(1, 2, 125.0),
            "[##########..........] 1/2 items, about 2 min 5 s left"
        );
    }
}
