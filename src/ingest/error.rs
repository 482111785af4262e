//! What can be wrong with a dataset: each problem names the file, row and column, and the fix.

use std::fmt;

/// One problem found in the dataset.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub struct Problem {
    /// File name as in the dataset folder, e.g. `trajectories.csv`.
    pub file: String,
    /// Row as the user sees it: for CSV the line number counting the header line as row 1;
    /// for Parquet the 1-based data row. `None` for problems of a whole file.
    pub row: Option<usize>,
    /// Column name, if the problem is in one column (or a comma-separated list of columns).
    pub column: Option<String>,
    /// The run the problem belongs to, if leaving that run out would remove it (`skip_bad_runs`).
    pub run: Option<String>,
    /// What is wrong, lowercase.
    pub message: String,
    /// What would fix it, lowercase.
    pub fix: String,
}

impl Problem {
    /// A problem of a whole file or of the dataset, that no skipping can remove.
    pub fn file(file: &str, message: impl Into<String>, fix: impl Into<String>) -> Problem {
        Problem {
            file: file.to_string(),
            row: None,
            column: None,
            run: None,
            message: message.into(),
            fix: fix.into(),
        }
    }

    /// A problem at a cell of a file.
    pub fn at(
        file: &str,
        row: usize,
        column: &str,
        message: impl Into<String>,
        fix: impl Into<String>,
    ) -> Problem {
        Problem {
            file: file.to_string(),
            row: Some(row),
            column: Some(column.to_string()),
            run: None,
            message: message.into(),
            fix: fix.into(),
        }
    }

    /// Marks the problem as belonging to `run`, so `skip_bad_runs` can leave the run out.
    pub fn in_run(mut self, run: &str) -> Problem {
        self.run = Some(run.to_string());
        self
    }
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        match (&self.row, &self.column) {
            (Some(r), Some(c)) => write!(f, " row {r}, column {c}")?,
            (Some(r), None) => write!(f, " row {r}")?,
            (None, Some(c)) => write!(f, ", column {c}")?,
            (None, None) => {}
        }
        write!(f, ": {}; {}", self.message, self.fix)
    }
}

/// The dataset cannot be ingested as asked: every problem found, sorted by file and row.
#[derive(Debug, Clone, PartialEq)]
pub struct IngestError {
    pub problems: Vec<Problem>,
}

/// How many problems the error message lists before summarising the rest.
const LISTED: usize = 20;

impl IngestError {
    pub fn new(mut problems: Vec<Problem>) -> IngestError {
        problems.sort();
        problems.dedup();
        IngestError { problems }
    }
}

impl From<Problem> for IngestError {
    fn from(p: Problem) -> IngestError {
        IngestError::new(vec![p])
    }
}

impl fmt::Display for IngestError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let [only] = self.problems.as_slice() {
            write!(f, "{only}")?;
        } else {
            write!(f, "{} problems in the dataset:", self.problems.len())?;
            for p in self.problems.iter().take(LISTED) {
                write!(f, "\n  {p}")?;
            }
            if self.problems.len() > LISTED {
                write!(f, "\n  ... and {} more", self.problems.len() - LISTED)?;
            }
        }
        if !self.problems.is_empty() && self.problems.iter().all(|p| p.run.is_some()) {
            write!(
                f,
                "\n(or set skip_bad_runs = true in the ingest params to leave these runs out)"
            )?;
        }
        Ok(())
    }
}

impl std::error::Error for IngestError {}
