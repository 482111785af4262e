//! Physical sanity of a recording, checked before any stage computes with it: values a real
//! recording of this experiment can have, and a clock that agrees with the frame numbers.
//!
//! The limits are wide (a real recording is far inside them) and stop what typing slips and
//! broken exports produce: a frame rate in kHz, a diameter in millimetres, positions in pixels or
//! micrometres, times that are not seconds, time going backwards. Downstream numerics (fits,
//! simulation, discovery) may rely on them: every number is finite, |z| ≤ `Z_MAX_M`, |t| ≤
//! `T_MAX_S`, times strictly increase along each track.

use super::error::Problem;
use super::samples::{RunRow, Sample, SampleFile};

/// Slowest frame rate accepted, frames per second: the sphere crosses the view in well under a
/// second, so a slower camera records nothing to fit (and 20 is how 20 kHz looks typed in kHz).
pub const FPS_MIN: f64 = 50.0;
/// Fastest frame rate accepted (the fastest high-speed cameras record at about 1e7 fps).
pub const FPS_MAX: f64 = 1e8;
/// Smallest and largest particle diameter accepted, metres (1 µm to 10 cm).
pub const DIAMETER_MIN_M: f64 = 1e-6;
pub const DIAMETER_MAX_M: f64 = 0.1;
pub use crate::recording::{T_MAX_S, Z_MAX_M};
/// How far t_s may stray from frame/fps: half a frame (timestamps rounded to the frame) plus this
/// fraction of the time elapsed since the run's first frame (a frame rate given to 2–3 digits,
/// e.g. 29.97 written as 30, is 0.1 %).
pub const CLOCK_TOLERANCE: f64 = 0.01;

/// A message and a fix, for the caller to place at its file, row and column (or params key).
pub type Complaint = (String, String);

/// `x` within `lo ..= hi`, or the complaint of the side it falls out on (NaN is for the
/// readers to refuse, not a range).
fn within(
    x: f64,
    (lo, hi): (f64, f64),
    below: impl FnOnce(f64) -> Complaint,
    above: impl FnOnce(f64) -> Complaint,
) -> Result<(), Complaint> {
    if x < lo {
        Err(below(x))
    } else if x > hi {
        Err(above(x))
    } else {
        Ok(())
    }
}

/// The run's frame rate is plausible, or what is wrong with it.
pub fn fps(fps: f64) -> Result<(), Complaint> {
    within(
        fps,
        (FPS_MIN, FPS_MAX),
        |fps| {
            (
                format!(
                    "{fps} frames per second is below {FPS_MIN}, too slow for a high-speed recording"
                ),
                format!(
                    "write the frame rate in frames per second (if {fps} is in kHz, write {})",
                    fps * 1000.0
                ),
            )
        },
        |fps| {
            (
                format!("{fps} frames per second is above {FPS_MAX:e}, faster than any camera"),
                "write the frame rate in frames per second".to_string(),
            )
        },
    )
}

/// The particle diameter is plausible, or what is wrong with it.
pub fn diameter(d: f64) -> Result<(), Complaint> {
    within(
        d,
        (DIAMETER_MIN_M, DIAMETER_MAX_M),
        |d| {
            (
                format!("a diameter of {d:e} m is below {DIAMETER_MIN_M:e} m (1 µm)"),
                "write the diameter in metres, e.g. 3e-4 for 300 µm".to_string(),
            )
        },
        |d| {
            (
                format!("a diameter of {d} m is above {DIAMETER_MAX_M} m"),
                format!(
                    "write the diameter in metres (if {d} is in millimetres, write {:e})",
                    d / 1000.0
                ),
            )
        },
    )
}

/// A position along the groove is plausible, or what is wrong with it.
pub fn position(z: f64) -> Result<(), Complaint> {
    let far = |z: f64| {
        (
            format!("{z:e} m is farther than {Z_MAX_M} m from the origin"),
            "write the position in metres (not pixels or micrometres), or delete the row if it is a tracking error".to_string(),
        )
    };
    within(z, (-Z_MAX_M, Z_MAX_M), far, far)
}

/// A time stamp is plausible, or what is wrong with it.
pub fn time(t: f64) -> Result<(), Complaint> {
    let far = |t: f64| {
        (
            format!("{t:e} s is more than {T_MAX_S} s from the run's first frame"),
            "write the time in seconds since the run's first frame".to_string(),
        )
    };
    within(t, (-T_MAX_S, T_MAX_S), far, far)
}

/// The run's clock: along each track (sorted by particle, then frame, without duplicates) t_s
/// grows with the frame, and every t_s agrees with frame/fps counted from the run's first frame
/// within half a frame plus `CLOCK_TOLERANCE` of the elapsed time. The first disagreement found.
pub fn clock(r: &RunRow, ss: &[(&SampleFile, &Sample)]) -> Option<Problem> {
    let run = r.info.run.as_str();
    let fps = r.info.fps;
    let &(_, first) = ss.iter().min_by_key(|(f, s)| (s.frame, &f.file, s.row))?;
    let mut previous: Option<&Sample> = None;
    for &(f, s) in ss {
        if let Some(p) = previous.filter(|p| p.particle == s.particle && s.t_s <= p.t_s) {
            return Some(
                Problem::at(
                    &f.file,
                    s.row,
                    f.time_column,
                    format!(
                        "time goes backwards: t_s = {} at frame {} is not after t_s = {} at frame {} (row {})",
                        s.t_s, s.frame, p.t_s, p.frame, p.row
                    ),
                    "t_s must grow with the frame number; correct the times or the frame numbers",
                )
                .in_run(run),
            );
        }
        previous = Some(s);
    }
    for &(f, s) in ss {
        let frames = s.frame as f64 - first.frame as f64;
        let expected = frames / fps;
        let elapsed = s.t_s - first.t_s;
        if (elapsed - expected).abs() > 0.5 / fps + CLOCK_TOLERANCE * expected.abs() {
            return Some(
                Problem::at(
                    &f.file,
                    s.row,
                    f.time_column,
                    format!(
                        "t_s = {} at frame {} is {elapsed:e} s after frame {} (t_s = {}), but {frames} frames at {fps} frames per second take {expected:e} s",
                        s.t_s, s.frame, first.frame, first.t_s
                    ),
                    format!(
                        "check fps in {} row {} (frames per second: 10 kHz is 10000) and that t_s is in seconds since the run's first frame",
                        r.file, r.row
                    ),
                )
                .in_run(run),
            );
        }
    }
    None
}
