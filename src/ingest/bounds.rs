//! Limits checked before a dataset file is read: the header's width of a CSV file and the size of
//! a file read whole, so that no input makes ingest hold memory in proportion to rows × columns
//! or to a file larger than memory.
//!
//! Both limits only refuse (exit 2, naming the file, the limit and how to raise it); a dataset
//! within them gives the same result whatever they are, so they are read from the environment
//! and are no part of a stage's key:
//!
//! - `GROOVE_INGEST_MAX_COLUMNS` (default 1,000): columns a CSV header may name. groove reads
//!   at most a dozen; a table with a few more kept as text is fine, one with 200,000 made the
//!   parser hold an empty cell per column per row (7.5 GB for 2,000 rows).
//! - `GROOVE_INGEST_MAX_WHOLE_MB` (default 256): size of a file ingest reads whole (`runs.csv`,
//!   tracker exports, and `trajectories.*` when it cannot be streamed). Parsing a table read
//!   whole holds a few times its size; the streamed trajectories have no such limit.

use super::error::Problem;

/// The longest header line read to count its columns (1 MiB: 1,000 names of 1,000 bytes).
pub const HEADER_BYTES: usize = 1 << 20;

const COLUMNS_VAR: &str = "GROOVE_INGEST_MAX_COLUMNS";
const WHOLE_VAR: &str = "GROOVE_INGEST_MAX_WHOLE_MB";

/// A limit from the environment, or its default (a value that is not a positive whole number is
/// an error naming the variable).
fn limit(var: &str, default: u64) -> Result<u64, Problem> {
    match std::env::var(var) {
        Err(_) => Ok(default),
        Ok(v) => v
            .trim()
            .parse::<u64>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| {
                Problem::file(
                    var,
                    format!("`{v}` is not a limit"),
                    format!("set {var} to a positive whole number, or unset it for the default"),
                )
            }),
    }
}

/// The header's width of a CSV file, from the start of its bytes (`start`: at least the header
/// line, or the whole file when it is shorter than [`HEADER_BYTES`]). Files that are not CSV
/// pass.
pub fn check_header(file: &str, start: &[u8]) -> Result<(), Problem> {
    if !file.to_ascii_lowercase().ends_with(".csv") {
        return Ok(());
    }
    let max = limit(COLUMNS_VAR, 1000)?;
    // the first line that is not blank is the header (as the parser takes it)
    let mut rest = start;
    // cut: the header line goes on past what was read
    let cut = !start.contains(&b'\n') && start.len() >= HEADER_BYTES;
    let header = loop {
        let (line, more) = match rest.iter().position(|&b| b == b'\n') {
            Some(i) => (&rest[..i], Some(&rest[i + 1..])),
            None => (rest, None),
        };
        match (line.iter().all(u8::is_ascii_whitespace), more) {
            (true, Some(more)) => rest = more,
            _ => break line,
        }
    };
    // commas outside double quotes separate the names
    let mut quoted = false;
    let mut columns: u64 = 1;
    for &b in header {
        match b {
            b'"' => quoted = !quoted,
            b',' if !quoted => columns += 1,
            _ => {}
        }
    }
    if columns > max {
        let more = if cut { " or more" } else { "" };
        return Err(Problem {
            row: Some(1),
            ..Problem::file(
                file,
                format!("the header names {columns}{more} columns, more than the {max} groove reads"),
                match cut {
                    false => format!("delete the columns groove does not use, or raise the limit with the environment variable {COLUMNS_VAR}={columns}"),
                    true => format!("delete the columns groove does not use (groove reads {} KiB of a header line at most)", HEADER_BYTES >> 10),
                },
            )
        });
    }
    if cut {
        return Err(Problem::file(
            file,
            format!("the header line is longer than {} KiB", HEADER_BYTES >> 10),
            "check that the file is a CSV table with one header line (column names separated by commas)",
        ));
    }
    Ok(())
}

/// The size of a file ingest would read whole (`why`: why it is read whole, and `fix`: what
/// else than raising the limit would do, both said in the error).
pub fn check_whole(file: &str, bytes: u64, why: &str, fix: &str) -> Result<(), Problem> {
    let max_mb = limit(WHOLE_VAR, 256)?;
    if bytes > max_mb.saturating_mul(1 << 20) {
        let mb = bytes.div_ceil(1 << 20);
        return Err(Problem::file(
            file,
            format!("is {mb} MB, more than the {max_mb} MB ingest reads whole ({why})"),
            format!("{fix}, or raise the limit with the environment variable {WHOLE_VAR}={mb}"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_header_wider_than_the_limit_is_refused_with_the_variable_to_raise() {
        let wide = format!("run,{}\nr1,1\n", vec!["x"; 1200].join(","));
        let p = check_header("runs.csv", wide.as_bytes()).unwrap_err();
        assert_eq!(p.row, Some(1));
        assert!(
            p.to_string().contains("1201 columns, more than the 1000"),
            "{p}"
        );
        assert!(p.fix.contains("GROOVE_INGEST_MAX_COLUMNS=1201"), "{p}");
        let narrow = format!("\n\"a,b\",{}\n", vec!["x"; 998].join(","));
        assert_eq!(check_header("runs.csv", narrow.as_bytes()), Ok(()));
        assert_eq!(check_header("runs.parquet", wide.as_bytes()), Ok(()));
    }

    #[test]
    fn a_header_line_without_its_end_is_refused() {
        let long = vec![b'x'; HEADER_BYTES];
        let p = check_header("t.csv", &long).unwrap_err();
        assert!(p.message.contains("longer than 1024 KiB"), "{p}");
        // a cut header already wider than the limit says so
        let wide: Vec<u8> = b"x,".iter().copied().cycle().take(HEADER_BYTES).collect();
        let p = check_header("t.csv", &wide).unwrap_err();
        assert!(p.message.contains("524289 or more columns"), "{p}");
    }

    #[test]
    fn a_file_read_whole_above_the_limit_is_refused_naming_it() {
        assert_eq!(
            check_whole("runs.csv", 256 << 20, "a table", "check it"),
            Ok(())
        );
        let p = check_whole("runs.csv", (256 << 20) + 1, "a table", "check it").unwrap_err();
        assert!(
            p.to_string()
                .starts_with("runs.csv: is 257 MB, more than the 256 MB"),
            "{p}"
        );
        assert!(p.fix.contains("GROOVE_INGEST_MAX_WHOLE_MB=257"), "{p}");
    }
}
