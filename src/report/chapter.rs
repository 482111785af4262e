//! The chapter's printed values and the constants used to check them.

/// T = T0 + T'·v0 as printed (Fig. 4.2c and text): intercept in s.
pub const T0_S: f64 = 0.052;
/// T = T0 + T'·v0 as printed: slope in s per (m/s).
pub const T_SLOPE_S_PER_MPS: f64 = 1.10;
/// Eq. 4.8: L in metres.
pub const L_M: f64 = 2.5e-3;
/// μ_pg means for v0 > 0.03 m/s (text and Eq. 4.8).
pub const MU_316: f64 = 0.337;
pub const MU_440C: f64 = 0.293;
/// μ_pg of 440c as printed in the caption of Fig. 4.2.
pub const MU_440C_CAPTION: f64 = 0.296;
/// The v0 threshold of the chapter's μ means (m/s).
pub const MU_MEAN_V0_MIN_MPS: f64 = 0.03;
/// Particle–particle friction (Fig. 4.4a).
pub const MU_PP: f64 = 1.4;
/// Secondary-collision factor as printed (Eq. 4.18 text) and the angle bound.
pub const SECONDARY_FACTOR: f64 = 0.09;
pub const THETA_BOUND_DEG: f64 = 78.5;
/// Groove opening angle (degrees).
pub const THETA_DEG: f64 = 70.6;
/// Stokes time as printed (s).
pub const STOKES_PRINTED_S: f64 = 0.074;
/// Fig. 4.2b: the typical trajectory's initial speed (m/s).
pub const FIG_4_2B_V0_MPS: f64 = 0.025;
/// Striker speed reached in Sect. 4.4 (m/s) and laser momentum scatter (relative SD).
pub const STRIKER_MAX_MPS: f64 = 0.3;
pub const LASER_SCATTER: f64 = 0.15;

/// Particle radius (m), density (kg/m³) and air viscosity (Pa·s) of the Stokes check.
pub const RADIUS_M: f64 = 150e-6;
pub const DENSITY_KG_M3: f64 = 7900.0;
pub const AIR_VISCOSITY_PA_S: f64 = 1.81e-5;

/// Stokes drag time m/(6πηR) of a sphere of radius `r_m` and density `rho`: 2ρR²/(9η).
pub fn stokes_time_s(r_m: f64, rho_kg_m3: f64, eta_pa_s: f64) -> f64 {
    let m_kg = rho_kg_m3 * 4.0 / 3.0 * std::f64::consts::PI * r_m.powi(3);
    m_kg / (6.0 * std::f64::consts::PI * eta_pa_s * r_m)
}

/// The chapter's T(v0) line.
pub fn t_line_s(v0_mps: f64) -> f64 {
    T0_S + T_SLOPE_S_PER_MPS * v0_mps.abs()
}

/// The chapter's μ mean for a material name, if it gives one.
pub fn mu_for(material: &str) -> Option<f64> {
    match material.to_ascii_lowercase().as_str() {
        "316" | "ss316" => Some(MU_316),
        "440c" | "ss440c" => Some(MU_440C),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stokes_time_is_about_two_seconds() {
        let t = stokes_time_s(RADIUS_M, DENSITY_KG_M3, AIR_VISCOSITY_PA_S);
        // 2ρR²/(9η) = 2·7900·2.25e-8/(9·1.81e-5) = 2.182 s
        assert!((t - 2.182).abs() < 0.002, "{t}");
        assert!((t_line_s(0.02) - 0.074).abs() < 1e-12);
    }
}
