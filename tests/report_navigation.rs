//! The shipped report (reports/, kept current by tests/reports_current.rs) read as its users move
//! through it: a contents column listing every section and subsection with a working anchor,
//! sticky beside the text on a wide window and on top of it on a narrow one; headings numbered
//! once each, in order; and Provenance listing every stage's params as run.

use std::path::Path;

fn shipped(name: &str) -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("reports")
        .join(name);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// `(id, heading)` of every `<section id="…">` opened by an `<h2>`/`<h3>`/`<h4>` heading.
fn sections(html: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for part in html.split("<section id=\"").skip(1) {
        let (id, rest) = part.split_once('"').unwrap();
        let rest = rest.split_once('>').unwrap().1.trim_start();
        let Some(level) = ["<h2>", "<h3>", "<h4>"]
            .iter()
            .find(|h| rest.starts_with(**h))
        else {
            continue;
        };
        let close = level.replace('<', "</");
        let heading = &rest[level.len()..rest.find(&close).unwrap()];
        out.push((id.to_string(), heading.to_string()));
    }
    out
}

#[test]
fn the_contents_list_every_section_and_subsection_with_its_anchor() {
    let html = shipped("report.html");
    let nav_at = html.find("<nav class=\"toc\"").expect("a contents column");
    let nav = &html[nav_at..html[nav_at..].find("</nav>").unwrap() + nav_at];
    assert!(
        nav_at < html.find("<main>").unwrap(),
        "the contents come before the text"
    );
    let all = sections(&html);
    assert!(all.len() > 20, "{all:?}");
    for (id, heading) in &all {
        let link = format!("<a href=\"#{id}\">{heading}</a>");
        assert!(nav.contains(&link), "the contents lack {link}");
    }
    // every link of the contents lands on a section of the page
    for href in nav.split("href=\"#").skip(1) {
        let id = href.split('"').next().unwrap();
        assert!(all.iter().any(|(i, _)| i == id), "no section #{id}");
    }
    // subsections are nested under their section
    let chapter = &nav[nav.find("href=\"#chapter\"").unwrap()..];
    let chapter = &chapter[..chapter.find("</ol>").unwrap()];
    assert!(
        chapter.contains("<ol>") && chapter.contains("3.5.1 "),
        "{chapter}"
    );
    // no script: the stylesheet keeps it in view on a wide window and on top on a narrow one
    assert!(!html.contains("<script"));
    let css = &html[html.find("<style>").unwrap()..html.find("</style>").unwrap()];
    assert!(css.contains(".toc { position: sticky; top: 0;"), "{css}");
    let narrow = &css[css.find("@media (max-width:").expect("a narrow layout")..];
    assert!(narrow.contains(".page { display: block; }") && narrow.contains("position: static"));
}

#[test]
fn every_heading_is_numbered_once_and_in_order() {
    let md = shipped("report.md");
    let mut seen: Vec<(Vec<u32>, &str)> = Vec::new();
    for line in md
        .lines()
        .filter(|l| l.starts_with("## ") || l.starts_with("### "))
    {
        let title = line.trim_start_matches('#').trim();
        let number = title.split(' ').next().unwrap().trim_end_matches('.');
        let Ok(key) = number
            .split('.')
            .map(str::parse::<u32>)
            .collect::<Result<Vec<u32>, _>>()
        else {
            continue;
        };
        if let Some((last, before)) = seen.last() {
            assert!(*last < key, "{title:?} follows {before:?}");
        }
        seen.push((key, title));
    }
    assert!(seen.len() > 20, "{seen:?}");
}

#[test]
fn provenance_lists_every_stages_params_as_run() {
    let md = shipped("report.md");
    let at = md
        .find("*Params of every stage as run")
        .expect("a params table");
    let table = &md[at..md[at..].find("\n\n*").unwrap() + at];
    let toml = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("pipeline.toml"))
        .unwrap();
    let stages: Vec<&str> = toml
        .lines()
        .filter_map(|l| l.strip_prefix("[stages.")?.strip_suffix(']'))
        .collect();
    assert!(stages.len() >= 10, "{stages:?}");
    for s in &stages {
        assert!(
            table.contains(&format!("\n| {s} | ")),
            "no params of stage {s}:\n{table}"
        );
    }
    // as resolved: the project's params inherited, a kind's defaults filled in, in name order
    assert!(table.contains("| fit | min_frames | `20` |"));
    assert!(table.contains("| ingest | format | `auto` |"));
    assert!(table.contains("| report | source_date_epoch | unset |"));
    let names: Vec<&str> = table
        .lines()
        .skip(3)
        .map(|l| l.split(" | ").next().unwrap().trim_start_matches("| "))
        .collect();
    assert!(names.windows(2).all(|w| w[0] <= w[1]), "{names:?}");
}

#[test]
fn the_chapter_audit_and_provenance_sections_open_with_what_they_found() {
    let html = shipped("report.html");
    for (id, needles) in [
        ("fig-4-2b", &["slides for", "µm RMS"][..]),
        ("fig-4-3", &["hits the target at t = ", "µm RMS"][..]),
        ("fig-4-4a", &["μ_pp"][..]),
        ("fig-4-4bc", &["slower half", "faster"][..]),
        ("secondary", &["% of the velocity difference"][..]),
        (
            "audit",
            &["statements of the chapter do not hold as printed"][..],
        ),
        ("provenance", &["with seed", "input files"][..]),
    ] {
        let at = html
            .find(&format!("<section id=\"{id}\""))
            .unwrap_or_else(|| panic!("no section {id}"));
        let rest = &html[at..];
        let heading_end = rest.find("</h").unwrap();
        let after = rest[heading_end..].split_once('\n').unwrap().1;
        assert!(
            after.starts_with("<p class=\"lead\">"),
            "{id} opens with {:?}",
            &after[..after.len().min(80)]
        );
        let lead = &after[..after.find("</p>").unwrap()];
        assert!(lead.chars().any(|c| c.is_ascii_digit()), "{id}: {lead}");
        for n in needles {
            assert!(lead.contains(n), "{id}: {lead} lacks {n:?}");
        }
    }
}

#[test]
fn formulas_are_mathml_in_html_and_tex_in_markdown() {
    let html = shipped("report.html");
    let md = shipped("report.md");
    let audit = &html[html.find("<section id=\"audit\"").unwrap()
        ..html.find("<section id=\"provenance\"").unwrap()];
    // every item's printed and correct form that holds a formula shows it as native MathML
    let dds: Vec<&str> = audit
        .split("<dd>")
        .skip(1)
        .map(|d| &d[..d.find("</dd>").unwrap()])
        .collect();
    assert_eq!(dds.len(), 12, "six items, printed and holds");
    assert!(
        dds.iter().filter(|d| d.contains("<math>")).count() >= 8,
        "{dds:?}"
    );
    assert!(
        audit.contains("<mi>T</mi><mi>e</mi></msub>")
            || audit.contains("<msub><mi>T</mi><mi>e</mi></msub>")
    );
    assert!(!html.contains("<script"), "MathML needs no script");
    // no TeX is left to read outside the formulas
    let outside: String = html
        .split("<math")
        .map(|p| p.split_once("</math>").map_or(p, |x| x.1))
        .collect();
    assert!(
        !outside.contains("\\mu") && !outside.contains("_{"),
        "TeX shown as text"
    );
    // the Markdown keeps the TeX, which a forge renders
    assert!(md.contains(r"- Printed: $T = m/6\pi\mu R = 0.074$"));
}

#[test]
fn wide_tables_scroll_in_their_own_box_and_keep_their_words_whole() {
    let html = shipped("report.html");
    let css = &html[html.find("<style>").unwrap()..html.find("</style>").unwrap()];
    // no rule lets a cell break a word to fit (tests/browser.sh measures it at 800 px)
    for breaking in ["break-word", "break-all", "anywhere"] {
        assert!(!css.contains(breaking), "the style sheet has {breaking:?}");
    }
    assert!(css.contains(".table-box { overflow-x: auto;"), "{css}");
    // every table of the report's own sections sits in its box (the notes' tables scroll themselves)
    let tables = html.matches("<table").count();
    let boxed = html.matches("<div class=\"table-box\">\n<table").count();
    assert!(tables > 20, "{tables} tables");
    assert_eq!(boxed, tables, "tables outside a scrolling box");
    assert!(css.contains("section.note table { display: block; overflow-x: auto;"));
    // a table of many columns keeps a readable width and scrolls on a narrow window
    assert!(html.contains("<table class=\"wide\">") && css.contains("table.wide { min-width:"));
}
