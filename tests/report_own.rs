//! The user's own sections through the built `groove` binary: a notes file and a `command`
//! stage's figure and table bound to the `report` stage appear where the notes' headings say and
//! in "Additional analyses"; editing the notes reruns the report alone; bad input exits 2 naming
//! the file and the fix, and the last good report stays.

#[path = "support/project.rs"]
mod project;

use project::Project;

/// A figures stage with nothing to draw, the user's `extra` stage (a table, an SVG plot and its
/// caption from their own input) and the report reading both and the notes.
const PIPELINE: &str = r#"[project]
seed = 7
data = "data"
reports = "reports"

[stages.figures]
kind = "command"
cmd = "echo figures >> trace.txt; mkdir -p {out.figures}"
outputs = { figures = "${reports}/figures" }

[stages.extra]
kind = "command"
cmd = '''echo extra >> trace.txt; mkdir -p {out.plots}; cp {in.table} {out.plots}/growth.csv; printf '<svg xmlns="http://www.w3.org/2000/svg" width="40" height="20"><title>growth</title><circle cx="10" cy="10" r="5"/></svg>' > {out.plots}/growth.svg; echo 'Growth of the *bump* with time.' > {out.plots}/growth.md'''
inputs = { table = "mine/growth.csv" }
outputs = { plots = "${reports}/additional" }

[stages.report]
kind = "report"
inputs = { figures = "figures:figures", notes = { path = "notes.md", optional = true }, additional = "extra:plots" }
outputs = { html = "${reports}/report.html", md = "${reports}/report.md" }
"#;

const NOTES: &str = "We looked at the bump by hand.\n\n# Discovery\n\nWe read the *drift* as a tilt.\n\n## Why a tilt\n\nBecause it grows with x.\n\n# Growth rate\n\nThe bump grows by 3 % per ms.\n";

fn project() -> Project {
    let p = Project::new(PIPELINE);
    p.write("mine/growth.csv", "t_ms,height_um\n1,2.5\n2,\"3,1\"\n");
    p.write("notes.md", NOTES);
    p
}

fn err(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn notes_and_a_command_stages_figure_and_table_appear_where_they_belong() {
    let p = project();
    p.ok(&["run"]);
    let md = p.read("reports/report.md");
    let html = p.read("reports/report.html");
    // the note headed "Discovery" closes section 4, its own subheading one level below it
    let discovery = md.find("## 4. Discovery").unwrap();
    let note = md
        .find("### Discovery\n\nWe read the *drift* as a tilt.")
        .unwrap();
    let audit = md.find("## 5. Equation audit").unwrap();
    assert!(discovery < note && note < audit, "{md}");
    assert!(md.contains("#### Why a tilt\n\nBecause it grows with x."));
    // the rest makes the last section: the preamble, the figure with its caption, the table, the
    // unmatched note
    let extra = &md[md.find("## 7. Additional analyses").expect("section 7")..];
    for needle in [
        "We looked at the bump by hand.",
        "![Growth of the *bump* with time.](additional/growth.svg)",
        "| t_ms | height_um |",
        "| 2 | 3,1 |",
        "### Growth rate\n\nThe bump grows by 3 % per ms.",
    ] {
        assert!(
            extra.contains(needle),
            "section 7 lacks {needle:?}:\n{extra}"
        );
    }
    // the HTML page carries the figure in itself and lists the notes in its contents
    assert!(html.contains("<img src=\"data:image/svg+xml;base64,PHN2ZyB4bWxucz0i"));
    assert!(html.contains("<figcaption>Growth of the <em>bump</em> with time.</figcaption>"));
    assert!(html.contains("<a href=\"#note-discovery\">Discovery</a>"));
    assert!(html.contains("<a href=\"#additional\">7. Additional analyses</a>"));
    assert!(html.contains("<h4>Why a tilt</h4>"));
    assert!(!html.contains("http://") && !html.contains("<script"));
    // same inputs, same bytes: a second project renders the same pages
    let q = project();
    q.ok(&["run"]);
    assert_eq!(q.read("reports/report.html"), html);
}

#[test]
fn editing_the_notes_reruns_the_report_alone() {
    let p = project();
    p.ok(&["run"]);
    assert_eq!(p.take_trace(), ["extra", "figures"]);
    let before = p.read("reports/report.md");
    p.write("notes.md", &NOTES.replace("3 %", "4 %"));
    let said = p.ok(&["run"]);
    assert!(p.take_trace().is_empty(), "only the report should run");
    assert!(said.contains("report"), "{said}");
    let after = p.read("reports/report.md");
    assert_ne!(before, after);
    assert!(after.contains("The bump grows by 4 % per ms."));
    // an unchanged project runs nothing at all
    let status = p.ok(&["status"]);
    assert!(status.contains("3 fresh, 0 stale"), "{status}");
}

#[test]
fn bad_notes_or_figures_exit_2_naming_the_file_and_keep_the_last_report() {
    let p = project();
    p.ok(&["run"]);
    let good = p.read("reports/report.html");
    std::fs::write(p.path("notes.md"), b"# Discovery\n\xff\xfe\n").unwrap();
    let out = p.groove(&["run"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        err(&out).contains(
            "the notes file (input `notes` of the report stage) is not UTF-8 text (line 2, byte 12); save it as UTF-8"
        ),
        "{}",
        err(&out)
    );
    assert_eq!(p.read("reports/report.html"), good, "the last report stays");

    // a notes file bound without `optional` that is not there
    p.write("notes.md", NOTES);
    p.write(
        "pipeline.toml",
        &PIPELINE.replace(
            "notes = { path = \"notes.md\", optional = true }",
            "notes = \"my-notes.md\"",
        ),
    );
    let out = p.groove(&["run"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        err(&out).contains("my-notes.md") && err(&out).contains("does not exist; create it"),
        "{}",
        err(&out)
    );

    // a file the page cannot show in the user's figures
    p.write(
        "pipeline.toml",
        &PIPELINE.replace("growth.md'''", "growth.md; echo x > {out.plots}/fit.pdf'''"),
    );
    let out = p.groove(&["run"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        err(&out)
            .contains("`fit.pdf` is neither a figure (.svg, .png), a table (.csv) nor a caption"),
        "{}",
        err(&out)
    );
    assert_eq!(p.read("reports/report.html"), good);
}
