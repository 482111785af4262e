//! The impact laws the whole-run fits carried from discovery (a restitution law, μ_pp depending
//! on the slip speed), in words.

use crate::physics::{Restitution, SlipFriction, SlipShape};
use crate::report::value::sig;

fn g(x: f64) -> String {
    sig(x, 3)
}

/// `0.81 at 20 mm/s, 0.62 at 50 mm/s, …`
fn nodes(speeds_mps: &[f64], values: &[f64]) -> String {
    speeds_mps
        .iter()
        .zip(values)
        .map(|(v, y)| format!("{} at {} mm/s", g(*y), g(1e3 * v)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A restitution law taken from discovery in words, with its parameters (a map at its
/// refitted values).
pub fn discovered_law(law: &Restitution) -> String {
    match *law {
        Restitution::Map(m) => format!(
            "discovery's map, its values refitted: C = {} (linear in ln v between the nodes, the end values beyond)",
            nodes(&m.speeds_mps(), m.values())
        ),
        Restitution::Viscoelastic { a } => {
            format!("viscoelastic, held from discovery: 1 − C = {} v^(1/5)", g(a))
        }
        Restitution::Adhesive {
            c_elastic,
            v_stick_mps,
        } => format!(
            "adhesive, held from discovery: C = {} √(1 − (v_s/v)²), v_s = {} mm/s",
            g(c_elastic),
            g(1e3 * v_stick_mps)
        ),
        Restitution::AdhesiveYield {
            c_elastic,
            v_stick_mps,
            v_yield_mps,
        } => format!(
            "adhesive with yield, held from discovery: C = {} √(1 − (v_s/v)²) e^(−v/v_y), v_s = {} mm/s, v_y = {} mm/s",
            g(c_elastic),
            g(1e3 * v_stick_mps),
            g(1e3 * v_yield_mps)
        ),
        Restitution::PowerLaw {
            c_ref,
            v_ref_mps,
            exponent,
        } => format!(
            "power law, held from discovery: C = {} (v / {} mm/s)^(−{})",
            g(c_ref),
            g(1e3 * v_ref_mps),
            g(exponent)
        ),
        Restitution::Constant(c) => format!("held from discovery: C = {}", g(c)),
        Restitution::SpeedDependent { c0, v_ref_mps } => format!(
            "held from discovery: C = {} + (1 − {0}) e^(−v/{} mm/s)",
            g(c0),
            g(1e3 * v_ref_mps)
        ),
        Restitution::Linear { c0, slope_per_mps } => format!(
            "held from discovery: C = {} − {} v",
            g(c0),
            g(slope_per_mps)
        ),
    }
}

/// μ_pp's dependence on the slip speed u in words: μ_pp(u) = μ_pp · s(u)/s(u_ref).
pub fn slip_law(s: &SlipFriction) -> String {
    let shape = match s.shape {
        SlipShape::Map(m) => format!(
            "s(u) discovery's map of μ_pp ({}; linear in ln u between, the end values beyond)",
            nodes(&m.speeds_mps(), m.values())
        ),
        SlipShape::Linear {
            at_zero_slip,
            fall_per_mps,
        } => format!(
            "s(u) = {} − {} u (linear, from discovery)",
            g(at_zero_slip),
            g(fall_per_mps)
        ),
        SlipShape::Weakening { slip_scale_mps } => format!(
            "s(u) = 1/(1 + u/u0), u0 = {} mm/s (weakening, from discovery)",
            g(1e3 * slip_scale_mps)
        ),
    };
    format!(
        "μ_pp depends on the slip speed u at the contact: μ_pp(u) = μ_pp · s(u)/s(u_ref), {shape}; μ_pp is its value at u_ref = {} mm/s",
        g(1e3 * s.u_ref_mps)
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::LnMap;

    #[test]
    fn carried_laws_are_said_with_their_numbers() {
        let h = Restitution::Map(LnMap::new(&[0.02, 0.05], &[0.81, 0.62]).unwrap());
        assert_eq!(
            discovered_law(&h),
            "discovery's map, its values refitted: C = 0.810 at 20.0 mm/s, 0.620 at 50.0 mm/s (linear in ln v between the nodes, the end values beyond)"
        );
        let w = SlipFriction {
            shape: SlipShape::Weakening {
                slip_scale_mps: 0.05,
            },
            u_ref_mps: 0.12,
        };
        let words = slip_law(&w);
        assert!(
            words.contains("u0 = 50.0 mm/s") && words.ends_with("u_ref = 120 mm/s"),
            "{words}"
        );
    }
}
