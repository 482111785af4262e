//! The user's own material for the report, read and checked: a Markdown notes file (the report
//! stage's input `notes`) and the outputs of a `command` stage (input `additional`: SVG and PNG
//! figures, CSV tables, a caption beside each); `sections::additional` places them on the page.
//!
//! Files of this folder:
//!
//! - `base64.rs`: Bytes as base64, for a figure's `data:` address in the self-contained page
//! - `csv.rs`: A user's CSV table read into cells
//! - `items.rs`: The figures and tables of the `additional` collection, each with its caption
//! - `notes.rs`: The notes file cut into the parts its headings make
//!
//! Errors are lowercase, name the file and say how to fix it; the stage then fails (exit 2).

pub mod base64;
pub mod csv;
pub mod items;
pub mod notes;

/// The notes file as the error messages name it.
pub const NOTES: &str = "the notes file (input `notes` of the report stage)";

/// Everything of the user's the page shows: nothing when neither input is bound.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Own {
    pub notes: notes::Notes,
    pub items: Vec<items::Shown>,
}

/// Read the notes file's bytes and the collection's items (by file name).
pub fn read(notes: Option<&[u8]>, additional: &[(&str, &[u8])]) -> Result<Own, String> {
    let notes = match notes {
        None => notes::Notes::default(),
        Some(bytes) => notes::parse(utf8(NOTES, bytes)?),
    };
    Ok(Own {
        notes,
        items: items::read(additional)?,
    })
}

/// `bytes` as UTF-8 text, or an error naming `what`, the line and the fix.
pub fn utf8<'a>(what: &str, bytes: &'a [u8]) -> Result<&'a str, String> {
    std::str::from_utf8(bytes).map_err(|e| {
        let at = e.valid_up_to();
        let line = bytes[..at].iter().filter(|b| **b == b'\n').count() + 1;
        format!("{what} is not UTF-8 text (line {line}, byte {at}); save it as UTF-8")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_that_is_not_utf8_is_refused_with_its_line() {
        let e = read(Some(b"# a\n\xff b\n"), &[]).unwrap_err();
        assert_eq!(
            e,
            "the notes file (input `notes` of the report stage) is not UTF-8 text (line 2, byte 4); save it as UTF-8"
        );
        assert_eq!(read(None, &[]).unwrap(), Own::default());
    }
}
