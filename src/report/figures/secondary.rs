//! The secondary-collision factor (1 − ks²)/(1 + ks²) against the groove's opening angle: positive
//! (secondary collisions follow) below the bound where ks² = 1, 78.5° for a solid sphere.

use super::common::{legend, line, linear_chart, render, scatter};
use crate::physics::Groove;
use crate::report::style::{self, Marker};
use plotters::prelude::*;

/// The factor for a groove of opening angle `theta_deg` and the chapter's k.
pub fn factor(theta_deg: f64) -> f64 {
    Groove::from_angle_deg(theta_deg).collision_factor()
}

/// The opening angle where the factor changes sign (ks² = 1): 2·asin(1/√k).
pub fn bound_deg(k: f64) -> f64 {
    2.0 * (1.0 / k.sqrt()).asin().to_degrees()
}

/// Render the factor figure for the groove `g` (its angle marked).
pub fn render_fig(g: Groove) -> Result<String, String> {
    let theta = 2.0 * g.s.asin().to_degrees();
    let bound = bound_deg(g.k);
    let curve: Vec<(f64, f64)> = (0..=160)
        .map(|i| 45.0 + i as f64 * 0.5)
        .map(|t| (t, Groove::of_params(t, g.k).collision_factor()))
        .collect();
    let f_here = g.collision_factor();
    render(|root| {
        let mut c = linear_chart(
            root,
            "Velocity-difference factor per collision and re-acceleration",
            (45.0, 110.0),
            (-0.3, 0.6),
            "groove opening angle θ (degrees)",
            "factor (1 − ks²)/(1 + ks²) (dimensionless)",
        )?;
        line(
            &mut c,
            vec![(45.0, 0.0), (110.0, 0.0)],
            style::GREY,
            1,
            false,
            None,
        )?;
        line(
            &mut c,
            curve,
            style::BLACK,
            2,
            false,
            Some("factor, solid sphere k = 5/2"),
        )?;
        let label = format!("bound θ = {bound:.1}° (ks² = 1)");
        line(
            &mut c,
            vec![(bound, -0.3), (bound, 0.6)],
            style::ROLLING,
            2,
            true,
            Some(&label),
        )?;
        let label = format!("this groove: θ = {theta:.1}°, factor {f_here:.3}");
        scatter(
            &mut c,
            &[(theta, f_here)],
            Marker::Diamond,
            style::SLIDING,
            true,
            Some(&label),
        )?;
        legend(&mut c, SeriesLabelPosition::UpperRight)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chapter_groove_factor_and_bound() {
        // ks² = 2.5·sin²(35.3°) = 0.8348 → (1 − 0.8348)/(1 + 0.8348) = 0.0900
        assert!((factor(70.6) - 0.0900).abs() < 5e-4, "{}", factor(70.6));
        assert!((bound_deg(2.5) - 78.46).abs() < 0.01);
        assert!(factor(bound_deg(2.5)).abs() < 1e-12);
    }
}
