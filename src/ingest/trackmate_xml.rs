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

/// Reads one TrackMate XML file into the spots of one run named after the file. Spots with
/// problems are returned as problems of the run; tracks TrackMate's filters removed and spots it
/// hid are left out and listed in the file's notes.
pub fn read(
    file: &str,
    bytes: &[u8],
    axis: Axis,
    run: &str,
) -> Result<(SpotFile, Vec<Problem>), Problem> {
    let mut reader = Reader::from_reader(bytes);
    let mut problems = Vec::new();
    let mut spots: Vec<RawSpot> = Vec::new();
    let mut track_of: BTreeMap<i64, i64> = BTreeMap::new();
    let mut tracks: BTreeSet<i64> = BTreeSet::new();
    let mut filtered: Option<BTreeSet<i64>> = None;
    let mut current_track: Option<i64> = None;
    let mut spatial_units = String::new();
    let mut time_units = String::new();
    let mut interval: Option<f64> = None;
    let mut root_seen = false;
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
                    current_track = None;
                }
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        let line = line_of(bytes, at);
        let bad = |column: &str, message: String, fix: &str| {
            Problem::at(file, line, column, message, fix).in_run(run)
        };
        let attrs = attributes(e, &reader).map_err(|m| {
            Problem::at(
                file,
                line,
                "xml",
                format!("an attribute cannot be read ({m})"),
                "save the TrackMate file again from Fiji",
            )
        })?;
        let number = |key: &str| -> Result<f64, Problem> {
            let text = attrs.get(key).ok_or_else(|| {
                bad(
                    key,
                    format!("the element has no {key} attribute"),
                    "save the TrackMate file again from Fiji",
                )
            })?;
            match text.trim().parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => Err(bad(
                    key,
                    format!("{text:?} is not a finite number"),
                    "write a finite number, e.g. 12.5 or 1.25E1",
                )),
            }
        };
        let whole = |key: &str| -> Result<i64, Problem> {
            let x = number(key)?;
            if x.fract() != 0.0 || x.abs() > 9.0e15 {
                return Err(bad(
                    key,
                    format!("{x} is not a whole number"),
                    "write a whole number",
                ));
            }
            Ok(x as i64)
        };
        match e.name().as_ref() {
            b"TrackMate" => root_seen = true,
            b"Model" => {
                spatial_units = attrs.get("spatialunits").cloned().unwrap_or_default();
                time_units = attrs.get("timeunits").cloned().unwrap_or_default();
            }
            b"ImageData" => {
                interval = attrs
                    .get("timeinterval")
                    .and_then(|t| t.trim().parse().ok())
            }
            b"Spot" => {
                let spot = (|| {
                    Ok::<RawSpot, Problem>(RawSpot {
                        id: whole("ID")?,
                        frame: whole("FRAME")?,
                        x: number("POSITION_X")?,
                        y: number("POSITION_Y")?,
                        visible: attrs
                            .get("VISIBILITY")
                            .is_none_or(|v| v.trim().parse::<f64>() != Ok(0.0)),
                        line,
                    })
                })();
                match spot {
                    Ok(s) => spots.push(s),
                    Err(p) => problems.push(p),
                }
            }
            b"Track" if !empty => match whole("TRACK_ID") {
                Ok(id) => {
                    tracks.insert(id);
                    current_track = Some(id);
                }
                Err(p) => problems.push(p),
            },
            b"Edge" => {
                if let Some(track) = current_track {
                    for key in ["SPOT_SOURCE_ID", "SPOT_TARGET_ID"] {
                        match whole(key) {
                            Ok(id) => {
                                track_of.insert(id, track);
                            }
                            Err(p) => problems.push(p),
                        }
                    }
                }
            }
            b"FilteredTracks" => {
                filtered.get_or_insert_with(BTreeSet::new);
            }
            b"TrackID" => match whole("TRACK_ID") {
                Ok(id) => {
                    filtered.get_or_insert_with(BTreeSet::new).insert(id);
                }
                Err(p) => problems.push(p),
            },
            _ => {}
        }
    }
    if !root_seen {
        return Err(Problem::file(
            file,
            "is not a TrackMate file (its root element is not TrackMate)",
            "save the tracks from Fiji TrackMate (File > Save), or move the file out of the dataset folder",
        ));
    }
    let mut notes = Vec::new();
    let kept_tracks: BTreeSet<i64> = match &filtered {
        Some(f) => tracks.intersection(f).copied().collect(),
        None => tracks.clone(),
    };
    for id in tracks.difference(&kept_tracks) {
        let n = track_of.values().filter(|t| *t == id).count();
        notes.push(format!(
            "track {id} ({n} spots) left out: TrackMate's track filters removed it (it is not in FilteredTracks)"
        ));
    }
    let hidden = spots.iter().filter(|s| !s.visible).count();
    if hidden > 0 {
        notes.push(format!(
            "{hidden} spots left out: TrackMate's spot filters hid them (VISIBILITY = 0)"
        ));
    }
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
