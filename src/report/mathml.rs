//! Formulas as MathML, which current browsers draw natively (no script, no font to load).
//!
//! The page's text writes a formula between dollar signs in the TeX subset a forge renders in
//! Markdown (`$T_e = T(1 + ks^2)/ks^2$`); report.md keeps it so, report.html gets it as MathML
//! through `md_html`. The subset: letters (each an identifier, as TeX sets them), numbers,
//! operators, `^` and `_` with a character or a `{group}`, `\frac{a}{b}`, `\sqrt{x}`,
//! `\text{words}`, Greek letters and a few symbols by name (`\mu`, `\pi`, `\cdot`, `\approx`,
//! `\le`, …). Anything else is shown as written, as text.

/// The MathML of one TeX formula (inline).
pub fn inline(tex: &str) -> String {
    let chars: Vec<char> = tex.chars().collect();
    let mut p = Parser { chars, at: 0 };
    let body = p.row(None);
    format!("<math>{}</math>", wrap(body))
}

struct Parser {
    chars: Vec<char>,
    at: usize,
}

/// `items` as one MathML element (an `mrow` when there are several).
fn wrap(items: Vec<String>) -> String {
    if items.len() == 1 {
        items.into_iter().next().unwrap_or_default()
    } else {
        format!("<mrow>{}</mrow>", items.concat())
    }
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A command's symbol: (element, text).
fn symbol(name: &str) -> Option<(&'static str, &'static str)> {
    Some(match name {
        "alpha" => ("mi", "α"),
        "beta" => ("mi", "β"),
        "gamma" => ("mi", "γ"),
        "delta" => ("mi", "δ"),
        "Delta" => ("mi", "Δ"),
        "eta" => ("mi", "η"),
        "theta" => ("mi", "θ"),
        "lambda" => ("mi", "λ"),
        "mu" => ("mi", "μ"),
        "nu" => ("mi", "ν"),
        "pi" => ("mi", "π"),
        "rho" => ("mi", "ρ"),
        "sigma" => ("mi", "σ"),
        "tau" => ("mi", "τ"),
        "phi" => ("mi", "φ"),
        "omega" => ("mi", "ω"),
        "cdot" => ("mo", "·"),
        "times" => ("mo", "×"),
        "approx" => ("mo", "≈"),
        "le" | "leq" => ("mo", "≤"),
        "ge" | "geq" => ("mo", "≥"),
        "ne" | "neq" => ("mo", "≠"),
        "pm" => ("mo", "±"),
        "to" | "rightarrow" => ("mo", "→"),
        "infty" => ("mi", "∞"),
        "ldots" | "dots" => ("mo", "…"),
        _ => return None,
    })
}

impl Parser {
    fn peek(&self) -> Option<char> {
        self.chars.get(self.at).copied()
    }

    /// Items up to `close` (consumed) or the end.
    fn row(&mut self, close: Option<char>) -> Vec<String> {
        let mut items = Vec::new();
        while let Some(c) = self.peek() {
            if Some(c) == close {
                self.at += 1;
                break;
            }
            let Some(mut base) = self.atom() else {
                continue;
            };
            // a sign after an operator or an opening (`a = -v`, `(-x`) is unary, set tight
            if base == "<mo>−</mo>" && items.last().is_none_or(|p: &String| p.starts_with("<mo"))
            {
                base = "<mo form=\"prefix\">−</mo>".into();
            }
            items.push(self.scripts(base));
        }
        items
    }

    /// `base` with the `^`/`_` scripts that follow it.
    fn scripts(&mut self, base: String) -> String {
        let (mut sub, mut sup) = (None, None);
        loop {
            match self.peek() {
                Some('_') if sub.is_none() => {
                    self.at += 1;
                    sub = Some(self.argument());
                }
                Some('^') if sup.is_none() => {
                    self.at += 1;
                    sup = Some(self.argument());
                }
                _ => break,
            }
        }
        match (sub, sup) {
            (None, None) => base,
            (Some(b), None) => format!("<msub>{base}{b}</msub>"),
            (None, Some(p)) => format!("<msup>{base}{p}</msup>"),
            (Some(b), Some(p)) => format!("<msubsup>{base}{b}{p}</msubsup>"),
        }
    }

    /// A `{group}` or a single atom.
    fn argument(&mut self) -> String {
        while self.peek() == Some(' ') {
            self.at += 1;
        }
        if self.peek() == Some('{') {
            self.at += 1;
            return wrap(self.row(Some('}')));
        }
        self.atom().unwrap_or_else(|| "<mrow></mrow>".into())
    }

    /// One element, or None for what shows nothing (a space).
    fn atom(&mut self) -> Option<String> {
        let c = self.peek()?;
        self.at += 1;
        Some(match c {
            ' ' => return None,
            '{' => wrap(self.row(Some('}'))),
            '\\' => self.command(),
            c if c.is_ascii_digit() || c == '.' => {
                let mut n = c.to_string();
                while let Some(d) = self.peek().filter(|d| d.is_ascii_digit() || *d == '.') {
                    n.push(d);
                    self.at += 1;
                }
                format!("<mn>{n}</mn>")
            }
            c if c.is_alphabetic() => format!("<mi>{}</mi>", esc(&c.to_string())),
            '-' => "<mo>−</mo>".into(),
            '\'' => "<mo>′</mo>".into(),
            c => format!("<mo>{}</mo>", esc(&c.to_string())),
        })
    }

    /// After a backslash: a command, or an escaped character.
    fn command(&mut self) -> String {
        let mut name = String::new();
        while let Some(c) = self.peek().filter(|c| c.is_ascii_alphabetic()) {
            name.push(c);
            self.at += 1;
        }
        if name.is_empty() {
            // `\,`, `\;`, `\ `: a space; `\{`, `\|`: the character
            let c = self.peek().unwrap_or(' ');
            self.at += 1;
            return match c {
                ',' | ';' | ' ' | '!' => "<mspace width=\"0.2em\"/>".into(),
                c => format!("<mo>{}</mo>", esc(&c.to_string())),
            };
        }
        match name.as_str() {
            // an absolute value's bars, set tight against what they enclose
            "lvert" | "rvert" | "vert" => "<mo lspace=\"0\" rspace=\"0\">|</mo>".into(),
            "frac" => {
                let (a, b) = (self.argument(), self.argument());
                format!("<mfrac>{a}{b}</mfrac>")
            }
            "sqrt" => format!("<msqrt>{}</msqrt>", self.argument()),
            "text" | "mathrm" => {
                let mut t = String::new();
                if self.peek() == Some('{') {
                    self.at += 1;
                    while let Some(c) = self.peek() {
                        self.at += 1;
                        if c == '}' {
                            break;
                        }
                        t.push(c);
                    }
                }
                format!("<mtext>{}</mtext>", esc(&t))
            }
            "left" | "right" => self.atom().unwrap_or_default(),
            n => match symbol(n) {
                Some((el, s)) => format!("<{el}>{s}</{el}>"),
                None => format!("<mtext>\\{}</mtext>", esc(n)),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::inline;

    #[test]
    fn scripts_fractions_and_symbols() {
        assert_eq!(
            inline("T_e = T(1 + ks^2)/ks^2"),
            "<math><mrow><msub><mi>T</mi><mi>e</mi></msub><mo>=</mo><mi>T</mi><mo>(</mo><mn>1</mn><mo>+</mo><mi>k</mi><msup><mi>s</mi><mn>2</mn></msup><mo>)</mo><mo>/</mo><mi>k</mi><msup><mi>s</mi><mn>2</mn></msup></mrow></math>"
        );
        assert_eq!(
            inline("\\frac{m}{6\\pi\\eta R}"),
            "<math><mfrac><mi>m</mi><mrow><mn>6</mn><mi>π</mi><mi>η</mi><mi>R</mi></mrow></mfrac></math>"
        );
        assert_eq!(
            inline("e^{-(t - t_1)/T} < x_{z1}^{(2)}"),
            "<math><mrow><msup><mi>e</mi><mrow><mo form=\"prefix\">−</mo><mo>(</mo><mi>t</mi><mo>−</mo><msub><mi>t</mi><mn>1</mn></msub><mo>)</mo><mo>/</mo><mi>T</mi></mrow></msup><mo>&lt;</mo><msubsup><mi>x</mi><mrow><mi>z</mi><mn>1</mn></mrow><mrow><mo>(</mo><mn>2</mn><mo>)</mo></mrow></msubsup></mrow></math>"
        );
    }

    #[test]
    fn a_sign_after_an_operator_is_unary_and_bars_are_tight() {
        assert_eq!(
            inline("a = -v - b"),
            "<math><mrow><mi>a</mi><mo>=</mo><mo form=\"prefix\">−</mo><mi>v</mi><mo>−</mo><mi>b</mi></mrow></math>"
        );
        assert_eq!(
            inline("\\lvert v\\rvert"),
            "<math><mrow><mo lspace=\"0\" rspace=\"0\">|</mo><mi>v</mi><mo lspace=\"0\" rspace=\"0\">|</mo></mrow></math>"
        );
    }

    #[test]
    fn unknown_commands_and_markup_are_text() {
        assert_eq!(
            inline("\\foo <b>"),
            "<math><mrow><mtext>\\foo</mtext><mo>&lt;</mo><mi>b</mi><mo>&gt;</mo></mrow></math>"
        );
        assert_eq!(
            inline("\\text{if } x"),
            "<math><mrow><mtext>if </mtext><mi>x</mi></mrow></math>"
        );
    }
}
