//! The user's own sections: each part of the notes file goes after the section or subsection its
//! heading names (the title as printed, its number optional, case ignored: `## Discovery` or
//! `## 3.2 Fig. 4.2c: drag time T against v0`); the other parts, the text before the first
//! heading and the `additional` figures and tables make "Additional analyses", the last section.

use super::{toc, Block, Item, Note, Page, Table};
use crate::report::own::items::{Shown, MAX_ROWS};
use crate::report::own::notes::Part;
use crate::report::own::Own;
use std::collections::BTreeSet;

/// A heading as notes are matched to it: without its number, lowercase, single spaces.
fn key(title: &str) -> String {
    let t = match toc::number(title) {
        Some(n) => title.trim_start()[title.trim_start().find(n).unwrap_or(0) + n.len()..]
            .trim_start_matches('.'),
        None => title,
    };
    t.split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .trim_end_matches([':', '.'])
        .to_lowercase()
}

/// `a heading` → `note-a-heading`, unique among `taken`.
fn anchor(heading: &str, taken: &mut BTreeSet<String>) -> String {
    let mut slug = String::from("note-");
    for c in heading.chars().flat_map(char::to_lowercase) {
        if c.is_ascii_alphanumeric() {
            slug.push(c);
        } else if !slug.ends_with('-') {
            slug.push('-');
        }
    }
    let slug = slug.trim_end_matches('-').to_string();
    let mut id = slug.clone();
    let mut n = 1;
    while !taken.insert(id.clone()) {
        n += 1;
        id = format!("{slug}-{n}");
    }
    id
}

fn note(p: &Part, level: usize, taken: &mut BTreeSet<String>) -> Note {
    Note {
        id: anchor(&p.heading, taken),
        heading: p.heading.clone(),
        level,
        body: p.body_at(level),
    }
}

/// Where a note goes: the notes of a block (at a level), or of sections 3 and 5.
fn place_note(page: &mut Page, p: &Part, taken: &mut BTreeSet<String>) -> Option<()> {
    let k = key(&p.heading);
    let is = |title: &str| key(title) == k;
    if is(toc::CHAPTER) {
        page.chapter_notes.push(note(p, 3, taken));
        return Some(());
    }
    if is(toc::AUDIT) {
        page.audit_notes.push(note(p, 3, taken));
        return Some(());
    }
    let top = [
        &mut page.summary,
        &mut page.data,
        &mut page.discovery,
        &mut page.provenance,
    ]
    .into_iter()
    .chain(page.baseline.as_mut())
    .map(|b| (b, 3));
    let sub = page.chapter.iter_mut().map(|b| (b, 4));
    let (b, level) = top.chain(sub).find(|(b, _)| is(&b.heading))?;
    b.notes.push(note(p, level, taken));
    Some(())
}

/// The user's figures and tables as items of a block.
fn item(s: &Shown) -> Item {
    match s {
        Shown::Figure {
            name,
            caption,
            mime,
            base64,
        } => Item::Image {
            name: name.clone(),
            caption: caption.clone(),
            mime: mime.to_string(),
            data: base64.clone(),
        },
        Shown::Table {
            caption,
            headers,
            rows,
            n_rows,
            ..
        } => {
            let caption = if *n_rows > rows.len() {
                format!("{caption} (the first {MAX_ROWS} of {n_rows} rows)")
            } else {
                caption.clone()
            };
            Item::Table(Table {
                caption,
                headers: headers.clone(),
                rows: rows.clone(),
                folded: false,
            })
        }
    }
}

/// Place the notes and make "Additional analyses" when anything is left for it.
pub fn place(page: &mut Page, own: &Own) {
    let number = if page.baseline.is_some() { 8 } else { 7 };
    let mut extra = Block::new("additional", &format!("{number}. Additional analyses"));
    if !own.notes.preamble.is_empty() {
        extra.items.push(Item::Markdown {
            text: own.notes.preamble.clone(),
        });
    }
    extra.items.extend(own.items.iter().map(item));
    let mut taken = BTreeSet::new();
    for p in &own.notes.parts {
        if place_note(page, p, &mut taken).is_none() {
            extra.notes.push(note(p, 3, &mut taken));
        }
    }
    if !extra.items.is_empty() || !extra.notes.is_empty() {
        page.additional = Some(extra);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headings_match_without_their_number_or_case() {
        assert_eq!(key("4. Discovery"), "discovery");
        assert_eq!(key("## ignored"), "## ignored");
        assert_eq!(
            key("3.2 Fig. 4.2c: drag time T against v0"),
            key("fig. 4.2C:  drag time T against v0:")
        );
        assert_eq!(key("Growth rate"), "growth rate");
    }

    #[test]
    fn anchors_are_unique() {
        let mut t = BTreeSet::new();
        assert_eq!(anchor("μ_pp, again!", &mut t), "note-pp-again");
        assert_eq!(anchor("μ pp again", &mut t), "note-pp-again-2");
    }
}
