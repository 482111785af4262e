//! Colours, marker shapes and font sizes shared by every figure: 316 is always red, 440c always blue.

use plotters::style::RGBColor;

/// Figure size in SVG pixels (readable when printed at half a page width).
pub const FIG_W: u32 = 760;
pub const FIG_H: u32 = 500;
pub const FONT: &str = "sans-serif";
pub const CAPTION_PX: u32 = 26;
pub const LABEL_PX: u32 = 22;
pub const TICK_PX: u32 = 19;
pub const LEGEND_PX: u32 = 18;
/// Room right of the plot for the last tick label of the x axis, half of it past the last tick.
pub const MARGIN_RIGHT: u32 = 34;

pub const BLACK: RGBColor = RGBColor(20, 20, 20);
pub const GREY: RGBColor = RGBColor(120, 120, 120);
pub const LIGHT_GREY: RGBColor = RGBColor(225, 225, 225);
/// Sliding and rolling phases (the chapter marks them green and red; rolling is magenta here so it
/// is never mistaken for 316).
pub const SLIDING: RGBColor = RGBColor(0, 140, 70);
pub const ROLLING: RGBColor = RGBColor(200, 30, 140);
/// Before / after a discovered term.
pub const BEFORE: RGBColor = RGBColor(120, 120, 120);
pub const AFTER: RGBColor = RGBColor(0, 140, 70);
/// A curve drawn under the physics discovery accepted, beside the baseline's (black).
pub const ACCEPTED: RGBColor = RGBColor(230, 120, 0);

const M316_ROLLING: RGBColor = RGBColor(205, 35, 35);
const M316_CONTACT: RGBColor = RGBColor(240, 140, 0);
const M440C_ROLLING: RGBColor = RGBColor(25, 90, 200);
const M440C_CONTACT: RGBColor = RGBColor(130, 50, 170);
const OTHERS: [RGBColor; 4] = [
    RGBColor(0, 150, 150),
    RGBColor(110, 80, 40),
    RGBColor(90, 90, 90),
    RGBColor(160, 160, 0),
];

/// The marker of a material: squares for 316, circles for 440c (as in the chapter).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    Circle,
    Square,
    Triangle,
    Diamond,
}

/// Colour of a material (`index` picks a stable colour for materials the chapter does not have).
pub fn material_colour(material: &str, index: usize) -> RGBColor {
    match material.to_ascii_lowercase().as_str() {
        "316" | "ss316" => M316_ROLLING,
        "440c" | "ss440c" => M440C_ROLLING,
        _ => OTHERS[index % OTHERS.len()],
    }
}

/// Colour of a collision series: material and setup (contact pairs get the chapter's second colour).
pub fn setup_colour(material: &str, contact: bool, index: usize) -> RGBColor {
    match (material.to_ascii_lowercase().as_str(), contact) {
        ("316" | "ss316", false) => M316_ROLLING,
        ("316" | "ss316", true) => M316_CONTACT,
        ("440c" | "ss440c", false) => M440C_ROLLING,
        ("440c" | "ss440c", true) => M440C_CONTACT,
        _ => OTHERS[(index + usize::from(contact)) % OTHERS.len()],
    }
}

/// Marker of a material and setup: 316 squares / triangles, 440c circles / diamonds.
pub fn marker(material: &str, contact: bool) -> Marker {
    let is_316 = matches!(material.to_ascii_lowercase().as_str(), "316" | "ss316");
    match (is_316, contact) {
        (true, false) => Marker::Square,
        (true, true) => Marker::Triangle,
        (false, false) => Marker::Circle,
        (false, true) => Marker::Diamond,
    }
}

/// CSS hex of a colour, for the HTML legend swatches.
pub fn hex(c: RGBColor) -> String {
    format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2)
}
