//! Estimates of the particle–particle friction μ_pp from the impacts of a dataset: the slope of
//! the target's spin change against its velocity change over slip impacts, and a fit of the
//! whole impulse model (stick and slip together).

use super::impulse::spin_change;
use crate::artifacts::collision_fit::{Contact, ImpactFit};

/// μ_pp = slope / k of y = −sign(S)·Δv_a2 against x = Δv_z2 through the origin, slip impacts.
pub fn slip_slope(impacts: &[&ImpactFit], k: f64) -> Option<f64> {
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for im in impacts.iter().filter(|im| im.contact == Contact::Slip) {
        let x = im.target_dvz_mps.value;
        let y = -im.spin_sum_before_mps.signum() * im.target_dva_mps.value;
        sxy += x * y;
        sxx += x * x;
    }
    (sxx > 0.0).then(|| sxy / sxx / k)
}

/// μ_pp minimizing Σ (Δv_a,meas − Δv_a,model(μ))² / se² over both particles of every impact
/// with resolved spins, by a log-grid search refined by golden sections.
pub fn impulse_fit(impacts: &[&ImpactFit], k: f64) -> Option<f64> {
    let used: Vec<&&ImpactFit> = impacts
        .iter()
        .filter(|im| im.contact != Contact::Undetermined)
        .collect();
    if !used.iter().any(|im| im.contact == Contact::Slip) {
        return None;
    }
    let cost = |mu: f64| -> f64 {
        used.iter()
            .map(|im| {
                let (pred, _) = spin_change(im.spin_sum_before_mps, im.target_dvz_mps.value, mu, k);
                let w = |se: Option<f64>| 1.0 / se.unwrap_or(1.0).max(1e-4).powi(2);
                w(im.target_dva_mps.se) * (im.target_dva_mps.value - pred).powi(2)
                    + w(im.striker_dva_mps.se) * (im.striker_dva_mps.value - pred).powi(2)
            })
            .sum()
    };
    let grid: Vec<f64> = (0..=240)
        .map(|i| 0.01 * 10f64.powf(i as f64 / 80.0))
        .collect();
    let best = (0..grid.len()).min_by(|&a, &b| cost(grid[a]).total_cmp(&cost(grid[b])))?;
    let (mut lo, mut hi) = (
        grid[best.saturating_sub(1)],
        grid[(best + 1).min(grid.len() - 1)],
    );
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..60 {
        let (a, b) = (hi - g * (hi - lo), lo + g * (hi - lo));
        if cost(a) < cost(b) {
            hi = b;
        } else {
            lo = a;
        }
    }
    Some(0.5 * (lo + hi))
}
