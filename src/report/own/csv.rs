//! A user's CSV table read into cells: commas between cells, double quotes around a cell that
//! holds a comma, a quote (doubled) or a line break; every row as long as the header.

/// The header and the rows of `text`, or an error naming `file`, the line and the fix.
pub fn parse(file: &str, text: &str) -> Result<(Vec<String>, Vec<Vec<String>>), String> {
    let mut rows = records(file, text)?;
    if rows.is_empty() {
        return Err(format!(
            "`{file}` is empty; write a header line and the table's rows, or leave the file out"
        ));
    }
    let (_, header) = rows.remove(0);
    for (line, r) in &rows {
        if r.len() != header.len() {
            return Err(format!(
                "`{file}` line {line} has {} cells but the header has {}; quote a cell that holds a comma (\"a, b\")",
                r.len(),
                header.len()
            ));
        }
    }
    Ok((header, rows.into_iter().map(|(_, r)| r).collect()))
}

/// The records of `text` with the line each starts on; blank lines are skipped.
fn records(file: &str, text: &str) -> Result<Vec<(usize, Vec<String>)>, String> {
    let mut out = Vec::new();
    let mut cells = Vec::new();
    let mut cell = String::new();
    let (mut line, mut start) = (1, 1);
    let (mut quoted, mut was_quoted) = (false, false);
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                chars.next();
                cell.push('"');
            }
            (true, '"') => quoted = false,
            (true, c) => {
                line += usize::from(c == '\n');
                cell.push(c);
            }
            (false, '"') if cell.is_empty() && !was_quoted => (quoted, was_quoted) = (true, true),
            (false, ',') => {
                cells.push(std::mem::take(&mut cell));
                was_quoted = false;
            }
            (false, '\r') if chars.peek() == Some(&'\n') => {}
            (false, '\n') => {
                cells.push(std::mem::take(&mut cell));
                let r = std::mem::take(&mut cells);
                if !(r.len() == 1 && r[0].is_empty() && !was_quoted) {
                    out.push((start, r));
                }
                was_quoted = false;
                line += 1;
                start = line;
            }
            (false, c) => cell.push(c),
        }
    }
    if quoted {
        return Err(format!(
            "`{file}` line {start}: a quoted cell is never closed; add the closing double quote"
        ));
    }
    if !cell.is_empty() || !cells.is_empty() || was_quoted {
        cells.push(cell);
        out.push((start, cells));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::parse;

    #[test]
    fn quoted_cells_keep_commas_quotes_and_line_breaks() {
        let (h, rows) =
            parse("t.csv", "a,b\r\n1,\"x, \"\"y\"\"\"\n\n2,\"two\nlines\"\n3,").unwrap();
        assert_eq!(h, ["a", "b"]);
        assert_eq!(rows, [["1", "x, \"y\""], ["2", "two\nlines"], ["3", ""]]);
    }

    #[test]
    fn a_ragged_row_or_an_open_quote_names_its_line() {
        assert_eq!(
            parse("t.csv", "a,b\n1,2\n1,2,3\n").unwrap_err(),
            "`t.csv` line 3 has 3 cells but the header has 2; quote a cell that holds a comma (\"a, b\")"
        );
        assert!(parse("t.csv", "a\n\"open\n")
            .unwrap_err()
            .contains("line 2: a quoted cell"));
        assert!(parse("t.csv", "").unwrap_err().contains("`t.csv` is empty"));
    }
}
