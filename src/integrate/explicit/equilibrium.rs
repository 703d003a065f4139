//! The explicit driver's equilibrium test (see the module doc of [`super`]): the window test and
//! MorphoShell's force-and-speed test, and the residual a frame reports.

use super::{gradient, Scales};
use crate::energy::Potential;
use crate::math::{Real, Vec3};
use crate::settings::{EquilibriumTest, Explicit};

/// The largest force (N) a term leaves unbalanced on a degree of freedom of its own
/// ([`crate::energy::term::ExplicitHooks::explicit_unbalanced`]), or why one never balances.
pub(super) fn unbalanced(pot: &Potential, x: &[Vec3]) -> Result<Real, String> {
    let mut worst: Real = 0.0;
    for hooks in pot.terms.iter().filter_map(|t| t.explicit()) {
        worst = worst.max(hooks.explicit_unbalanced(pot, x)?);
    }
    Ok(worst)
}

/// The residual a frame reports: the window test's force measure `‖∇Φ‖∞ / F`, the terms'
/// unbalanced forces included, at positions `x` (`g` is scratch).
pub(super) fn residual_at(pot: &Potential, x: &[Vec3], g: &mut [Real]) -> Real {
    gradient(pot, x, g);
    let f = pot.body.force_scale.max(Real::MIN_POSITIVE);
    pot.residual(g).max(unbalanced(pot, x).unwrap_or(0.0) / f)
}

/// A snapshot for the window test.
pub(super) struct Window {
    /// The positions at the window's start.
    pub(super) x: Vec<Vec3>,
    /// Φ there (J; NaN before the first window).
    pub(super) energy: Real,
}

/// The state one window test looks at: positions, velocities (m/s), the gradient `∇Φ` (N),
/// the energy Φ and kinetic energy (J), the largest force a term leaves unbalanced (N), and the
/// drag rate of the phase (1/s).
pub(super) struct Sample<'a> {
    pub(super) x: &'a [Vec3],
    pub(super) v: &'a [Vec3],
    pub(super) g: &'a [Real],
    pub(super) energy: Real,
    pub(super) kinetic: Real,
    pub(super) unbalanced: Real,
    pub(super) drag: Real,
}

/// The equilibrium test of a run: its settings, scales and masses.
pub(super) struct Test<'a> {
    pub(super) cf: &'a Explicit,
    pub(super) sca: &'a Scales,
    /// The sheet's size, its bounding-box diagonal (m).
    pub(super) size: Real,
    /// Newton's force scale F (N), at least the smallest positive number.
    pub(super) force_scale: Real,
    pub(super) inv_m: &'a [Real],
    pub(super) mass: &'a [Real],
}

impl Test<'_> {
    /// Whether `s` is at rest against the last window `w`, by `explicit.equilibrium`:
    /// `"window"`, the force residual `‖∇Φ‖∞ / F` (unbalanced forces included) below
    /// `force_tolerance`, the largest displacement over the window below `shape_tolerance` × the
    /// size, the change of Φ over the window and the kinetic energy below `energy_tolerance` ×
    /// max(|Φ|, `energy_floor`); `"morphoshell"`, the largest node force (drag and unbalanced
    /// forces included) below `morphoshell_force_threshold` × μ t a_min and the largest speed
    /// below `morphoshell_speed_threshold` × √(μ/ρ).
    pub(super) fn at_rest(
        &self,
        pot: &Potential,
        s: &Sample,
        w: &Window,
        energy_floor: Real,
    ) -> bool {
        let (cf, sca) = (self.cf, self.sca);
        match cf.equilibrium {
            EquilibriumTest::Window => {
                let r = pot.residual(s.g).max(s.unbalanced / self.force_scale);
                let moved =
                    s.x.iter()
                        .zip(&w.x)
                        .map(|(a, b)| (a - b).norm())
                        .fold(0.0, Real::max);
                let scale = s.energy.abs().max(energy_floor).max(Real::MIN_POSITIVE);
                r <= cf.force_tolerance
                    && moved <= cf.shape_tolerance * self.size
                    && (s.energy - w.energy).abs() <= cf.energy_tolerance * scale
                    && s.kinetic <= cf.energy_tolerance * scale
            }
            EquilibriumTest::Morphoshell => {
                let (mut fmax, mut vmax): (Real, Real) = (0.0, 0.0);
                for i in 0..s.x.len() {
                    if self.inv_m[i] == 0.0 {
                        continue;
                    }
                    let f = -Vec3::new(s.g[3 * i], s.g[3 * i + 1], s.g[3 * i + 2])
                        - s.v[i] * (s.drag * self.mass[i]);
                    fmax = fmax.max(f.norm());
                    vmax = vmax.max(s.v[i].norm());
                }
                fmax = fmax.max(s.unbalanced);
                fmax / (sca.mu * sca.t * sca.a_min) < cf.morphoshell_force_threshold
                    && vmax / (sca.mu / sca.rho).sqrt() < cf.morphoshell_speed_threshold
            }
        }
    }
}
