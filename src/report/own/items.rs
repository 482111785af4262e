//! The figures and tables of the `additional` collection (a `command` stage's folder output), each
//! with its caption: `NAME.svg` or `NAME.png` is a figure, `NAME.csv` a table, and `NAME.md` or
//! `NAME.txt` beside them the caption (inline Markdown) of every figure and table named NAME.
//! Shown in file-name order; a file of any other kind is an error, not silently dropped.

use super::{base64, csv, utf8};
use std::collections::BTreeMap;

/// Rows of a table beyond this many are left out of the page (the caption says how many).
pub const MAX_ROWS: usize = 200;

/// One figure or table of the user's.
#[derive(Debug, Clone, PartialEq)]
pub enum Shown {
    Figure {
        name: String,
        caption: String,
        mime: &'static str,
        base64: String,
    },
    Table {
        name: String,
        caption: String,
        headers: Vec<String>,
        rows: Vec<Vec<String>>,
        /// Rows in the file (more than `rows` when it was cut at `MAX_ROWS`).
        n_rows: usize,
    },
}

const PNG: &[u8] = b"\x89PNG\r\n\x1a\n";

fn stem_ext(name: &str) -> (&str, String) {
    match name.rsplit_once('.') {
        Some((s, e)) => (s, e.to_ascii_lowercase()),
        None => (name, String::new()),
    }
}

fn where_(name: &str) -> String {
    format!("additional analyses (input `additional` of the report stage): `{name}`")
}

/// The figures and tables of the collection's items (file name → bytes).
pub fn read(items: &[(&str, &[u8])]) -> Result<Vec<Shown>, String> {
    let mut captions: BTreeMap<&str, (&str, String)> = BTreeMap::new();
    for (name, bytes) in items {
        let (stem, ext) = stem_ext(name);
        if ext == "md" || ext == "txt" {
            let text = utf8(&where_(name), bytes)?;
            let one_line = text.split_whitespace().collect::<Vec<_>>().join(" ");
            if let Some((other, _)) = captions.insert(stem, (name, one_line)) {
                return Err(format!(
                    "{} and `{other}` both caption `{stem}`; keep one of them",
                    where_(name)
                ));
            }
        }
    }
    let mut out = Vec::new();
    let mut used = BTreeMap::new();
    for (name, bytes) in items {
        let (stem, ext) = stem_ext(name);
        let caption = match captions.get(stem) {
            Some((_, c)) if !c.is_empty() => c.clone(),
            _ => format!("`{name}`"),
        };
        let shown = match ext.as_str() {
            "md" | "txt" => continue,
            "png" if bytes.starts_with(PNG) => figure(name, caption, "image/png", bytes),
            "png" => {
                return Err(format!(
                    "{} does not start with PNG's signature; write it as a PNG image or give it the extension of its format",
                    where_(name)
                ))
            }
            "svg" => {
                let text = utf8(&where_(name), bytes)?;
                if !text.contains("<svg") {
                    return Err(format!(
                        "{} holds no <svg> element; write an SVG image or give it the extension of its format",
                        where_(name)
                    ));
                }
                figure(name, caption, "image/svg+xml", bytes)
            }
            "csv" => {
                let (headers, mut rows) = csv::parse(&where_(name), utf8(&where_(name), bytes)?)?;
                let n_rows = rows.len();
                rows.truncate(MAX_ROWS);
                Shown::Table {
                    name: name.to_string(),
                    caption,
                    headers,
                    rows,
                    n_rows,
                }
            }
            _ => {
                return Err(format!(
                    "{} is neither a figure (.svg, .png), a table (.csv) nor a caption (.md, .txt beside them); remove it from the stage's output or convert it",
                    where_(name)
                ))
            }
        };
        used.insert(stem, ());
        out.push(shown);
    }
    if let Some((_, (file, _))) = captions.iter().find(|(s, _)| !used.contains_key(*s)) {
        return Err(format!(
            "{} captions nothing: there is no figure or table of that name beside it; rename it to match one, or remove it",
            where_(file)
        ));
    }
    Ok(out)
}

fn figure(name: &str, caption: String, mime: &'static str, bytes: &[u8]) -> Shown {
    Shown::Figure {
        name: name.to_string(),
        caption,
        mime,
        base64: base64::encode(bytes),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SVG: &[u8] = b"<svg xmlns=\"http://www.w3.org/2000/svg\"/>";

    #[test]
    fn figures_and_tables_take_the_caption_of_their_name() {
        let png = [PNG, b"rest"].concat();
        let items: Vec<(&str, &[u8])> = vec![
            ("a.csv", b"x,y\n1,2\n"),
            ("a.md", b"The *growth*\nof x.\n"),
            ("b.png", &png),
            ("c.svg", SVG),
        ];
        let shown = read(&items).unwrap();
        assert_eq!(shown.len(), 3);
        let Shown::Table { caption, rows, .. } = &shown[0] else {
            panic!()
        };
        assert_eq!((caption.as_str(), rows.len()), ("The *growth* of x.", 1));
        let Shown::Figure { caption, mime, .. } = &shown[1] else {
            panic!()
        };
        assert_eq!((caption.as_str(), *mime), ("`b.png`", "image/png"));
        let Shown::Figure { base64, .. } = &shown[2] else {
            panic!()
        };
        assert_eq!(*base64, super::base64::encode(SVG));
    }

    #[test]
    fn a_file_the_page_cannot_show_is_an_error_naming_it() {
        let bad: [(&str, &[u8]); 4] = [
            ("x.pdf", b"%PDF"),
            ("x.png", b"GIF89a"),
            ("x.svg", b"<html/>"),
            ("x.txt", b"a caption"),
        ];
        for (name, bytes) in bad {
            let e = read(&[(name, bytes)]).unwrap_err();
            assert!(e.contains(&format!("`{name}`")) && e.contains("; "), "{e}");
        }
    }
}
