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

/// The points of one part of a figure, with the axes they are read on: the chart itself
/// (`name` empty) or a strip under it (`residuals`).
#[derive(Debug, Default)]
struct Group {
    name: String,
    x_desc: String,
    y_desc: String,
    marks: Vec<Mark>,
}

#[derive(Debug, Default)]
struct Open {
    /// The chart's group first, then the named parts in the order they were opened.
    groups: Vec<Group>,
    /// The group points go to.
    current: usize,
    labels: Vec<String>,
    /// The run every point belongs to, in a figure of one run (Figs. 4.2b, 4.3c–d).
    run: String,
}

impl Open {
    /// Make the group `name` current (opened with these axes if new).
    fn switch(&mut self, name: &str, x_desc: &str, y_desc: &str) {
        if self.groups.is_empty() {
            self.groups.push(Group::default());
        }
        let i = match self.groups.iter().position(|g| g.name == name) {
            Some(i) => i,
            None => {
                self.groups.push(Group {
                    name: name.into(),
                    ..Group::default()
                });
                self.groups.len() - 1
            }
        };
        self.groups[i].x_desc = x_desc.into();
        self.groups[i].y_desc = y_desc.into();
        self.current = i;
    }
}

thread_local! {
    static OPEN: RefCell<Option<Open>> = const { RefCell::new(None) };
}

/// Start collecting the points of a figure.
pub fn open() {
    OPEN.with(|o| *o.borrow_mut() = Some(Open::default()));
}

/// The axes' descriptions of the chart being drawn (the CSV's column names); its points follow.
pub fn axes(x_desc: &str, y_desc: &str) {
    part("", x_desc, y_desc);
}

/// A part of the figure with axes of its own (a residual strip: `name` "residuals"); the points
/// that follow are its own, written to `<figure>_<name>.csv`.
pub fn part(name: &str, x_desc: &str, y_desc: &str) {
    OPEN.with(|o| {
        if let Some(o) = o.borrow_mut().as_mut() {
            o.switch(name, x_desc, y_desc);
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
            if o.groups.is_empty() {
                o.groups.push(Group::default());
            }
            let i = o.current;
            o.groups[i].marks.push(m);
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
        o.borrow().as_ref().map_or(Vec::new(), |o| {
            o.groups
                .iter()
                .flat_map(|g| g.marks.iter().map(|m| m.px))
                .collect()
        })
    })
}

/// Stop collecting; `svg` with the points appended as titled, invisible circles, one group per
/// part of the figure.
pub fn close(svg: String) -> String {
    let Some(open) = OPEN.with(|o| o.borrow_mut().take()) else {
        return svg;
    };
    let groups: String = open
        .groups
        .iter()
        .filter(|g| !g.marks.is_empty())
        .map(group_svg)
        .collect();
    if groups.is_empty() {
        return svg;
    }
    match svg.rfind("</svg>") {
        Some(i) => format!("{}{groups}{}", &svg[..i], &svg[i..]),
        None => svg,
    }
}

/// One part's points as an SVG group of titled circles.
fn group_svg(grp: &Group) -> String {
    let (xd, yd) = (name_or(&grp.x_desc, "x"), name_or(&grp.y_desc, "y"));
    let part = if grp.name.is_empty() {
        String::new()
    } else {
        format!(" data-part=\"{}\"", esc(&grp.name))
    };
    let mut g = format!(
        "<g class=\"data-points\"{part} data-x=\"{}\" data-y=\"{}\" fill=\"#000000\" fill-opacity=\"0\" stroke=\"none\">\n",
        esc(xd),
        esc(yd)
    );
    for m in &grp.marks {
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
    g
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

/// The chart's data points as CSV (series, run, x, y; the header names the axes), or None when
/// the chart has no data points.
pub fn csv_of(svg: &str) -> Option<String> {
    csv_parts(svg).remove("")
}

/// Every part's data points as CSV, by part name ("" for the chart itself, `residuals` for a
/// residual strip).
pub fn csv_parts(svg: &str) -> std::collections::BTreeMap<String, String> {
    let mut out = std::collections::BTreeMap::new();
    let mut rest = svg;
    while let Some(start) = rest.find("<g class=\"data-points\"") {
        let g = &rest[start..];
        let Some(head_end) = g.find('>') else { break };
        let Some(end) = g.find("</g>") else { break };
        let head = &g[..head_end];
        if let (Some(xd), Some(yd)) = (attr(head, "data-x"), attr(head, "data-y")) {
            let name = attr(head, "data-part").map(unesc).unwrap_or_default();
            let mut csv = format!("series,run,{},{}\n", field(&unesc(xd)), field(&unesc(yd)));
            for tag in g[head_end..end].split("<circle ").skip(1) {
                let get = |n: &str| attr(&format!(" {tag}"), n).map(unesc).unwrap_or_default();
                csv.push_str(&format!(
                    "{},{},{},{}\n",
                    field(&get("data-series")),
                    field(&get("data-run")),
                    get("data-vx"),
                    get("data-vy")
                ));
            }
            out.insert(name, csv);
        }
        rest = &g[end..];
    }
    out
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

    #[test]
    fn a_strip_keeps_its_points_apart_with_its_own_axes() {
        open();
        figure_run("r1");
        part("residuals", "time t (ms)", "data − model (µm)");
        let mark = |x: f64, y: f64, series: &str| Mark {
            px: (x as i32, y as i32),
            series: series.into(),
            run: String::new(),
            x,
            y,
        };
        add(mark(1.0, -2.5, "sliding"));
        axes("time t (ms)", "z (mm)");
        add(mark(1.0, 0.5, "observed"));
        let svg = close("<svg>\n</svg>\n".into());
        assert!(
            svg.contains(
                "<title>run r1, sliding: time t (ms) = 1; data − model (µm) = -2.5</title>"
            ),
            "{svg}"
        );
        let parts = csv_parts(&svg);
        assert_eq!(parts.len(), 2, "{parts:?}");
        assert_eq!(
            parts[""],
            "series,run,time t (ms),z (mm)\nobserved,r1,1,0.5\n"
        );
        assert_eq!(
            parts["residuals"],
            "series,run,time t (ms),data − model (µm)\nsliding,r1,1,-2.5\n"
        );
    }
}
