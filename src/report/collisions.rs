//! Collision-run fits read from the per-run fit JSON: impacts (pre/post velocities and spins) and the
//! fitted motion segments of each particle.

use super::value::{as_num, field, num, text};
use serde_json::Value;

/// Velocities of both particles at one instant: (v_z, v_a) of striker (0) and target (1), m/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairState {
    pub v_mps: [f64; 2],
    pub va_mps: [Option<f64>; 2],
}

/// One impact of a collision run.
#[derive(Debug, Clone, PartialEq)]
pub struct Impact {
    pub t_s: Option<f64>,
    /// Relative speed before the impact, |v1 − v2| (m/s).
    pub speed_mps: f64,
    pub restitution: Option<f64>,
    pub dvz_target_mps: Option<f64>,
    pub dva_target_mps: Option<f64>,
    /// true = slip, false = stick, None = not classified.
    pub slip: Option<bool>,
}

impl CollisionRun {
    /// A fit whose impacts can be used: converged (or stopped at the iteration cap with a result).
    pub fn usable(&self) -> bool {
        let s = self.status.to_ascii_lowercase();
        s.is_empty() || s == "converged" || s == "max_iterations"
    }
}

/// One fitted motion segment of one particle, with its sliding→rolling switch if it has one.
#[derive(Debug, Clone, PartialEq)]
pub struct Segment {
    pub particle: u32,
    pub t_start_s: f64,
    pub t_end_s: f64,
    pub t_switch_s: Option<f64>,
}

/// A collision run's fit as the report shows it.
#[derive(Debug, Clone, PartialEq)]
pub struct CollisionRun {
    pub run: String,
    pub material: String,
    pub contact: bool,
    pub impacts: Vec<Impact>,
    pub segments: Vec<Segment>,
    pub status: String,
}

fn pair(v: &Value) -> Option<PairState> {
    // {"v_mps": [v1, v2], "va_mps": [..]} or {"striker": {v_mps, va_mps}, "target": {...}}
    if let Some(a) = field(v, &["v_mps", "vz_mps", "v"]).and_then(Value::as_array) {
        let va = field(v, &["va_mps", "v_a_mps", "va"]).and_then(Value::as_array);
        let vai = |i: usize| va.and_then(|a| a.get(i)).and_then(as_num);
        return Some(PairState {
            v_mps: [as_num(a.first()?)?, as_num(a.get(1)?)?],
            va_mps: [vai(0), vai(1)],
        });
    }
    let s = field(v, &["striker", "p0", "0"])?;
    let t = field(v, &["target", "p1", "1"])?;
    let vs = ["v_mps", "vz_mps", "v"];
    let vas = ["va_mps", "v_a_mps", "va"];
    Some(PairState {
        v_mps: [num(s, &vs)?, num(t, &vs)?],
        va_mps: [num(s, &vas), num(t, &vas)],
    })
}

fn impact(v: &Value) -> Option<Impact> {
    let pre = field(v, &["pre", "before"]).and_then(pair);
    let post = field(v, &["post", "after"]).and_then(pair);
    let speed = num(
        v,
        &[
            "impact_speed_mps",
            "v_impact_mps",
            "relative_speed_mps",
            "speed_mps",
        ],
    )
    .or_else(|| pre.map(|p| p.v_mps[0] - p.v_mps[1]))?
    .abs();
    let restitution = num(
        v,
        &["restitution", "c", "C", "cor", "coefficient_of_restitution"],
    )
    .or_else(|| {
        let (a, b) = (pre?, post?);
        let rel = a.v_mps[0] - a.v_mps[1];
        (rel.abs() > 0.0).then(|| (b.v_mps[1] - b.v_mps[0]) / rel)
    });
    let dvz = num(
        v,
        &[
            "dvz_target_mps",
            "target_dvz_mps",
            "delta_vz_target_mps",
            "dv_z_mps",
        ],
    )
    .or_else(|| Some(post?.v_mps[1] - pre?.v_mps[1]));
    let dva = num(
        v,
        &[
            "dva_target_mps",
            "target_dva_mps",
            "delta_va_target_mps",
            "dv_a_mps",
        ],
    )
    .or_else(|| Some(post?.va_mps[1]? - pre?.va_mps[1]?));
    let slip = match field(v, &["contact", "slip", "regime", "kind", "contact_mode"]) {
        Some(Value::Bool(b)) => Some(*b),
        Some(Value::String(s)) if s.contains("slip") => Some(true),
        Some(Value::String(s)) if s.contains("stick") => Some(false),
        _ => None,
    };
    Some(Impact {
        t_s: num(v, &["t_s", "time_s", "t_impact_s", "t"]),
        speed_mps: speed,
        restitution,
        dvz_target_mps: dvz,
        dva_target_mps: dva,
        slip,
    })
}

fn segment(v: &Value, particle: u32) -> Option<Segment> {
    let particle = num(v, &["particle"]).map(|p| p as u32).unwrap_or(particle);
    let range = field(v, &["t_range_s", "range_s"]).and_then(Value::as_array);
    let from_range = |i: usize| range.and_then(|r| r.get(i)).and_then(as_num);
    Some(Segment {
        particle,
        t_start_s: num(v, &["t_start_s", "start_s", "from_s", "t_from_s"]).or(from_range(0))?,
        t_end_s: num(v, &["t_end_s", "end_s", "to_s", "t_to_s"]).or(from_range(1))?,
        t_switch_s: num(v, &["t_switch_s", "switch_s", "t_roll_s"]),
    })
}

/// Read one collision fit JSON (`{"experiment": "collision", ...}`).
pub fn from_fit_json(run: &str, material: &str, setup: Option<&str>, fit: &Value) -> CollisionRun {
    let body = fit.get("fit").filter(|b| b.is_object()).unwrap_or(fit);
    let impacts = field(body, &["impacts", "collisions"])
        .and_then(Value::as_array)
        .map(|a| a.iter().filter_map(impact).collect())
        .unwrap_or_default();
    let mut segments: Vec<Segment> = field(body, &["segments", "phases"])
        .and_then(Value::as_array)
        .map(|a| a.iter().filter_map(|s| segment(s, 0)).collect())
        .unwrap_or_default();
    if let Some(parts) = field(body, &["particles", "tracks"]).and_then(Value::as_array) {
        for (i, p) in parts.iter().enumerate() {
            let id = num(p, &["particle"]).map(|x| x as u32).unwrap_or(i as u32);
            if let Some(segs) = field(p, &["segments", "phases"]).and_then(Value::as_array) {
                segments.extend(segs.iter().filter_map(|s| segment(s, id)));
            }
        }
    }
    segments.sort_by(|a, b| {
        (a.particle, a.t_start_s)
            .partial_cmp(&(b.particle, b.t_start_s))
            .unwrap()
    });
    let setup = text(fit, &["setup"]).or(setup).unwrap_or("rolling");
    CollisionRun {
        run: text(fit, &["run"]).unwrap_or(run).to_string(),
        material: text(fit, &["material"]).unwrap_or(material).to_string(),
        contact: setup.eq_ignore_ascii_case("contact"),
        impacts,
        segments,
        status: text(body, &["status"]).unwrap_or("").to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn derives_restitution_and_target_changes_from_pre_post() {
        let fit = json!({"experiment": "collision", "impacts": [
            {"t_s": 0.01, "pre": {"v_mps": [0.1, 0.0], "va_mps": [0.17, 0.0]},
                          "post": {"v_mps": [0.01, 0.08], "va_mps": [0.1, -0.2]}}]});
        let c = from_fit_json("r1", "316", Some("rolling"), &fit);
        let i = &c.impacts[0];
        assert!((i.speed_mps - 0.1).abs() < 1e-12);
        assert!((i.restitution.unwrap() - 0.7).abs() < 1e-12);
        assert!((i.dvz_target_mps.unwrap() - 0.08).abs() < 1e-12);
        assert!((i.dva_target_mps.unwrap() + 0.2).abs() < 1e-12);
        assert!(!c.contact);
    }
}
