//! Reads the XML file Fiji TrackMate saves (one movie, one run): spots from
//! `Model/AllSpots/SpotsInFrame/Spot` (`ID`, `FRAME`, `POSITION_X`, `POSITION_Y`, `VISIBILITY`),
//! tracks from `Model/AllTracks/Track/Edge` (`SPOT_SOURCE_ID`, `SPOT_TARGET_ID`), the tracks kept by
//! TrackMate's filters from `Model/FilteredTracks/TrackID`, the spatial and time units from the
//! `Model` attributes and the frame interval from `Settings/ImageData`.

use super::error::Problem;
use super::params::Axis;
use super::spots::{RunSpots, Spot, SpotFile, Units};
use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;
use std::collections::{BTreeMap, BTreeSet};

/// True if the bytes are a TrackMate XML file (its root element is `TrackMate`).
pub fn looks_like(bytes: &[u8]) -> bool {
    let mut reader = Reader::from_reader(bytes);
    loop {
        match reader.read_event() {
            Ok(Event::Start(e) | Event::Empty(e)) => return e.name().as_ref() == b"TrackMate",
            Ok(Event::Eof) | Err(_) => return false,
            Ok(_) => {}
        }
    }
}

/// Metres per unit of a TrackMate spatial unit, or `None` for pixels (or an unknown unit).
pub fn metres_per(unit: &str) -> Option<f64> {
    match unit.trim() {
        "m" | "meter" | "metre" | "meters" | "metres" => Some(1.0),
        "mm" | "millimeter" | "millimetre" | "millimeters" | "millimetres" => Some(1e-3),
        "µm" | "μm" | "um" | "micron" | "microns" | "micrometer" | "micrometre" | "micrometers"
        | "micrometres" => Some(1e-6),
        "nm" | "nanometer" | "nanometre" | "nanometers" | "nanometres" => Some(1e-9),
        _ => None,
    }
}

/// Seconds per unit of a TrackMate time unit, or `None` for frames (or an unknown unit).
fn seconds_per(unit: &str) -> Option<f64> {
    match unit.trim() {
        "s" | "sec" | "second" | "seconds" => Some(1.0),
        "ms" | "msec" | "millisecond" | "milliseconds" => Some(1e-3),
        "µs" | "μs" | "us" | "microsecond" | "microseconds" => Some(1e-6),
        "min" | "minute" | "minutes" => Some(60.0),
        _ => None,
    }
}

/// The 1-based line of a byte offset.
fn line_of(bytes: &[u8], offset: usize) -> usize {
    1 + bytes[..offset.min(bytes.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// The attributes of an element, unescaped, by name.
fn attributes(e: &BytesStart, reader: &Reader<&[u8]>) -> Result<BTreeMap<String, String>, String> {
    let mut out = BTreeMap::new();
    for a in e.attributes() {
        let a = a.map_err(|e| e.to_string())?;
        let value = a
            .decode_and_unescape_value(reader.decoder())
            .map_err(|e| e.to_string())?;
        out.insert(
            String::from_utf8_lossy(a.key.as_ref()).into_owned(),
            value.into_owned(),
        );
    }
    Ok(out)
}

/// A spot as read, before tracks are known.
struct RawSpot {
    id: i64,
    frame: i64,
    x: f64,
    y: f64,
    visible: bool,
    line: usize,
}

/// One element's attributes, where it stands, and the problems they can raise.
struct Element<'a> {
    file: &'a str,
    run: &'a str,
    line: usize,
    attrs: BTreeMap<String, String>,
}

impl Element<'_> {
    fn bad(&self, column: &str, message: String, fix: &str) -> Problem {
        Problem::at(self.file, self.line, column, message, fix).in_run(self.run)
    }

    /// The attribute `key` as a finite number.
    fn number(&self, key: &str) -> Result<f64, Problem> {
        let text = self.attrs.get(key).ok_or_else(|| {
            self.bad(
                key,
                format!("the element has no {key} attribute"),
                "save the TrackMate file again from Fiji",
            )
        })?;
        match text.trim().parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(self.bad(
                key,
                format!("{text:?} is not a finite number"),
                "write a finite number, e.g. 12.5 or 1.25E1",
            )),
        }
    }

    /// The attribute `key` as a whole number.
    fn whole(&self, key: &str) -> Result<i64, Problem> {
        let x = self.number(key)?;
        if x.fract() != 0.0 || x.abs() > 9.0e15 {
            return Err(self.bad(
                key,
                format!("{x} is not a whole number"),
                "write a whole number",
            ));
        }
        Ok(x as i64)
    }
}

/// What one pass over the file's elements found.
#[derive(Default)]
struct Scan {
    problems: Vec<Problem>,
    spots: Vec<RawSpot>,
    track_of: BTreeMap<i64, i64>,
    tracks: BTreeSet<i64>,
    filtered: Option<BTreeSet<i64>>,
    current_track: Option<i64>,
    spatial_units: String,
    time_units: String,
    interval: Option<f64>,
    root_seen: bool,
}

impl Scan {
    /// Takes in one opening (or empty) element named `name`.
    fn element(&mut self, name: &[u8], empty: bool, el: &Element) {
        match name {
            b"TrackMate" => self.root_seen = true,
            b"Model" => {
                self.spatial_units = el.attrs.get("spatialunits").cloned().unwrap_or_default();
                self.time_units = el.attrs.get("timeunits").cloned().unwrap_or_default();
            }
            b"ImageData" => {
                self.interval = el
                    .attrs
                    .get("timeinterval")
                    .and_then(|t| t.trim().parse().ok())
            }
            b"Spot" => {
                let spot = (|| {
                    Ok::<RawSpot, Problem>(RawSpot {
                        id: el.whole("ID")?,
                        frame: el.whole("FRAME")?,
                        x: el.number("POSITION_X")?,
                        y: el.number("POSITION_Y")?,
                        visible: el
                            .attrs
                            .get("VISIBILITY")
                            .is_none_or(|v| v.trim().parse::<f64>() != Ok(0.0)),
                        line: el.line,
                    })
                })();
                match spot {
                    Ok(s) => self.spots.push(s),
                    Err(p) => self.problems.push(p),
                }
            }
            b"Track" if !empty => match el.whole("TRACK_ID") {
                Ok(id) => {
                    self.tracks.insert(id);
                    self.current_track = Some(id);
                }
                Err(p) => self.problems.push(p),
            },
            b"Edge" => {
                if let Some(track) = self.current_track {
                    for key in ["SPOT_SOURCE_ID", "SPOT_TARGET_ID"] {
                        match el.whole(key) {
                            Ok(id) => {
                                self.track_of.insert(id, track);
                            }
                            Err(p) => self.problems.push(p),
                        }
                    }
                }
            }
            b"FilteredTracks" => {
                self.filtered.get_or_insert_with(BTreeSet::new);
            }
            b"TrackID" => match el.whole("TRACK_ID") {
                Ok(id) => {
                    self.filtered.get_or_insert_with(BTreeSet::new).insert(id);
                }
                Err(p) => self.problems.push(p),
            },
            _ => {}
        }
    }
}

/// Every element of the file, read in one pass; an unreadable file or attribute is an error.
fn scan(file: &str, bytes: &[u8], run: &str) -> Result<Scan, Problem> {
    let mut reader = Reader::from_reader(bytes);
    let mut found = Scan::default();
    loop {
        let at = reader.buffer_position() as usize;
        let event = reader.read_event().map_err(|e| {
            Problem::at(
                file,
                line_of(bytes, reader.error_position() as usize),
                "xml",
                format!("cannot be read as XML ({e})"),
                "save the TrackMate file again from Fiji (File > Save), or export its spots as CSV",
            )
        })?;
        let (e, empty) = match &event {
            Event::Start(e) => (e, false),
            Event::Empty(e) => (e, true),
            Event::End(e) => {
                if e.name().as_ref() == b"Track" {
                    found.current_track = None;
                }
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        let line = line_of(bytes, at);
        let attrs = attributes(e, &reader).map_err(|m| {
            Problem::at(
                file,
                line,
                "xml",
                format!("an attribute cannot be read ({m})"),
                "save the TrackMate file again from Fiji",
            )
        })?;
        let el = Element {
            file,
            run,
            line,
            attrs,
        };
        found.element(e.name().as_ref(), empty, &el);
    }
    Ok(found)
}

/// The tracks TrackMate's filters kept, and the notes on what its filters left out.
fn kept_and_notes(found: &Scan) -> (BTreeSet<i64>, Vec<String>) {
    let mut notes = Vec::new();
    let kept_tracks: BTreeSet<i64> = match &found.filtered {
        Some(f) => found.tracks.intersection(f).copied().collect(),
        None => found.tracks.clone(),
    };
    for id in found.tracks.difference(&kept_tracks) {
        let n = found.track_of.values().filter(|t| *t == id).count();
        notes.push(format!(
            "track {id} ({n} spots) left out: TrackMate's track filters removed it (it is not in FilteredTracks)"
        ));
    }
    let hidden = found.spots.iter().filter(|s| !s.visible).count();
    if hidden > 0 {
        notes.push(format!(
            "{hidden} spots left out: TrackMate's spot filters hid them (VISIBILITY = 0)"
        ));
    }
    (kept_tracks, notes)
}

/// Reads one TrackMate XML file into the spots of one run named after the file. Spots with
/// problems are returned as problems of the run; tracks TrackMate's filters removed and spots it
/// hid are left out and listed in the file's notes.
pub fn read(
    file: &str,
    bytes: &[u8],
    axis: Axis,
    run: &str,
) -> Result<(SpotFile, Vec<Problem>), Problem> {
    let found = scan(file, bytes, run)?;
    if !found.root_seen {
        return Err(Problem::file(
            file,
            "is not a TrackMate file (its root element is not TrackMate)",
            "save the tracks from Fiji TrackMate (File > Save), or move the file out of the dataset folder",
        ));
    }
    let (kept_tracks, notes) = kept_and_notes(&found);
    let Scan {
        problems,
        spots,
        track_of,
        spatial_units,
        time_units,
        interval,
        ..
    } = found;
    let m_per_unit = metres_per(&spatial_units);
    let fps = match (interval, seconds_per(&time_units)) {
        (Some(dt), Some(s)) if dt > 0.0 => Some(1.0 / (dt * s)),
        _ => None,
    };
    let spots: Vec<Spot> = spots
        .into_iter()
        .filter(|s| s.visible)
        .filter(|s| track_of.get(&s.id).is_none_or(|t| kept_tracks.contains(t)))
        .map(|s| {
            let (p, q) = match axis {
                Axis::X => (s.x, s.y),
                Axis::Y => (s.y, s.x),
            };
            Spot {
                track: track_of.get(&s.id).copied(),
                frame: s.frame,
                p_px: p,
                q_px: q,
                row: s.line,
            }
        })
        .collect();
    Ok((
        SpotFile {
            file: file.to_string(),
            key_columns: "TRACK_ID, FRAME",
            frame_column: "FRAME",
            track_column: "TRACK_ID",
            position_column: match axis {
                Axis::X => "POSITION_X",
                Axis::Y => "POSITION_Y",
            },
            runs: vec![RunSpots {
                run: run.to_string(),
                named_by_file: true,
                spots,
                notes,
            }],
            units: Units {
                m_per_unit,
                fps,
                spatial: spatial_units,
            },
        },
        problems,
    ))
}
