//! The data points of a figure as it is drawn: each gets an SVG `<title>` (its run and values, shown
//! on hover, no script) and a row of the figure's CSV, and the legend is placed where no point is.
//!
//! `common::render` opens a collection for the figure being drawn (one per thread: a figure is
//! drawn on one thread from start to end); the scatter helpers add each point with its pixel
//! position; `render` closes it and appends the points as invisible circles with titles, whose
//! attributes `csv_of` reads back into the CSV written beside the SVG.

use std::cell::RefCell;

/// One drawn data point.
#[derive(Debug, Clone, PartialEq)]
pub struct Mark {
    /// Pixel position on the canvas.
    pub px: (i32, i32),
    /// The legend label of its series ("" when it has none).
    pub series: String,
    /// The run it belongs to ("" when not one run's).
    pub run: String,
    pub x: f64,
    pub y: f64,
}

#[derive(Debug, Default)]
struct Open {
    x_desc: String,
    y_desc: String,
    marks: Vec<Mark>,
    labels: Vec<String>,
    /// The run every point belongs to, in a figure of one run (Figs. 4.2b, 4.3c–d).
    run: String,
}

thread_local! {
    static OPEN: RefCell<Option<Open>> = const { RefCell::new(None) };
}

/// Start collecting the points of a figure.
pub fn open() {
    OPEN.with(|o| *o.borrow_mut() = Some(Open::default()));
}

/// The axes' descriptions of the figure being drawn (the CSV's column names).
pub fn axes(x_desc: &str, y_desc: &str) {
    OPEN.with(|o| {
        if let Some(o) = o.borrow_mut().as_mut() {
            o.x_desc = x_desc.into();
            o.y_desc = y_desc.into();
        }
    });
}

/// Add one drawn point (of the figure's run when it names none).
pub fn add(mut m: Mark) {
    OPEN.with(|o| {
        if let Some(o) = o.borrow_mut().as_mut() {
            if m.run.is_empty() {
                m.run.clone_from(&o.run);
            }
            o.marks.push(m);
        }
    });
}

/// The run every point of the figure being drawn belongs to (a figure of one run).
pub fn figure_run(run: &str) {
    OPEN.with(|o| {
        if let Some(o) = o.borrow_mut().as_mut() {
            o.run = run.into();
        }
    });
}

/// A series label of the legend, in drawing order.
pub fn label(text: &str) {
    OPEN.with(|o| {
        if let Some(o) = o.borrow_mut().as_mut() {
            o.labels.push(text.into());
        }
    });
}

/// The legend's labels so far.
pub fn labels() -> Vec<String> {
    OPEN.with(|o| o.borrow().as_ref().map_or(Vec::new(), |o| o.labels.clone()))
}

/// The points drawn so far in the figure being drawn.
pub fn drawn() -> Vec<(i32, i32)> {
    OPEN.with(|o| {
        o.borrow()
            .as_ref()
            .map_or(Vec::new(), |o| o.marks.iter().map(|m| m.px).collect())
    })
}

/// Stop collecting; `svg` with the points appended as titled, invisible circles.
pub fn close(svg: String) -> String {
    let Some(open) = OPEN.with(|o| o.borrow_mut().take()) else {
        return svg;
    };
    if open.marks.is_empty() {
        return svg;
    }
    let (xd, yd) = (name_or(&open.x_desc, "x"), name_or(&open.y_desc, "y"));
    let mut g = format!(
        "<g class=\"data-points\" data-x=\"{}\" data-y=\"{}\" fill=\"#000000\" fill-opacity=\"0\" stroke=\"none\">\n",
        esc(xd),
        esc(yd)
    );
    for m in &open.marks {
        let (x, y) = (num(m.x), num(m.y));
        let mut title = String::new();
        if !m.run.is_empty() {
            title.push_str(&format!("run {}", m.run));
        }
        if !m.series.is_empty() {
            let sep = if title.is_empty() { "" } else { ", " };
            title.push_str(&format!("{sep}{}", m.series));
        }
        let sep = if title.is_empty() { "" } else { ": " };
        title.push_str(&format!("{sep}{xd} = {x}; {yd} = {y}"));
        g.push_str(&format!(
            "<circle class=\"pt\" cx=\"{}\" cy=\"{}\" r=\"6\" data-series=\"{}\" data-run=\"{}\" data-vx=\"{x}\" data-vy=\"{y}\"><title>{}</title></circle>\n",
            m.px.0,
            m.px.1,
            esc(&m.series),
            esc(&m.run),
            esc(&title)
        ));
    }
    g.push_str("</g>\n");
    match svg.rfind("</svg>") {
        Some(i) => format!("{}{g}{}", &svg[..i], &svg[i..]),
        None => svg,
    }
}

fn name_or<'a>(s: &'a str, default: &'a str) -> &'a str {
    if s.is_empty() {
        default
    } else {
        s
    }
}

/// A value as the title and CSV print it: shortest round-trip, 6 significant digits at most.
fn num(x: f64) -> String {
    if !x.is_finite() {
        return String::new();
    }
    let s = format!("{x:.5e}");
    let v: f64 = s.parse().unwrap_or(x);
    format!("{v}")
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn unesc(s: &str) -> String {
    s.replace("&quot;", "\"")
        .replace("&gt;", ">")
        .replace("&lt;", "<")
        .replace("&amp;", "&")
}

/// The value of attribute `name` in the tag text `tag`.
fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let i = tag.find(&key)? + key.len();
    let end = tag[i..].find('"')? + i;
    Some(&tag[i..end])
}

/// A CSV field, quoted when it holds a comma, a quote or a line break.
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The figure's data points as CSV (series, run, x, y; the header names the axes), or None when
/// the figure has no data points.
pub fn csv_of(svg: &str) -> Option<String> {
    let start = svg.find("<g class=\"data-points\"")?;
    let head_end = svg[start..].find('>')? + start;
    let head = &svg[start..head_end];
    let (xd, yd) = (unesc(attr(head, "data-x")?), unesc(attr(head, "data-y")?));
    let mut out = format!("series,run,{},{}\n", field(&xd), field(&yd));
    let end = svg[start..].find("</g>")? + start;
    for tag in svg[head_end..end].split("<circle ").skip(1) {
        let get = |n: &str| attr(&format!(" {tag}"), n).map(unesc).unwrap_or_default();
        out.push_str(&format!(
            "{},{},{},{}\n",
            field(&get("data-series")),
            field(&get("data-run")),
            get("data-vx"),
            get("data-vy")
        ));
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_get_titles_and_come_back_as_csv() {
        open();
        axes("initial speed |v0| (m/s)", "T, fitted (s)");
        add(Mark {
            px: (10, 20),
            series: "316: fitted T".into(),
            run: "s316_a".into(),
            x: 0.025,
            y: 0.079512345,
        });
        let svg = close("<svg>\n</svg>\n".into());
        assert!(
            svg.contains("<title>run s316_a, 316: fitted T: initial speed |v0| (m/s) = 0.025; T, fitted (s) = 0.0795123</title>"),
            "{svg}"
        );
        assert_eq!(
            csv_of(&svg).unwrap(),
            "series,run,initial speed |v0| (m/s),\"T, fitted (s)\"\n316: fitted T,s316_a,0.025,0.0795123\n"
        );
        // nothing collected outside a figure, and no CSV without points
        add(Mark {
            px: (0, 0),
            series: String::new(),
            run: String::new(),
            x: 1.0,
            y: 1.0,
        });
        assert_eq!(close("<svg></svg>".into()), "<svg></svg>");
        assert_eq!(csv_of("<svg></svg>"), None);
    }
}
