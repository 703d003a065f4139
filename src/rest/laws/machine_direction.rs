//! Linear differential swelling with a machine direction (`growth.law = "machine_direction"`,
//! seed 000 §3): with `d` the direction (barycentric), `d⊥` its `a⁰`-orthogonal complement,
//! `P = [d d⊥]` and `M(z) = diag(1 + μ m(z), 1 + μ⊥ m(z))` in the `(d, d⊥)` basis,
//! `ḡ(z) = P⁻ᵀ M(z) Pᵀ (a⁰ + 2z b⁰) P M(z) P⁻¹` (seed 000's `TᵀMT⁻ᵀ(·)T⁻¹MT` with `T = P⁻¹`),
//! projected as in [`super`]. With `μ⊥ = μ` it is [`super::linear_swelling`]. The thickness is
//! kept, unless `growth.mu_through` grows it ([`super::through_thickness`]). Coefficients:
//! `growth.mu` along, `growth.mu_perp` across (per unit moisture, per face when regions or face
//! fields give them); the direction from the face field `machine_direction` or
//! `growth.machine_direction`.
//! Units: ā in m², b̄ in m.

use super::{
    check_stretch, moisture_at, project_through_thickness, reference_metric, through_thickness,
    FaceInput, Grown, GrowthError, LawEntry, RestLaw,
};
use crate::config::growth::{GrowthLaw, GrowthModel};
use crate::math::{sym_to_mat, Mat2, Real, Sym2};

/// Swelling with a machine direction, each face's `mu` along it and `mu_perp` across
/// ([`super::Coefficients`]).
#[derive(Debug)]
pub struct MachineDirection;

/// The registry's entry ([`super::LAWS`]).
pub const ENTRY: LawEntry = LawEntry {
    law: GrowthLaw::MachineDirection,
    example: "mu = 0.02\nmu_perp = 0.06\nmoisture_top = 0.4\nmoisture_bottom = 0.1\nmachine_direction = [1, 1, 0]",
    build: |m| {
        matches!(m, GrowthModel::MachineDirection { .. })
            .then(|| Box::new(MachineDirection) as Box<dyn RestLaw>)
    },
};

/// Linear swelling with a machine direction `d` (barycentric, non-zero): `mu` along `d`,
/// `mu_perp` across it (see the module doc).
#[allow(clippy::too_many_arguments)]
pub fn machine_direction(
    a0: &Sym2,
    b0: &Sym2,
    h: Real,
    m_top: Real,
    m_bottom: Real,
    mu: Real,
    mu_perp: Real,
    d: [Real; 2],
) -> (Sym2, Sym2) {
    let (p, pinv) = direction_frame(a0, d);
    project_through_thickness(h, |z| {
        let m = moisture_at(z, h, m_top, m_bottom);
        let mz = Mat2::new(1.0 + mu * m, 0.0, 0.0, 1.0 + mu_perp * m);
        pinv.transpose() * mz * p.transpose() * reference_metric(a0, b0, z) * p * mz * pinv
    })
}

/// `P = [d d⊥]` and `P⁻¹` for a machine direction `d` (barycentric) and its
/// `a⁰`-orthogonal complement `d⊥` (the identity when `d` is degenerate).
pub(crate) fn direction_frame(a0: &Sym2, d: [Real; 2]) -> (Mat2, Mat2) {
    let a = sym_to_mat(a0);
    let dv = crate::math::Vec2::new(d[0], d[1]);
    // d⊥ ⟂ d in the metric a⁰: rotate a⁰d by 90° in the plane.
    let ad = a * dv;
    let dp = crate::math::Vec2::new(-ad.y, ad.x);
    let p = Mat2::new(dv.x, dp.x, dv.y, dp.y);
    match p.try_inverse() {
        Some(pinv) => (p, pinv),
        None => (Mat2::identity(), Mat2::identity()),
    }
}

impl RestLaw for MachineDirection {
    fn grow(&self, i: &FaceInput) -> Result<Grown, GrowthError> {
        let (mu, mp) = (i.coef.mu, i.coef.mu_perp);
        check_stretch(i, mu, true, true)?;
        check_stretch(i, mp, true, true)?;
        through_thickness(
            i,
            machine_direction(&i.a0, &i.b0, i.h, i.m_top, i.m_bottom, mu, mp, i.direction),
        )
    }
    fn needs_direction(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::super::close;
    use super::super::linear_swelling::linear_swelling;
    use super::*;

    #[test]
    fn machine_direction_limits() {
        let a0 = Sym2::new(1.0, 0.3, 1.2);
        let b0 = Sym2::new(0.2, 0.0, -0.1);
        let (h, mt, mb) = (0.01, 0.3, 0.1);
        // μ⊥ = μ: the isotropic law, for any direction.
        let iso = linear_swelling(&a0, &b0, h, mt, mb, 0.2);
        let md = machine_direction(&a0, &b0, h, mt, mb, 0.2, 0.2, [0.3, 0.7]);
        assert!(close(&md.0, &iso.0, 1e-13) && close(&md.1, &iso.1, 1e-12));
        // μ⊥ = 0, flat identity metric, d = e1: only the d direction stretches.
        let (a, b) = machine_direction(
            &Sym2::new(1.0, 0.0, 1.0),
            &Sym2::zeros(),
            h,
            0.2,
            0.2,
            0.5,
            0.0,
            [1.0, 0.0],
        );
        assert!(
            close(&a, &Sym2::new(1.1f64.powi(2), 0.0, 1.0), 1e-14),
            "{a:?}"
        );
        assert!(b.amax() < 1e-13);
        // The direction's length does not matter.
        let m1 = machine_direction(&a0, &b0, h, mt, mb, 0.3, 0.1, [0.3, 0.7]);
        let m2 = machine_direction(&a0, &b0, h, mt, mb, 0.3, 0.1, [0.9, 2.1]);
        assert!(close(&m1.0, &m2.0, 1e-13) && close(&m1.1, &m2.1, 1e-12));
    }
}
