//! A law given by its values at a few speeds, piecewise linear in the logarithm of the speed
//! (the shape discovery's maps of the impact laws take), held in fixed arrays so that the laws
//! built on it stay `Copy`.

use serde::{Deserialize, Serialize};

/// Most nodes a map holds (discovery's restitution maps have 3–6, its μ_pp maps 2–4).
pub const MAX_NODES: usize = 6;

/// Values at increasing speeds, linear in ln speed between them. Beyond the end nodes the end
/// value is held, not extrapolated: that is the map discovery fitted and tested, and a line in
/// ln speed would run away at the slowest impacts of a cascade (ln v → −∞ as the pair closes).
/// Written `{speeds_mps: [...], values: [...]}`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "Nodes", into = "Nodes")]
pub struct LnMap {
    n: usize,
    ln_speed: [f64; MAX_NODES],
    value: [f64; MAX_NODES],
}

/// The written form of a map.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Nodes {
    pub speeds_mps: Vec<f64>,
    pub values: Vec<f64>,
}

impl LnMap {
    /// The map through (speed, value) at `speeds_mps`, which must be positive, finite and
    /// increasing, 1 to `MAX_NODES` of them, with as many finite values.
    pub fn new(speeds_mps: &[f64], values: &[f64]) -> Result<LnMap, String> {
        let n = speeds_mps.len();
        if n == 0 || n > MAX_NODES || values.len() != n {
            return Err(format!(
                "a map needs 1 to {MAX_NODES} speeds and as many values (got {n} speeds, {} values)",
                values.len()
            ));
        }
        if !speeds_mps.iter().all(|s| s.is_finite() && *s > 0.0)
            || !speeds_mps.windows(2).all(|w| w[0] < w[1])
        {
            return Err(format!(
                "a map's speeds must be positive and increasing: {speeds_mps:?}"
            ));
        }
        if !values.iter().all(|v| v.is_finite()) {
            return Err(format!("a map's values must be finite: {values:?}"));
        }
        let mut map = LnMap {
            n,
            ln_speed: [0.0; MAX_NODES],
            value: [0.0; MAX_NODES],
        };
        for i in 0..n {
            map.ln_speed[i] = speeds_mps[i].ln();
            map.value[i] = values[i];
        }
        Ok(map)
    }

    /// The speeds of the nodes (m/s).
    pub fn speeds_mps(&self) -> Vec<f64> {
        self.ln_speed[..self.n].iter().map(|u| u.exp()).collect()
    }

    /// The values at the nodes.
    pub fn values(&self) -> &[f64] {
        &self.value[..self.n]
    }

    /// The number of nodes.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Always false: a map has at least one node.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The same nodes with the values `values` (as many as nodes; missing ones keep theirs).
    pub fn with_values(&self, values: &[f64]) -> LnMap {
        let mut out = *self;
        for (v, x) in out.value[..self.n].iter_mut().zip(values) {
            *v = *x;
        }
        out
    }

    /// The speed of the middle node (the upper of the two middle ones for an even count).
    pub fn median_speed_mps(&self) -> f64 {
        self.ln_speed[self.n / 2].exp()
    }

    /// The value at `speed_mps` (its magnitude): linear in ln speed between the nodes, the end
    /// value beyond them (and at speed 0).
    pub fn at(&self, speed_mps: f64) -> f64 {
        let (x, y) = (&self.ln_speed[..self.n], &self.value[..self.n]);
        let u = speed_mps.abs().ln();
        if u <= x[0] {
            return y[0];
        }
        let last = self.n - 1;
        if u >= x[last] {
            return y[last];
        }
        let i = x.windows(2).position(|w| u < w[1]).unwrap_or(last - 1);
        let t = (u - x[i]) / (x[i + 1] - x[i]);
        y[i] + t * (y[i + 1] - y[i])
    }
}

impl TryFrom<Nodes> for LnMap {
    type Error = String;
    fn try_from(n: Nodes) -> Result<LnMap, String> {
        LnMap::new(&n.speeds_mps, &n.values)
    }
}

impl From<LnMap> for Nodes {
    fn from(m: LnMap) -> Nodes {
        Nodes {
            speeds_mps: m.speeds_mps(),
            values: m.values().to_vec(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_map_is_linear_in_ln_speed_between_its_nodes_and_flat_beyond() {
        let m = LnMap::new(&[0.01, 0.1, 1.0], &[0.2, 0.8, 0.5]).unwrap();
        assert!((m.at(0.01) - 0.2).abs() < 1e-12 && (m.at(0.1) - 0.8).abs() < 1e-12);
        // halfway in ln speed between 0.01 and 0.1
        assert!((m.at(0.1f64.sqrt() * 0.1) - 0.5).abs() < 1e-12);
        assert!((m.at(-0.1) - 0.8).abs() < 1e-12, "the speed's magnitude");
        assert_eq!((m.at(1e-4), m.at(0.0), m.at(10.0)), (0.2, 0.2, 0.5));
        assert_eq!(m.median_speed_mps(), 0.1f64.ln().exp());
        let moved = m.with_values(&[0.3, 0.6, 0.9]);
        assert_eq!(
            (moved.len(), moved.values()),
            (3, [0.3, 0.6, 0.9].as_slice())
        );
        assert_eq!(moved.speeds_mps(), m.speeds_mps());
        let one = LnMap::new(&[0.05], &[0.7]).unwrap();
        assert_eq!((one.at(0.001), one.at(1.0)), (0.7, 0.7));
    }

    #[test]
    fn a_map_reads_and_writes_its_nodes_and_refuses_bad_ones() {
        let m: LnMap =
            serde_json::from_str(r#"{"speeds_mps": [0.02, 0.05], "values": [0.9, 0.6]}"#).unwrap();
        assert_eq!(m.values(), [0.9, 0.6]);
        let back: Nodes = serde_json::from_value(serde_json::to_value(m).unwrap()).unwrap();
        assert!((back.speeds_mps[1] - 0.05).abs() < 1e-15);
        assert!(LnMap::new(&[0.05, 0.02], &[0.9, 0.6]).is_err());
        assert!(LnMap::new(&[0.0, 0.02], &[0.9, 0.6]).is_err());
        assert!(LnMap::new(&[0.02], &[0.9, 0.6]).is_err());
        assert!(LnMap::new(&[0.1; 7], &[0.5; 7]).is_err());
        assert!(LnMap::new(&[], &[]).is_err());
        assert!(LnMap::new(&[0.02], &[f64::NAN]).is_err());
    }
}
