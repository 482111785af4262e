//! The HTML page (report.html): one self-contained file — inline CSS and inline SVG figures, no
//! external resource, no script.

use super::sections::Page;
use minijinja::{context, AutoEscape, Environment};

const TEMPLATE: &str = include_str!("templates/report.html.jinja");
const CSS: &str = include_str!("templates/style.css");

/// An SVG ready to inline in HTML: no XML declaration, no namespace URL (the HTML parser puts `<svg>`
/// in the SVG namespace itself), so the page names no external address at all.
pub fn inline_svg(svg: &str) -> String {
    let body = match svg.find("<svg") {
        Some(i) => &svg[i..],
        None => svg,
    };
    body.replacen(" xmlns=\"http://www.w3.org/2000/svg\"", "", 1)
        .replacen(" xmlns:xlink=\"http://www.w3.org/1999/xlink\"", "", 1)
}

/// Render report.html.
pub fn render(page: &Page) -> Result<String, String> {
    let mut page = page.clone();
    let all = std::iter::once(&mut page.summary)
        .chain(std::iter::once(&mut page.data))
        .chain(page.chapter.iter_mut())
        .chain(std::iter::once(&mut page.discovery))
        .chain(std::iter::once(&mut page.provenance))
        .chain(page.baseline.iter_mut());
    for b in all {
        for f in b.figures_mut() {
            f.svg = inline_svg(&f.svg);
        }
    }
    let mut env = Environment::new();
    let syntax = minijinja::syntax::SyntaxConfig::builder()
        .trim_blocks(true)
        .lstrip_blocks(true)
        .build()
        .map_err(|e| format!("template syntax: {e}"))?;
    env.set_syntax(syntax);
    env.set_auto_escape_callback(|_| AutoEscape::Html);
    // every text of the page is Markdown (as report.md prints it): rendered, never shown raw
    env.add_filter("md", |s: String| {
        minijinja::Value::from_safe_string(super::md_html::inline(&s))
    });
    // the user's notes: whole Markdown documents
    env.add_filter("block", |s: String| {
        minijinja::Value::from_safe_string(super::md_html::block(&s))
    });
    env.add_template("report.html", TEMPLATE)
        .map_err(|e| format!("html template: {e}"))?;
    env.get_template("report.html")
        .and_then(|t| t.render(context! { page => minijinja::value::Serde(&page), css => CSS }))
        .map(|s| if s.ends_with('\n') { s } else { s + "\n" })
        .map_err(|e| format!("rendering report.html failed: {e}"))
}
