//! Small statistics shared by the fits, the collision fits and the discoverer: medians and robust
//! scales (each convention named once), straight-line fits (and Theil–Sen slopes of resamples), quantiles of bootstrap draws, and the
//! distributions behind p-values (from `statrs`).
//!
//! Files of this folder:
//!
//! - `dist.rs`: Tail probabilities and quantiles for the tests
//! - `intercept_order.rs`: Theil–Sen intercepts of bootstrap resamples without a selection over every pick
//! - `line.rs`: Straight-line fits
//! - `median.rs`: Medians and median-based scales
//! - `quantile.rs`: Quantiles of sorted bootstrap draws, in the two conventions the intervals use
//! - `slope_order.rs`: Theil–Sen slopes of bootstrap resamples without redrawing pairs

pub mod dist;
pub mod intercept_order;
pub mod line;
pub mod median;
pub mod quantile;
pub mod slope_order;

pub use intercept_order::InterceptOrder;
pub use line::{
    ols_indexed, ols_line, theil_sen_indexed, theil_sen_intercept, theil_sen_many, weighted_line,
    Line,
};
pub use median::{abs_scale, mad_scale, median_in_place, upper_median, MAD_TO_SIGMA};
pub use quantile::{quantile_interpolated, quantile_nearest};
pub use slope_order::{SlopeOrder, LANES as SLOPE_LANES};
