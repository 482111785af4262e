//! Holm's step-down correction for testing several candidates at once.

/// Holm-adjusted p-values, in the input order (monotone, ≤ 1).
pub fn holm(p: &[f64]) -> Vec<f64> {
    let m = p.len();
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|a, b| p[*a].total_cmp(&p[*b]).then(a.cmp(b)));
    let mut adj = vec![0.0; m];
    let mut running: f64 = 0.0;
    for (rank, &i) in order.iter().enumerate() {
        running = running.max(((m - rank) as f64 * p[i]).min(1.0));
        adj[i] = running;
    }
    adj
}

#[cfg(test)]
mod tests {
    #[test]
    fn matches_hand_computation() {
        // sorted 0.01, 0.02, 0.04 with m = 3: 0.03, 0.04, 0.04
        let a = super::holm(&[0.04, 0.01, 0.02]);
        assert_eq!(a, vec![0.04, 0.03, 0.04]);
    }
}
