//! The page's text (Markdown, as report.md prints it) rendered to HTML by a CommonMark parser, so
//! both pages show one source alike: `**x**` is bold in both, never literal asterisks in one.
//!
//! Every paragraph, table cell, caption and heading of `sections::Page` is Markdown inline text.
//! Raw HTML in it is shown as text (the page's own markup comes from the template alone), and a
//! text that Markdown would read as a block (a list, a heading, a rule) outside a paragraph is
//! shown as written, as a table cell on a forge shows it. The user's notes (`block`) are whole
//! Markdown documents: lists, headings and code blocks render, raw HTML is still text, and an
//! image becomes a link to it, so the page loads nothing from outside itself.

use pulldown_cmark::{html, Event, Options, Parser, Tag, TagEnd};

/// The Markdown extensions report.md relies on where it is read (a forge): strikethrough and
/// formulas between dollar signs (drawn as MathML here, `super::mathml`).
fn options() -> Options {
    Options::ENABLE_STRIKETHROUGH | Options::ENABLE_MATH
}

/// A formula as MathML, markup the page makes itself (the TeX's own characters are escaped).
fn math(ev: Event) -> Event {
    match ev {
        Event::InlineMath(t) => Event::InlineHtml(super::mathml::inline(&t).into()),
        Event::DisplayMath(t) => Event::Html(
            super::mathml::inline(&t)
                .replacen("<math>", "<math display=\"block\">", 1)
                .into(),
        ),
        ev => ev,
    }
}

/// The HTML of one piece of inline Markdown text (no enclosing `<p>`), escaped for HTML.
pub fn inline(text: &str) -> String {
    let mut events = Vec::new();
    for ev in Parser::new_ext(text, options()) {
        match ev {
            Event::Start(Tag::Paragraph) | Event::End(TagEnd::Paragraph) => {}
            Event::Start(
                Tag::Heading { .. }
                | Tag::List(_)
                | Tag::Item
                | Tag::BlockQuote(_)
                | Tag::CodeBlock(_)
                | Tag::HtmlBlock
                | Tag::Table(_)
                | Tag::FootnoteDefinition(_),
            )
            | Event::Rule => return escape(text),
            // raw HTML is text here: the page's markup is the template's alone
            Event::Html(s) | Event::InlineHtml(s) => events.push(Event::Text(s)),
            Event::SoftBreak | Event::HardBreak => events.push(Event::Text(" ".into())),
            ev => events.push(math(ev)),
        }
    }
    let mut out = String::with_capacity(text.len() + 16);
    html::push_html(&mut out, events.into_iter());
    out.trim_end_matches('\n').to_string()
}

/// The HTML of a Markdown document of the user's (blocks and all), escaped for HTML.
pub fn block(text: &str) -> String {
    let mut events = Vec::new();
    let mut in_image = false;
    for ev in Parser::new_ext(text, options() | Options::ENABLE_TABLES) {
        match ev {
            Event::Html(s) | Event::InlineHtml(s) => events.push(Event::Text(s)),
            Event::Start(Tag::Image {
                dest_url,
                title,
                id,
                ..
            }) => {
                in_image = true;
                events.push(Event::Start(Tag::Link {
                    link_type: pulldown_cmark::LinkType::Inline,
                    dest_url,
                    title,
                    id,
                }));
            }
            Event::End(TagEnd::Image) if in_image => {
                in_image = false;
                events.push(Event::End(TagEnd::Link));
            }
            ev => events.push(math(ev)),
        }
    }
    let mut out = String::with_capacity(text.len() + 64);
    html::push_html(&mut out, events.into_iter());
    out.trim_end_matches('\n').to_string()
}

/// `text` escaped for HTML, shown as written.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn emphasis_and_code_become_html_elements() {
        assert_eq!(
            inline("**saturating** (chosen)"),
            "<strong>saturating</strong> (chosen)"
        );
        assert_eq!(
            inline("held in `after`; *one* run"),
            "held in <code>after</code>; <em>one</em> run"
        );
    }

    #[test]
    fn raw_html_and_markup_characters_are_text() {
        assert_eq!(
            inline("<script>x</script> a < b & c"),
            "&lt;script&gt;x&lt;/script&gt; a &lt; b &amp; c"
        );
        // an identifier's underscores are no emphasis, as on a forge
        assert_eq!(inline("v_ref_mps = 0.06"), "v_ref_mps = 0.06");
    }

    #[test]
    fn formulas_between_dollar_signs_become_mathml() {
        assert_eq!(
            inline("with $T_e$ and ${data}/x"),
            "with <math><msub><mi>T</mi><mi>e</mi></msub></math> and ${data}/x"
        );
        assert!(block("$$a<b$$").contains("<math display=\"block\"><mrow><mi>a</mi><mo>&lt;</mo>"));
    }

    #[test]
    fn a_document_renders_its_blocks_and_loads_nothing() {
        assert_eq!(
            block("#### Why\n\n- one\n- <b>two</b>\n\n![plot](x.png)"),
            "<h4>Why</h4>\n<ul>\n<li>one</li>\n<li>&lt;b&gt;two&lt;/b&gt;</li>\n</ul>\n<p><a href=\"x.png\">plot</a></p>"
        );
    }

    #[test]
    fn block_syntax_outside_a_paragraph_is_shown_as_written() {
        assert_eq!(inline("- 3"), "- 3");
        assert_eq!(inline("# not a heading"), "# not a heading");
        assert_eq!(inline("1. first"), "1. first");
    }
}
