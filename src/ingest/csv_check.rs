//! Checks of a CSV file's bytes before the parser sees them, so that the errors polars would give
//! in its own words ("found more fields than defined in 'Schema'", invalid UTF-8) are said in
//! groove's: file, row (the line as the user sees it, header = row 1) and column.

use super::error::Problem;

/// The first problem of the file's shape: bytes that are not UTF-8, or a row with more fields
/// than the header names. Rows with fewer fields are left to the parser (their missing cells read
/// as empty and are named by the cell checks).
pub fn check(file: &str, bytes: &[u8]) -> Result<(), Problem> {
    let rows = split_rows(bytes);
    let Some(header) = rows.iter().find(|r| !r.blank) else {
        return Ok(());
    };
    let names = header_names(bytes, header);
    let mut seen = std::collections::HashMap::new();
    for (k, name) in names
        .iter()
        .enumerate()
        .filter(|(_, n)| !n.trim().is_empty())
    {
        if let Some(first) = seen.insert(name.trim(), k) {
            return Err(Problem::at(
                file,
                header.line,
                name.trim(),
                format!(
                    "the header names column {} twice (fields {} and {})",
                    name.trim(),
                    first + 1,
                    k + 1
                ),
                "rename or delete one of the two columns",
            ));
        }
    }
    if let Err(e) = std::str::from_utf8(bytes) {
        let at = e.valid_up_to();
        let row = rows.iter().find(|r| at < r.end).unwrap_or(header);
        let field = row
            .fields
            .iter()
            .position(|&(_, end)| at < end)
            .unwrap_or(0);
        let column = names
            .get(field)
            .filter(|n| !n.is_empty())
            .cloned()
            .unwrap_or_else(|| format!("field {}", field + 1));
        let what = if std::ptr::eq(row, header) {
            "the header row is not UTF-8 text".to_string()
        } else {
            "is not UTF-8 text".to_string()
        };
        return Err(Problem::at(
            file,
            row.line,
            &column,
            format!("{what} (byte 0x{:02x})", bytes[at]),
            "save the file as UTF-8 text (in a spreadsheet: CSV UTF-8)",
        ));
    }
    let expected = header.fields.len();
    for row in rows.iter().filter(|r| !r.blank && r.line > header.line) {
        if row.fields.len() > expected {
            return Err(Problem::at(
                file,
                row.line,
                &format!("field {}", expected + 1),
                format!(
                    "the row has {} fields but the header names {expected} columns ({})",
                    row.fields.len(),
                    names.join(", ")
                ),
                "delete the extra commas, or put a field holding a comma in double quotes",
            ));
        }
    }
    Ok(())
}

/// One record of the file: its first line number (1-based), where it ends, and its fields' byte
/// ranges. A quoted field may span lines; the record then spans them too.
#[derive(Debug)]
struct Row {
    line: usize,
    end: usize,
    fields: Vec<(usize, usize)>,
    blank: bool,
}

/// Splits the bytes into records, honouring double quotes (`""` inside quotes is a quote).
fn split_rows(bytes: &[u8]) -> Vec<Row> {
    let mut rows = Vec::new();
    let mut line = 1;
    let mut i = 0;
    while i < bytes.len() {
        let (start, first_line) = (i, line);
        let mut fields = Vec::new();
        let mut field_start = i;
        let mut quoted = false;
        while i < bytes.len() {
            match bytes[i] {
                b'"' => quoted = !quoted,
                b',' if !quoted => {
                    fields.push((field_start, i));
                    field_start = i + 1;
                }
                b'\n' if quoted => line += 1,
                b'\n' => break,
                _ => {}
            }
            i += 1;
        }
        fields.push((field_start, i));
        let end = i;
        let blank = bytes[start..end].iter().all(u8::is_ascii_whitespace);
        rows.push(Row {
            line: first_line,
            end,
            fields,
            blank,
        });
        // Past the newline.
        i += 1;
        line += 1;
    }
    rows
}

/// The header's names, trimmed and unquoted, as lossy text.
fn header_names(bytes: &[u8], header: &Row) -> Vec<String> {
    header
        .fields
        .iter()
        .map(|&(a, b)| {
            let s = String::from_utf8_lossy(&bytes[a..b]);
            s.trim().trim_matches('"').trim().to_string()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn more_fields_are_named_at_their_row() {
        let p = check("t.csv", b"a,b\n1,2\n\n3,4,5\n").unwrap_err();
        assert_eq!(p.row, Some(4));
        assert!(p.message.contains("3 fields"), "{p}");
    }

    #[test]
    fn quoted_commas_and_line_breaks_are_one_field() {
        assert!(check("t.csv", b"a,b\n\"1,5\",2\n\"x\ny\",3\n").is_ok());
    }

    #[test]
    fn invalid_utf8_names_row_and_column() {
        let p = check("t.csv", b"a,b\n1,2\n3,\xff\n").unwrap_err();
        assert_eq!((p.row, p.column.as_deref()), (Some(3), Some("b")));
        let p = check("t.csv", b"a,\xffb\n1,2\n").unwrap_err();
        assert_eq!(p.row, Some(1));
        assert!(p.message.contains("header"), "{p}");
    }
}
