//! The bytes of a recording item (`ingest:runs`): a small binary format, one encoder and one decoder used by every reader.
//!
//! Layout (all integers and floats little-endian, no padding):
//!
//! | bytes | field |
//! | --- | --- |
//! | 8 | magic `GROOVREC` |
//! | 4 | version, u32 = 1 |
//! | 4 | length M of the metadata, u32 |
//! | M | metadata: compact UTF-8 JSON of `RunInfo` (`run`, `experiment`, `material`, `diameter_m`, `fps`, `setup`, `extra`) |
//! | 4 | number of tracks, u32 |
//!
//! then per track (sorted by particle):
//!
//! | bytes | field |
//! | --- | --- |
//! | 4 | particle, u32 |
//! | 4 | number of samples N, u32 |
//! | 4 | number of frame segments S, u32 |
//! | 8·S | first frame of each segment, i64 |
//! | 8·S | length of each segment, i64 (≥ 1; the lengths add up to N) |
//! | 8·N | t_s, f64 |
//! | 8·N | z_m, f64 |
//!
//! A segment is a stretch of consecutive frames, so a track without dropped frames has one and
//! its frames cost 16 bytes instead of 8 per sample. Nothing follows the last track. Floats are
//! their IEEE bits, so a recording decodes to exactly the numbers that were encoded.

use super::{Recording, RunInfo, Track};

/// The first 8 bytes of every recording item.
pub const MAGIC: &[u8; 8] = b"GROOVREC";
/// The format version this build writes and reads.
pub const VERSION: u32 = 1;

/// The item bytes of `rec`.
pub fn encode(rec: &Recording) -> Vec<u8> {
    // RunInfo holds strings, numbers and a map of strings: serializing it cannot fail.
    let meta = serde_json::to_vec(&rec.info).unwrap_or_default();
    let segs: Vec<Vec<(i64, i64)>> = rec.tracks.iter().map(|t| segments(&t.frame)).collect();
    // the exact size: an item kept in memory (100,000 of them) holds no spare capacity
    let size = MAGIC.len()
        + 12
        + meta.len()
        + rec
            .tracks
            .iter()
            .zip(&segs)
            .map(|(t, s)| 12 + 16 * s.len() + 16 * t.frame.len())
            .sum::<usize>();
    let mut out = Vec::with_capacity(size);
    out.extend_from_slice(MAGIC);
    put_u32(&mut out, VERSION);
    put_u32(&mut out, meta.len() as u32);
    out.extend_from_slice(&meta);
    put_u32(&mut out, rec.tracks.len() as u32);
    for (t, segments) in rec.tracks.iter().zip(segs) {
        put_u32(&mut out, t.particle);
        put_u32(&mut out, t.frame.len() as u32);
        put_u32(&mut out, segments.len() as u32);
        for (first, _) in &segments {
            out.extend_from_slice(&first.to_le_bytes());
        }
        for (_, len) in &segments {
            out.extend_from_slice(&len.to_le_bytes());
        }
        for v in t.t_s.iter().chain(&t.z_m) {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    debug_assert_eq!(out.len(), size, "the item's size was computed exactly");
    out
}

/// Why bytes are not a recording item of this version (lowercase, without the item's name:
/// the caller names it and says to rerun the ingest stage).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DecodeError {
    #[error("it does not start with GROOVREC (an item of an older groove, or not a recording)")]
    Magic,
    #[error("it is version {0} of the format; this groove reads version {VERSION}")]
    Version(u32),
    #[error("its metadata is not a run's ({0})")]
    Metadata(String),
    #[error("it ends after {0} bytes, inside a field (a truncated item)")]
    Truncated(usize),
    #[error("track of particle {particle}: a frame segment of length {len} does not fit its {n} samples")]
    Segment { particle: u32, len: i64, n: usize },
    #[error("track of particle {particle}: its frame segments hold {held} frames, not {n}")]
    Frames {
        particle: u32,
        held: usize,
        n: usize,
    },
    #[error("{0} bytes follow the last track")]
    Trailing(usize),
}

/// The recording in `bytes`; an error if they are not a recording item of this version.
pub fn decode(bytes: &[u8]) -> Result<Recording, DecodeError> {
    let mut r = Reader { bytes, at: 0 };
    let info = header(&mut r)?;
    let n_tracks = r.u32()? as usize;
    let mut tracks = Vec::with_capacity(n_tracks.min(16));
    for _ in 0..n_tracks {
        let particle = r.u32()?;
        let n = r.u32()? as usize;
        let s = r.u32()? as usize;
        if 16 * (n as u64) + 16 * (s as u64) > r.left() as u64 {
            return Err(r.truncated());
        }
        let firsts = r.take(8 * s)?;
        let lens = r.take(8 * s)?;
        let mut frame = Vec::with_capacity(n);
        for (first, len) in firsts.chunks_exact(8).zip(lens.chunks_exact(8)) {
            let first = i64::from_le_bytes(first.try_into().unwrap_or_default());
            let len = i64::from_le_bytes(len.try_into().unwrap_or_default());
            if len < 1
                || first.checked_add(len - 1).is_none()
                || frame.len() as i64 + len > n as i64
            {
                return Err(DecodeError::Segment { particle, len, n });
            }
            frame.extend((0..len).map(|k| first + k));
        }
        if frame.len() != n {
            return Err(DecodeError::Frames {
                particle,
                held: frame.len(),
                n,
            });
        }
        let t_s = floats(r.take(8 * n)?);
        let z_m = floats(r.take(8 * n)?);
        tracks.push(Track {
            particle,
            frame,
            t_s,
            z_m,
        });
    }
    if r.at != bytes.len() {
        return Err(DecodeError::Trailing(bytes.len() - r.at));
    }
    Ok(Recording { info, tracks })
}

/// The run metadata of a recording item, without decoding its tracks.
pub fn decode_info(bytes: &[u8]) -> Result<RunInfo, DecodeError> {
    header(&mut Reader { bytes, at: 0 })
}

/// Magic, version and metadata.
fn header(r: &mut Reader) -> Result<RunInfo, DecodeError> {
    if r.take(8).ok() != Some(&MAGIC[..]) {
        return Err(DecodeError::Magic);
    }
    let version = r.u32()?;
    if version != VERSION {
        return Err(DecodeError::Version(version));
    }
    let m = r.u32()? as usize;
    serde_json::from_slice(r.take(m)?).map_err(|e| DecodeError::Metadata(e.to_string()))
}

/// Consecutive frames as (first frame, count).
fn segments(frame: &[i64]) -> Vec<(i64, i64)> {
    let mut out: Vec<(i64, i64)> = Vec::new();
    for &f in frame {
        match out.last_mut() {
            Some((first, len)) if first.checked_add(*len) == Some(f) => *len += 1,
            _ => out.push((f, 1)),
        }
    }
    out
}

fn floats(bytes: &[u8]) -> Vec<f64> {
    bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap_or_default()))
        .collect()
}

fn put_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_le_bytes());
}

/// A cursor over the item's bytes that refuses to read past the end.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], DecodeError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| self.truncated())?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn left(&self) -> usize {
        self.bytes.len() - self.at
    }

    fn truncated(&self) -> DecodeError {
        DecodeError::Truncated(self.bytes.len())
    }

    fn u32(&mut self) -> Result<u32, DecodeError> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::{Experiment, Setup};
    use std::collections::BTreeMap;

    fn rec() -> Recording {
        Recording {
            info: RunInfo {
                run: "c 01/ä".into(),
                experiment: Experiment::Collision,
                material: "316".into(),
                diameter_m: 3e-4,
                fps: 10_000.0,
                setup: Some(Setup::Rolling),
                extra: BTreeMap::from([("v0_laser_mps".into(), "0.1".into())]),
            },
            tracks: vec![
                Track {
                    particle: 0,
                    frame: vec![-3, -2, 0, 1, 2, 7],
                    t_s: vec![-0.0, 1e-4, 3e-4, 4e-4, 5e-4, 1.0e-3],
                    z_m: vec![1e-3, -2.5e-3, f64::MIN_POSITIVE, 0.1, 0.2, 9.99],
                },
                Track {
                    particle: 1,
                    frame: vec![],
                    t_s: vec![],
                    z_m: vec![],
                },
            ],
        }
    }

    #[test]
    fn decode_gives_back_the_same_bits() {
        let r = rec();
        let bytes = encode(&r);
        let back = decode(&bytes).unwrap();
        assert_eq!(back, r);
        assert_eq!(back.tracks[0].t_s[0].to_bits(), (-0.0f64).to_bits());
        assert_eq!(decode_info(&bytes).unwrap(), r.info);
        assert_eq!(encode(&back), bytes);
    }

    #[test]
    fn a_track_without_dropped_frames_costs_16_bytes_a_sample() {
        let n = 600;
        let mut r = rec();
        r.tracks = vec![Track {
            particle: 0,
            frame: (0..n).collect(),
            t_s: vec![0.5; n as usize],
            z_m: vec![0.25; n as usize],
        }];
        let meta = serde_json::to_vec(&r.info).unwrap().len();
        assert_eq!(
            encode(&r).len(),
            8 + 4 + 4 + meta + 4 + 12 + 16 + 16 * n as usize
        );
    }

    #[test]
    fn damaged_items_are_refused_with_the_reason() {
        let bytes = encode(&rec());
        let magic = decode(b"{\"info\":{}}").unwrap_err();
        assert_eq!(magic, DecodeError::Magic);
        assert!(magic.to_string().contains("GROOVREC"), "{magic}");
        let mut v2 = bytes.clone();
        v2[8] = 2;
        let version = decode(&v2).unwrap_err();
        assert_eq!(version, DecodeError::Version(2));
        assert!(version.to_string().contains("version 2"), "{version}");
        for cut in [10, 20, bytes.len() - 1] {
            let e = decode(&bytes[..cut]).unwrap_err();
            assert_eq!(e, DecodeError::Truncated(cut), "cut {cut}");
            assert!(e.to_string().contains("truncated"), "cut {cut}: {e}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        let trailing = decode(&longer).unwrap_err();
        assert_eq!(trailing, DecodeError::Trailing(1));
        assert_eq!(trailing.to_string(), "1 bytes follow the last track");
    }
}
