//! The noise floor of a scan over frequencies measured on the data itself: each trial's ratio of
//! the data's statistic to its replicates' mean, taken as a running median over the trials
//! around it (its own neighbours left out), so that a noise the replicates model too weakly (a
//! correlated tracking noise that is not quite AR(1)) raises the null where it does, while a
//! real peak, a few trials wide, moves no median.

/// Trials left out on each side of a trial (a peak's main lobe and its first side lobes).
pub const GUARD: usize = 3;
/// Trials on each side that the median is taken over, the guard included.
pub const HALF_WIDTH: usize = 30;

/// For each trial, the median of `ratio` over the trials within `HALF_WIDTH` of it but more
/// than `GUARD` away (`None`: a trial with no statistic, skipped), at least 1 (the replicates'
/// model is kept where the data are not noisier than it); 1 where fewer than 8 ratios are there.
pub fn local_floor(ratio: &[Option<f64>]) -> Vec<f64> {
    (0..ratio.len())
        .map(|i| {
            let lo = i.saturating_sub(HALF_WIDTH);
            let hi = (i + HALF_WIDTH + 1).min(ratio.len());
            let mut near: Vec<f64> = (lo..hi)
                .filter(|&j| j.abs_diff(i) > GUARD)
                .filter_map(|j| ratio[j])
                .filter(|r| r.is_finite())
                .collect();
            if near.len() < 8 {
                return 1.0;
            }
            crate::stats::median_in_place(&mut near).max(1.0)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_peak_moves_no_floor_and_a_raised_noise_raises_it() {
        // a flat ratio of 1 with a peak of 50 three trials wide: the floor stays 1 everywhere
        let mut ratio: Vec<Option<f64>> = vec![Some(1.0); 100];
        for r in &mut ratio[49..52] {
            *r = Some(50.0);
        }
        assert!(local_floor(&ratio).iter().all(|f| (*f - 1.0).abs() < 1e-12));
        // the data 20 % noisier than the replicates from trial 60 on: the floor follows
        let ratio: Vec<Option<f64>> = (0..100)
            .map(|i| Some(if i >= 60 { 1.2 } else { 0.9 }))
            .collect();
        let floor = local_floor(&ratio);
        assert_eq!(
            floor[10], 1.0,
            "a quieter noise keeps the replicates' model"
        );
        assert!((floor[95] - 1.2).abs() < 1e-12);
        // trials with no statistic are skipped, and too few neighbours leave the model as it is
        let sparse: Vec<Option<f64>> = (0..100).map(|i| (i % 20 == 0).then_some(3.0)).collect();
        assert!(local_floor(&sparse).iter().all(|f| *f == 1.0));
    }
}
