//! μ along the lab: μ_m·(1 + p₁P₁(x) + p₂P₂(x)), x over the observed stretch.

use super::form::{p, values_of, Entry, Fitted, Form, ParamInfo, Place};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::Ranges;
use crate::physics::FrictionVariation;
use std::collections::BTreeMap;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrictionPosition {
    pub z_mid_m: f64,
    pub half_span_m: f64,
}


impl Form for FrictionPosition {
    /// μ varying along the observed stretch of groove.
    fn offer(_n_materials: usize, rg: &Ranges) -> Option<Self> {
        Some(FrictionPosition {
            z_mid_m: rg.z_ref(),
            half_span_m: 0.5 * rg.span(),
        })
    }
    fn name(&self) -> &'static str {
        "friction_position"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("position_dependent_friction")
    }
    fn place(&self) -> Place {
        Place::Friction
    }
    fn form(&self) -> String {
        "mu(z) along the groove: mu (1 + p1 P1(x) + p2 P2(x)), fixed in the lab".into()
    }
    fn size_name(&self) -> &'static str {
        "a variation of friction along the groove"
    }
    /// How much μ varies over the observed stretch, and where it is furthest from its mean.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::{num, value, with_error};
        let peak = value(f, "peak_rel")?;
        Some(format!(
            "μ varies by ± {} % along the groove between z = {} and {} mm in the lab, {} % {} at z = {} mm, while sliding",
            with_error(f, "delta_mu_rel", 1e2)?,
            num(1e3 * value(f, "z_lo_m")?),
            num(1e3 * value(f, "z_hi_m")?),
            num(1e2 * peak.abs()),
            if peak >= 0.0 { "higher" } else { "lower" },
            num(1e3 * value(f, "z_at_peak_m")?)
        ))
    }
    fn params(&self) -> Vec<ParamInfo> {
        vec![
            p("p1_rel", 0.0, -0.9, 0.9, 1e-5),
            p("p2_rel", 0.0, -0.9, 0.9, 1e-5),
        ]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        e.model.variation.z_mid_m = self.z_mid_m;
        e.model.variation.half_span_m = self.half_span_m;
        e.model.variation.by_position = [x[0], x[1]];
    }
    fn lab_friction(&self, f: &Finding) -> Option<FrictionVariation> {
        let v = values_of(f, &["p1_rel", "p2_rel", "z_lo_m", "z_hi_m"])?;
        Some(FrictionVariation {
            z_mid_m: 0.5 * (v[2] + v[3]),
            half_span_m: 0.5 * (v[3] - v[2]),
            by_position: [v[0], v[1]],
            ..FrictionVariation::default()
        })
    }
    fn position_dependent(&self) -> bool {
        true
    }
    fn refused_at_bound(&self, _param: usize, _lower: bool) -> bool {
        true
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        let (z_mid_m, half_span_m) = (self.z_mid_m, self.half_span_m);
        let est = Estimate::new;
        let mut out = BTreeMap::new();
        let (p1, p2) = (f.x[0], f.x[1]);
        let (mut peak, mut at) = (0.0f64, z_mid_m);
        for j in 0..=200 {
            let x = -1.0 + 2.0 * j as f64 / 200.0;
            let d = p1 * x + p2 * 0.5 * (3.0 * x * x - 1.0);
            if d.abs() > peak.abs() {
                peak = d;
                at = z_mid_m + half_span_m * x;
            }
        }
        // half the range of the relative variation over the stretch: the amplitude "μ varies
        // by ± δ along the groove" that a periodic μ(z) reports as its A, so the two forms of a
        // tie say one size; its error from both coefficients' errors alone (`Fitted` holds no
        // covariance, so their correlation is left out)
        let half = half_range(p1, p2);
        let (h1, h2) = (1e-6f64.max(f.se[0].abs()), 1e-6f64.max(f.se[1].abs()));
        let g1 = (half_range(p1 + h1, p2) - half_range(p1 - h1, p2)) / (2.0 * h1);
        let g2 = (half_range(p1, p2 + h2) - half_range(p1, p2 - h2)) / (2.0 * h2);
        out.insert(
            "delta_mu_rel".into(),
            est(half, (g1 * f.se[0]).hypot(g2 * f.se[1])),
        );
        out.insert("p1_rel".into(), est(p1, f.se[0]));
        out.insert("p2_rel".into(), est(p2, f.se[1]));
        out.insert("peak_rel".into(), est(peak, f64::NAN));
        out.insert("z_at_peak_m".into(), est(at, 0.0));
        out.insert("z_lo_m".into(), est(z_mid_m - half_span_m, 0.0));
        out.insert("z_hi_m".into(), est(z_mid_m + half_span_m, 0.0));
        out
    }
}

/// Half the range of p₁P₁(x) + p₂P₂(x) over x in [−1, 1]: its extremes are at the ends or at
/// the parabola's vertex x = −p₁/(3p₂).
fn half_range(p1: f64, p2: f64) -> f64 {
    let d = |x: f64| p1 * x + p2 * 0.5 * (3.0 * x * x - 1.0);
    let mut values = vec![d(-1.0), d(1.0)];
    if p2 != 0.0 {
        let x = -p1 / (3.0 * p2);
        if x.abs() < 1.0 {
            values.push(d(x));
        }
    }
    let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
    0.5 * (hi - lo)
}

#[cfg(test)]
mod tests {
    use super::half_range;

    #[test]
    fn the_half_range_is_the_amplitude_of_a_variation_over_the_stretch() {
        // a line: from −p1 to p1
        assert!((half_range(0.1, 0.0) - 0.1).abs() < 1e-15);
        // a parabola centred on the stretch: P2 runs from −1/2 to 1
        assert!((half_range(0.0, 0.2) - 0.15).abs() < 1e-15);
        // against a dense grid, vertex inside and outside the stretch
        for &(p1, p2) in &[(-0.10165, -0.20634), (0.3, 0.05), (0.02, -0.4)] {
            let d = |x: f64| p1 * x + p2 * 0.5 * (3.0 * x * x - 1.0);
            let v: Vec<f64> = (0..=20000).map(|j| d(-1.0 + j as f64 / 10000.0)).collect();
            let want = 0.5
                * (v.iter().copied().fold(f64::MIN, f64::max)
                    - v.iter().copied().fold(f64::MAX, f64::min));
            assert!((half_range(p1, p2) - want).abs() < 1e-8, "{p1} {p2}");
        }
    }
}
