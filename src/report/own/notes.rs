//! The notes file cut into the parts its headings make. The file's highest heading level (ATX
//! headings, `#` to `######`, outside code fences) starts a part; deeper headings stay inside it.
//! Text before the first heading is the preamble. `sections::additional` places each part under
//! the section its heading names, or in "Additional analyses".

/// One part: its heading, its Markdown, and the level its heading had in the file.
#[derive(Debug, Clone, PartialEq)]
pub struct Part {
    pub heading: String,
    body: Vec<String>,
    top: usize,
}

/// The file cut into a preamble and parts, in the file's order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Notes {
    pub preamble: String,
    pub parts: Vec<Part>,
}

impl Part {
    /// The part's Markdown with its headings moved so that a heading one level below the part's
    /// is printed at `level + 1` (never deeper than `######`).
    pub fn body_at(&self, level: usize) -> String {
        let mut fence = None;
        let lines: Vec<String> = self
            .body
            .iter()
            .map(|l| match heading(l, &mut fence) {
                Some((n, text)) => {
                    format!("{} {text}", "#".repeat((n + level - self.top).min(6)))
                }
                None => l.clone(),
            })
            .collect();
        lines.join("\n").trim().to_string()
    }
}

/// The level and text of `line` when it is an ATX heading outside a code fence; tracks `fence`.
fn heading<'a>(line: &'a str, fence: &mut Option<(char, usize)>) -> Option<(usize, &'a str)> {
    let indent = line.len() - line.trim_start_matches(' ').len();
    let t = line.trim_start_matches(' ');
    if indent > 3 {
        return None;
    }
    if let Some(c) = t.chars().next().filter(|c| *c == '`' || *c == '~') {
        let n = t.chars().take_while(|x| *x == c).count();
        if n >= 3 {
            match *fence {
                None => *fence = Some((c, n)),
                Some((fc, fnum)) if fc == c && n >= fnum && t.trim_end().len() == n => {
                    *fence = None
                }
                _ => {}
            }
            return None;
        }
    }
    if fence.is_some() {
        return None;
    }
    let n = t.chars().take_while(|c| *c == '#').count();
    let rest = &t[n..];
    if !(1..=6).contains(&n) || !(rest.is_empty() || rest.starts_with([' ', '\t'])) {
        return None;
    }
    let text = rest.trim();
    let closed = text.trim_end_matches('#');
    let text = if closed.is_empty() || closed.ends_with([' ', '\t']) {
        closed.trim_end()
    } else {
        text
    };
    Some((n, text))
}

/// Cut `text` into its preamble and parts.
pub fn parse(text: &str) -> Notes {
    let mut fence = None;
    let levels: Vec<Option<(usize, &str)>> = text.lines().map(|l| heading(l, &mut fence)).collect();
    let Some(top) = levels.iter().flatten().map(|(n, _)| *n).min() else {
        return Notes {
            preamble: text.trim().to_string(),
            parts: Vec::new(),
        };
    };
    let mut notes = Notes::default();
    let mut preamble = Vec::new();
    for (line, h) in text.lines().zip(&levels) {
        match (h, notes.parts.last_mut()) {
            (Some((n, t)), _) if *n == top => notes.parts.push(Part {
                heading: t.to_string(),
                body: Vec::new(),
                top,
            }),
            (_, Some(p)) => p.body.push(line.to_string()),
            (_, None) => preamble.push(line),
        }
    }
    notes.preamble = preamble.join("\n").trim().to_string();
    notes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_highest_headings_cut_the_file_and_deeper_ones_move_with_it() {
        let n = parse(
            "Intro *text*.\n\n## Discovery ##\nWe agree.\n### Why\nbecause\n```\n## not a heading\n```\n## Growth rate\nx\n",
        );
        assert_eq!(n.preamble, "Intro *text*.");
        let heads: Vec<&str> = n.parts.iter().map(|p| p.heading.as_str()).collect();
        assert_eq!(heads, ["Discovery", "Growth rate"]);
        assert_eq!(
            n.parts[0].body_at(3),
            "We agree.\n#### Why\nbecause\n```\n## not a heading\n```"
        );
        assert_eq!(
            n.parts[0].body_at(6),
            "We agree.\n###### Why\nbecause\n```\n## not a heading\n```"
        );
    }

    #[test]
    fn a_file_without_headings_is_all_preamble() {
        let n = parse("  just words\n#hashtag is no heading\n");
        assert_eq!(n.preamble, "just words\n#hashtag is no heading");
        assert!(n.parts.is_empty());
        assert_eq!(parse(""), Notes::default());
    }
}
