//! The groove geometry: the factor `s = sin(θ/2)` and the sphere's inertia factor `k = m R²/I`.

use serde::{Deserialize, Serialize};

/// Geometry of a sphere in a v-groove.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Groove {
    /// `sin(θ/2)` with θ the opening angle of the groove.
    pub s: f64,
    /// `m R² / I`: 5/2 for a solid sphere.
    pub k: f64,
}

/// The chapter's groove, what every stage assumes when its params do not say otherwise.
impl Default for Groove {
    fn default() -> Groove {
        Groove::CHAPTER
    }
}

impl Groove {
    /// The chapter's groove: θ = 70.6°, solid sphere (k = 5/2).
    pub const CHAPTER: Groove = Groove {
        s: 0.577_857_624_383_505_3,
        k: 2.5,
    };

    /// The groove of opening angle `groove_angle_deg` holding a sphere of inertia factor `k`: a
    /// stage's params
    /// `groove_angle_deg` (default 70.6, the chapter's) and `k` (default 2.5).
    pub fn of_params(groove_angle_deg: f64, k: f64) -> Groove {
        Groove {
            k,
            ..Groove::from_angle_deg(groove_angle_deg)
        }
    }

    /// `k s²`, the ratio that sets the rolling decay and the collision factor.
    pub fn ks2(&self) -> f64 {
        self.k * self.s * self.s
    }

    /// A groove of opening angle `theta_deg` holding a solid sphere (k = 5/2).
    pub fn from_angle_deg(theta_deg: f64) -> Groove {
        Groove {
            s: (0.5 * theta_deg).to_radians().sin(),
            k: 2.5,
        }
    }

    /// Fraction of an extra acceleration that survives while rolling: `ks² / (1 + ks²)`.
    pub fn rolling_factor(&self) -> f64 {
        let ks2 = self.ks2();
        ks2 / (1.0 + ks2)
    }

    /// The collision-plus-reacceleration factor `(1 − ks²)/(1 + ks²)` (Eq. 4.18).
    pub fn collision_factor(&self) -> f64 {
        let ks2 = self.ks2();
        (1.0 - ks2) / (1.0 + ks2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chapter_groove_matches_its_angle() {
        let g = Groove::from_angle_deg(70.6);
        assert!((g.s - Groove::CHAPTER.s).abs() < 1e-15);
        assert!((Groove::CHAPTER.ks2() - 0.8348).abs() < 1e-4);
        assert!((Groove::CHAPTER.collision_factor() - 0.090).abs() < 5e-4);
    }
}
