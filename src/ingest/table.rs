//! A table read from CSV or Parquet bytes with polars, with typed cell access that reports bad cells
//! by file, row (as the user sees it) and column.

use super::csv_check;
use super::error::Problem;
use super::parquet_pages;
use polars::prelude::*;
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::io::Cursor;

/// One column's cells. CSV columns are all text; Parquet columns keep their type.
#[derive(Debug, Clone)]
enum Cells {
    Text(StringChunked),
    Float(Vec<Option<f64>>),
    Int(Vec<Option<i64>>),
    /// A Parquet type groove does not read; the text is the type's name.
    Unsupported(String),
}

/// A table of one file: header names in file order, cells by column, and each data row's number
/// as the user sees it.
#[derive(Debug, Clone)]
pub struct Table {
    pub file: String,
    pub names: Vec<String>,
    columns: BTreeMap<String, Cells>,
    rows: Vec<usize>,
    /// Read from Parquet, whose columns carry types (numbers must not be stored as text).
    parquet: bool,
}

impl Table {
    /// Reads a comma-separated file with one header line. Every cell is read as text; header names
    /// and cells are trimmed of surrounding spaces when used.
    pub fn from_csv(file: &str, bytes: &[u8]) -> Result<Table, Problem> {
        let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
        if bytes.iter().all(|b| b.is_ascii_whitespace()) {
            return Err(Problem::file(
                file,
                "is empty",
                "write a header line and at least one data row",
            ));
        }
        csv_check::check(file, bytes)?;
        let read = || {
            CsvReadOptions::default()
                .with_has_header(true)
                .with_infer_schema_length(Some(0))
                .into_reader_with_file_handle(Cursor::new(bytes))
                .finish()
        };
        let df = guarded(read)
            .map_err(|e| {
                Problem::file(
                    file,
                    format!("cannot be read as CSV ({})", parser_words(&e)),
                    "save it as comma-separated text with one header line and the same number of fields on every line",
                )
            })?;
        let mut table = Table::from_frame(file, &df)?;
        table.rows = csv_row_numbers(bytes, df.height());
        Ok(table)
    }

    /// Reads a Parquet file. Rows are numbered from 1 (Parquet has no header line).
    pub fn from_parquet(file: &str, bytes: &[u8]) -> Result<Table, Problem> {
        let damaged = |reason: &str| {
            Problem::file(
                file,
                format!("cannot be read as Parquet: it is damaged or not Parquet ({reason})"),
                "write it again as a Parquet file, or use the CSV form",
            )
        };
        let metadata = guarded(|| {
            ParquetReader::new(Cursor::new(bytes))
                .get_metadata()
                .cloned()
        })
        .map_err(|e| damaged(&parser_words(&e)))?;
        // a damaged page header would make polars' decoder abort the process
        if !parquet_pages::sound(bytes, &metadata, 0..metadata.num_rows, None) {
            return Err(damaged("a page's header is damaged"));
        }
        let df = guarded(|| {
            // one thread: a damaged file gives the same first error (and message) every time
            let mut reader = ParquetReader::new(Cursor::new(bytes));
            reader.set_metadata(metadata);
            reader.read_parallel(ParallelStrategy::None).finish()
        })
        .map_err(|e| damaged(&parser_words(&e)))?;
        let mut table = Table::from_frame(file, &df)?;
        table.parquet = true;
        Ok(table)
    }

    /// Reads a file by its extension: `.parquet` as Parquet, anything else as CSV.
    pub fn from_bytes(file: &str, bytes: &[u8]) -> Result<Table, Problem> {
        if file.to_ascii_lowercase().ends_with(".parquet") {
            Table::from_parquet(file, bytes)
        } else {
            Table::from_csv(file, bytes)
        }
    }

    fn from_frame(file: &str, df: &DataFrame) -> Result<Table, Problem> {
        let mut names = Vec::new();
        let mut columns = BTreeMap::new();
        for col in df.columns() {
            let name = col.name().trim().to_string();
            let cells = cells_of(col).map_err(|e| {
                Problem::file(
                    file,
                    format!("column {name} cannot be read ({e})"),
                    "store numbers as float64 or int64 and text as string",
                )
            })?;
            if columns.insert(name.clone(), cells).is_some() {
                return Err(Problem::file(
                    file,
                    format!("column {name} appears twice"),
                    "rename or delete one of the two columns",
                ));
            }
            names.push(name);
        }
        Ok(Table {
            file: file.to_string(),
            names,
            columns,
            rows: (1..=df.height()).collect(),
            parquet: false,
        })
    }

    /// In a Parquet file, a problem if any of `numeric` is stored as text: numbers as strings are
    /// not read (a spreadsheet export that quoted them would otherwise pass unnoticed).
    pub fn require_numeric(&self, numeric: &[&str]) -> Result<(), Problem> {
        if !self.parquet {
            return Ok(());
        }
        for name in numeric {
            let Some(Cells::Text(v)) = self.columns.get(*name) else {
                continue;
            };
            if v.iter().all(|c| c.is_none()) {
                continue;
            }
            return Err(Problem {
                file: self.file.clone(),
                row: None,
                column: Some(name.to_string()),
                run: None,
                message: "holds numbers stored as text (Parquet type string)".into(),
                fix: "store the column as float64 or int64 (e.g. pandas: df[col].astype(float))"
                    .into(),
            });
        }
        Ok(())
    }

    /// Number of data rows.
    pub fn height(&self) -> usize {
        self.rows.len()
    }

    /// The row number of data row `i` (0-based) as the user sees it in the file.
    pub fn row(&self, i: usize) -> usize {
        self.rows[i]
    }

    pub fn has(&self, column: &str) -> bool {
        self.columns.contains_key(column)
    }

    /// Removes the first `n` data rows (extra header rows of TrackMate tables), keeping row numbers.
    pub fn drop_leading_rows(&mut self, n: usize) {
        let n = n.min(self.rows.len());
        self.rows.drain(..n);
        for cells in self.columns.values_mut() {
            match cells {
                Cells::Text(v) => *v = v.slice(n as i64, v.len() - n),
                Cells::Float(v) => drop(v.drain(..n)),
                Cells::Int(v) => drop(v.drain(..n)),
                Cells::Unsupported(_) => {}
            }
        }
    }

    /// A problem if any of `required` is missing, naming each with what it holds.
    pub fn require(&self, required: &[(&str, &str)]) -> Result<(), Problem> {
        let missing: Vec<&(&str, &str)> = required.iter().filter(|(c, _)| !self.has(c)).collect();
        if missing.is_empty() {
            return Ok(());
        }
        let names: Vec<&str> = missing.iter().map(|(c, _)| *c).collect();
        let fixes: Vec<String> = missing.iter().map(|(c, m)| format!("{c} ({m})")).collect();
        Err(Problem {
            file: self.file.clone(),
            row: Some(1),
            column: Some(names.join(", ")),
            run: None,
            message: format!(
                "missing column{} (the header has: {})",
                if names.len() > 1 { "s" } else { "" },
                self.names.join(", ")
            ),
            fix: format!("add {}", fixes.join(", ")),
        })
    }

    /// One column, looked up once for reading many rows.
    pub fn col<'a>(&'a self, name: &'a str) -> Col<'a> {
        Col {
            table: self,
            name,
            cells: self.columns.get(name),
        }
    }

    /// The cell's text, trimmed; `None` for an empty cell (see `Col::text`).
    pub fn text(&self, column: &str, i: usize) -> Option<Cow<'_, str>> {
        text_of(self.columns.get(column), i)
    }

    /// A required non-empty text cell.
    pub fn string(&self, column: &str, i: usize, fix: &str) -> Result<String, Problem> {
        self.col(column).string(i, fix)
    }

    /// A finite number (see `Col::float`).
    pub fn float(&self, column: &str, i: usize, fix: &str) -> Result<f64, Problem> {
        self.col(column).float(i, fix)
    }

    /// A problem at data row `i` (0-based) and `column`.
    pub fn problem(
        &self,
        column: &str,
        i: usize,
        message: impl Into<String>,
        fix: impl Into<String>,
    ) -> Problem {
        Problem::at(&self.file, self.rows[i], column, message, fix)
    }
}

/// One column of a table with typed access to its cells; a missing column reads as empty cells.
#[derive(Clone, Copy)]
pub struct Col<'a> {
    table: &'a Table,
    name: &'a str,
    cells: Option<&'a Cells>,
}

impl<'a> Col<'a> {
    /// The cell's text, trimmed; `None` for an empty cell. Numbers of Parquet files are written
    /// in their shortest round-trip form.
    pub fn text(&self, i: usize) -> Option<Cow<'a, str>> {
        text_of(self.cells, i)
    }

    /// A required non-empty text cell.
    pub fn string(&self, i: usize, fix: &str) -> Result<String, Problem> {
        self.check_supported(i)?;
        self.text(i)
            .map(Cow::into_owned)
            .ok_or_else(|| self.problem(i, "is empty", fix))
    }

    /// A finite number. `fix` says what to write, e.g. "write a finite number in metres".
    pub fn float(&self, i: usize, fix: &str) -> Result<f64, Problem> {
        self.check_supported(i)?;
        let x = match self.cells {
            Some(Cells::Float(v)) => v[i],
            Some(Cells::Int(v)) => v[i].map(|x| x as f64),
            _ => match self.text(i) {
                None => None,
                Some(s) => Some(
                    s.parse::<f64>()
                        .map_err(|_| self.problem(i, format!("{s:?} is not a number"), fix))?,
                ),
            },
        };
        let x = x.ok_or_else(|| self.problem(i, "is empty", fix))?;
        if !x.is_finite() {
            return Err(self.problem(i, format!("{x} is not a finite number"), fix));
        }
        Ok(x)
    }

    /// A whole number (written as an integer, or as a number with no fractional part such as `12.0`).
    pub fn int(&self, i: usize, fix: &str) -> Result<i64, Problem> {
        self.check_supported(i)?;
        if let Some(Cells::Int(v)) = self.cells {
            return v[i].ok_or_else(|| self.problem(i, "is empty", fix));
        }
        let text = self
            .text(i)
            .ok_or_else(|| self.problem(i, "is empty", fix))?;
        if let Ok(n) = text.parse::<i64>() {
            return Ok(n);
        }
        match text.parse::<f64>() {
            Ok(x) if x.is_finite() && x.fract() == 0.0 && x.abs() < 9.0e15 => Ok(x as i64),
            _ => Err(self.problem(i, format!("{text:?} is not a whole number"), fix)),
        }
    }

    /// A problem at data row `i` (0-based) of this column.
    pub fn problem(&self, i: usize, message: impl Into<String>, fix: impl Into<String>) -> Problem {
        self.table.problem(self.name, i, message, fix)
    }

    fn check_supported(&self, i: usize) -> Result<(), Problem> {
        match self.cells {
            Some(Cells::Unsupported(dtype)) => Err(self.problem(
                i,
                format!("has the Parquet type {dtype}, which groove does not read"),
                "store numbers as float64 or int64 and text as string",
            )),
            _ => Ok(()),
        }
    }
}

/// The text of cell `i`, trimmed; `None` if empty.
fn text_of(cells: Option<&Cells>, i: usize) -> Option<Cow<'_, str>> {
    match cells? {
        Cells::Text(v) => v
            .get(i)
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(Cow::Borrowed),
        Cells::Float(v) => v[i].map(|x| Cow::Owned(x.to_string())),
        Cells::Int(v) => v[i].map(|x| Cow::Owned(x.to_string())),
        Cells::Unsupported(_) => None,
    }
}

/// The cells of one polars column.
fn cells_of(col: &Column) -> PolarsResult<Cells> {
    let dtype = col.dtype().clone();
    Ok(match dtype {
        DataType::String => Cells::Text(col.str()?.rechunk().into_owned()),
        DataType::Float32 | DataType::Float64 => {
            let c = col.cast(&DataType::Float64)?;
            Cells::Float(c.f64()?.iter().collect())
        }
        d if d.is_integer() => {
            let c = col.cast(&DataType::Int64)?;
            Cells::Int(c.i64()?.iter().collect())
        }
        DataType::Null => {
            let c = col.cast(&DataType::String)?;
            Cells::Text(c.str()?.rechunk().into_owned())
        }
        other => Cells::Unsupported(other.to_string()),
    })
}

/// The line number of each data row of a CSV file, counting the header line as row 1. Blank lines
/// are not data rows; if the lines do not match polars' row count (quoted line breaks), rows are
/// assumed to follow the header one per line.
fn csv_row_numbers(bytes: &[u8], height: usize) -> Vec<usize> {
    let mut lines = bytes.split(|&b| b == b'\n').enumerate();
    // The header is the first non-blank line.
    let header = lines.find(|(_, l)| !is_blank(l)).map_or(0, |(k, _)| k);
    let data: Vec<usize> = bytes
        .split(|&b| b == b'\n')
        .enumerate()
        .skip(header + 1)
        .filter(|(_, l)| !is_blank(l))
        .map(|(k, _)| k + 1)
        .collect();
    if data.len() == height {
        data
    } else {
        (0..height).map(|i| header + 2 + i).collect()
    }
}

fn is_blank(line: &[u8]) -> bool {
    line.iter().all(|b| b.is_ascii_whitespace())
}

/// Runs a polars reader, turning a panic inside it (seen on damaged files) into an error, so bad
/// bytes never crash groove.
pub(super) fn guarded<T>(read: impl FnOnce() -> PolarsResult<T>) -> Result<T, String> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(read)) {
        Ok(Ok(t)) => Ok(t),
        Ok(Err(e)) => Err(e.to_string()),
        Err(_) => Err("the reader stopped on malformed bytes".into()),
    }
}

/// polars' reason in groove's words: known parser phrases translated; anything else (thrift
/// structures, internal names) is left out rather than shown untranslated.
fn parser_words(reason: &str) -> String {
    const WORDS: [(&str, &str); 9] = [
        (
            "found more fields than defined",
            "a row has more fields than the header",
        ),
        ("invalid utf-8", "the text is not UTF-8"),
        (
            "csv malformed",
            "the quoting or the field count is malformed",
        ),
        ("out of spec", "the file does not follow the Parquet format"),
        ("thrift", "the file's metadata is damaged"),
        ("invalidoffset", "the file's metadata is damaged"),
        ("error_kind", "the file's metadata is damaged"),
        ("unexpected end", "the file ends too early (cut short?)"),
        ("eof", "the file ends too early (cut short?)"),
    ];
    let lower = reason.to_ascii_lowercase();
    WORDS
        .iter()
        .find(|(phrase, _)| lower.contains(phrase))
        .map_or("the reader could not make sense of it", |(_, words)| words)
        .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parser_wording_is_translated() {
        assert_eq!(
            parser_words("CSV malformed: quote"),
            "the quoting or the field count is malformed"
        );
        assert_eq!(
            parser_words("parquet error: Error { error_kind: InvalidOffset }"),
            "the file's metadata is damaged"
        );
        assert_eq!(
            parser_words("CSV malformed: found more fields than defined in 'Schema'"),
            "a row has more fields than the header"
        );
    }
}
