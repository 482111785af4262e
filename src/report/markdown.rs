//! The Markdown page (report.md): the page data through the Markdown template; figures referenced as
//! `figures/<name>.svg` so it renders on GitHub beside the figure files.

use super::sections::Page;
use minijinja::{context, AutoEscape, Environment};

const TEMPLATE: &str = include_str!("templates/report.md.jinja");

/// A Markdown table cell: pipes escaped, line breaks folded.
fn cell(s: String) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

/// Render report.md.
pub fn render(page: &Page) -> Result<String, String> {
    let mut env = Environment::new();
    let syntax = minijinja::syntax::SyntaxConfig::builder()
        .trim_blocks(true)
        .lstrip_blocks(true)
        .build()
        .map_err(|e| format!("template syntax: {e}"))?;
    env.set_syntax(syntax);
    env.set_auto_escape_callback(|_| AutoEscape::None);
    env.add_filter("cell", cell);
    env.add_filter("hashes", |n: usize| "#".repeat(n));
    env.add_template("report.md", TEMPLATE)
        .map_err(|e| format!("markdown template: {e}"))?;
    let out = env
        .get_template("report.md")
        .and_then(|t| t.render(context! { page => minijinja::value::Serde(page) }))
        .map_err(|e| format!("rendering report.md failed: {e}"))?;
    Ok(tidy(&out))
}

/// Collapse runs of blank lines to one and end with exactly one newline.
fn tidy(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut blank = 0;
    for line in s.lines() {
        let line = line.trim_end();
        if line.is_empty() {
            blank += 1;
            if blank > 1 {
                continue;
            }
        } else {
            blank = 0;
        }
        out.push_str(line);
        out.push('\n');
    }
    while out.ends_with("\n\n") {
        out.pop();
    }
    out
}
