//! The table of contents: every section and subsection of the page with its anchor, in reading
//! order, built from the page itself so a heading cannot be missing from it or numbered twice.

use super::{Block, Note, Page};
use serde::Serialize;

/// One entry: the anchor (`id` of its `<section>`), the heading as printed, and its subsections.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Entry {
    pub id: String,
    pub title: String,
    pub children: Vec<Entry>,
}

/// The heading of section 3, whose subsections are the chapter's figures.
pub const CHAPTER: &str = "3. The chapter reproduced";
/// The heading of section 5, whose subsections are the audit's items.
pub const AUDIT: &str = "5. Equation audit";

fn of_notes(notes: &[Note]) -> impl Iterator<Item = Entry> + '_ {
    notes.iter().map(|n| Entry {
        id: n.id.clone(),
        title: n.heading.clone(),
        children: Vec::new(),
    })
}

fn leaf(b: &Block) -> Entry {
    Entry {
        id: b.id.clone(),
        title: b.heading.clone(),
        children: of_notes(&b.notes).collect(),
    }
}

/// The heading of audit item `i` (0-based), as the page prints it.
pub fn audit_heading(i: usize, title: &str) -> String {
    format!("5.{} {title}", i + 1)
}

/// The contents of `page`, sections in the order the templates print them.
pub fn of(page: &Page) -> Vec<Entry> {
    let mut out = vec![leaf(&page.summary), leaf(&page.data)];
    out.push(Entry {
        id: "chapter".into(),
        title: CHAPTER.into(),
        children: page
            .chapter
            .iter()
            .map(leaf)
            .chain(of_notes(&page.chapter_notes))
            .collect(),
    });
    out.push(leaf(&page.discovery));
    out.push(Entry {
        id: "audit".into(),
        title: AUDIT.into(),
        children: page
            .audit
            .iter()
            .enumerate()
            .map(|(i, a)| Entry {
                id: format!("audit-{}", a.id),
                title: audit_heading(i, &a.title),
                children: Vec::new(),
            })
            .chain(of_notes(&page.audit_notes))
            .collect(),
    });
    out.push(leaf(&page.provenance));
    out.extend(page.baseline.iter().map(leaf));
    out.extend(page.additional.iter().map(leaf));
    out
}

/// The number a heading starts with (`3.5.1` of `3.5.1 μ_pp …`), if any.
pub fn number(title: &str) -> Option<&str> {
    let n = title.split(' ').next()?.trim_end_matches('.');
    (!n.is_empty() && n.chars().all(|c| c.is_ascii_digit() || c == '.')).then_some(n)
}

/// Headings whose number repeats or does not follow the one before it, in reading order.
pub fn numbering_faults(toc: &[Entry]) -> Vec<String> {
    fn walk<'a>(es: &'a [Entry], flat: &mut Vec<&'a str>) {
        for e in es {
            flat.push(&e.title);
            walk(&e.children, flat);
        }
    }
    let mut flat = Vec::new();
    walk(toc, &mut flat);
    let key = |t: &str| -> Option<Vec<u32>> {
        number(t).map(|n| n.split('.').filter_map(|p| p.parse().ok()).collect())
    };
    let numbered: Vec<(&str, Vec<u32>)> = flat
        .iter()
        .filter_map(|t| key(t).map(|k| (*t, k)))
        .collect();
    numbered
        .windows(2)
        .filter(|w| w[0].1 >= w[1].1)
        .map(|w| format!("{:?} follows {:?}", w[1].0, w[0].0))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(title: &str, children: Vec<Entry>) -> Entry {
        Entry {
            id: title.into(),
            title: title.into(),
            children,
        }
    }

    #[test]
    fn a_repeated_or_backward_number_is_a_fault() {
        let ok = vec![
            e("1. Summary", vec![]),
            e("3. Chapter", vec![e("3.1 a", vec![]), e("3.1.1 b", vec![])]),
            e("3.2 c", vec![]),
            e("Additional analyses", vec![]),
        ];
        assert!(
            numbering_faults(&ok).is_empty(),
            "{:?}",
            numbering_faults(&ok)
        );
        let twice = vec![e(
            "3. Chapter",
            vec![e("3.6 a", vec![]), e("3.7 b", vec![]), e("3.6 c", vec![])],
        )];
        assert_eq!(
            numbering_faults(&twice),
            vec!["\"3.6 c\" follows \"3.7 b\""]
        );
    }

    #[test]
    fn numbers_are_read_from_the_heading() {
        assert_eq!(number("3.5.1 μ_pp and restitution"), Some("3.5.1"));
        assert_eq!(number("4. Discovery"), Some("4"));
        assert_eq!(number("Additional analyses"), None);
    }
}
