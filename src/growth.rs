//! Rest-form laws of seed 000 §3 ("Choosing Rest Fundamental Forms"): pure functions from
//! per-face fields to the rest forms `(ā, b̄)` of a face, in the face's barycentric frame.
//!
//! ## One derivation for every law
//! Each law prescribes the rest *metric of the 3D shell* at every height `z ∈ [−h/2, h/2]` above
//! the mid-surface, `ḡ(z)` (a 2×2 tensor in the face's barycentric frame). The Koiter energy
//! only sees the part of `ḡ` linear in `z`, `ḡ(z) ≈ ā + 2z b̄` (shellsim's sign: offsetting
//! toward the normal by `z` turns `a` into `a + 2z b`, so that a positive `b̄` bulges toward the
//! normal). shellsim takes the least-squares projection of `ḡ` onto linear functions of `z`:
//!
//! `ā = (1/h) ∫ ḡ(z) dz`,   `b̄ = (6/h³) ∫ z ḡ(z) dz`,
//!
//! evaluated with 3-point Gauss–Legendre quadrature on each half `[−h/2, 0]`, `[0, h/2]`, which
//! is exact for every law below (each is a polynomial of degree ≤ 3 in `z` on each half).
//!
//! The reference shell's own metric at height `z` is `a⁰ + 2z b⁰`.
//!
//! * **No growth**: `ḡ = a⁰ + 2z b⁰`, so `(ā, b̄) = (a⁰, b⁰)`.
//! * **Isotropic growth** with conformal factor `s` (uniform through the thickness):
//!   `ḡ = e^{2s}(a⁰ + 2z b⁰)`, so `ā = e^{2s} a⁰`, `b̄ = e^{2s} b⁰`. (Seed 000 writes `b̄ = b⁰`;
//!   the two agree for the flat sheets it uses. Growing the metric at every height by the same
//!   factor scales `b̄` with it, which keeps the reference curvature `a⁻¹b` of a curved shell.)
//! * **Linear differential swelling**: moisture varies linearly from `m⁻` (bottom, `z = −h/2`)
//!   to `m⁺` (top, `z = +h/2`), and lengths scale by `1 + μ m(z)`:
//!   `ḡ = (1 + μ m(z))² (a⁰ + 2z b⁰)`. With `s₀ = 1 + μ(m⁺ + m⁻)/2` and `s₁ = μ(m⁺ − m⁻)/h`:
//!   `ā = (s₀² + s₁²h²/12) a⁰ + (s₀ s₁ h²/3) b⁰`, `b̄ = s₀ s₁ a⁰ + (s₀² + 3 s₁²h²/20) b⁰`.
//!   Seed 000 gives two different expressions: `ā` from the end values `(ḡ⁺ + ḡ⁻)/2` (which
//!   weights the `z²` term by h²/4 instead of h²/12) and `b̄ = (ḡ⁻ − ḡ⁺)/(2h)` (the same `s₀s₁`
//!   term, opposite sign convention); the projection is the one consistent with the energy.
//!   `m⁺ = m⁻` leaves a flat sheet flat; a wetter top (`m⁺ > m⁻`, μ > 0) gives `b̄ > 0`: the
//!   sheet bulges toward the wet side's normal, i.e. curls away from the water.
//! * **Piecewise-constant bilayer** (van Rees et al. 2017): the top half has metric
//!   `(1 + μ⁺ m⁺)²(a⁰ + 2z b⁰)`, the bottom half `(1 + μ⁻ m⁻)²(a⁰ + 2z b⁰)`. For a flat
//!   reference, `ā = (ḡ⁺ + ḡ⁻)/2`, `b̄ = 3(ḡ⁺ − ḡ⁻)/(4h)`: van Rees' equivalence, which with
//!   equal layers reproduces Timoshenko's κ = 3Δε/(2h).
//! * **Linear differential swelling with a machine direction** `d` (a barycentric vector): with
//!   `d⊥` its `a⁰`-orthogonal complement, `P = [d d⊥]` and
//!   `M(z) = diag(1 + μ m(z), 1 + μ⊥ m(z))` in the `(d, d⊥)` basis,
//!   `ḡ(z) = P⁻ᵀ M(z) Pᵀ (a⁰ + 2z b⁰) P M(z) P⁻¹` (seed 000's `TᵀMT⁻ᵀ(·)T⁻¹MT` with
//!   `T = P⁻¹`). With `μ⊥ = μ` it is the isotropic linear swelling above.
//!
//! Units: `a`, `ā` in m² (barycentric), `b`, `b̄` in m, `h` in m, moisture `m` dimensionless
//! (seed 000 uses percent; shellsim uses fractions), `μ` per unit moisture.

use crate::math::{mat_to_sym, sym_to_mat, Mat2, Real, Sym2};

/// Gauss–Legendre nodes and weights on [−1, 1] (3 points, exact to degree 5).
const GAUSS3: [(Real, Real); 3] = [
    (-0.774_596_669_241_483_4, 5.0 / 9.0),
    (0.0, 8.0 / 9.0),
    (0.774_596_669_241_483_4, 5.0 / 9.0),
];

/// Projects a through-thickness metric `g(z)` onto `ā + 2z b̄` (see the module doc). `g` may be
/// discontinuous at `z = 0`; it is sampled strictly inside each half.
pub fn project_through_thickness(h: Real, g: impl Fn(Real) -> Mat2) -> (Sym2, Sym2) {
    let mut mean = Mat2::zeros();
    let mut moment = Mat2::zeros();
    for (lo, hi) in [(-0.5 * h, 0.0), (0.0, 0.5 * h)] {
        let (c, r) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        for (t, w) in GAUSS3 {
            let z = c + r * t;
            let gz = g(z);
            mean += gz * (w * r);
            moment += gz * (w * r * z);
        }
    }
    let abar = mean / h;
    let bbar = moment * (6.0 / (h * h * h));
    (mat_to_sym(&abar), mat_to_sym(&bbar))
}

/// The reference shell's metric at height `z`: `a⁰ + 2z b⁰`.
#[inline]
fn reference_metric(a0: &Sym2, b0: &Sym2, z: Real) -> Mat2 {
    sym_to_mat(a0) + sym_to_mat(b0) * (2.0 * z)
}

/// Isotropic growth: `(e^{2s} a⁰, e^{2s} b⁰)`.
pub fn isotropic(a0: &Sym2, b0: &Sym2, s: Real) -> (Sym2, Sym2) {
    let f = (2.0 * s).exp();
    (a0 * f, b0 * f)
}

/// Linear differential swelling with moisture `m_top` at `z = +h/2`, `m_bottom` at `z = −h/2`
/// and moisture-length coefficient `mu`.
pub fn linear_swelling(
    a0: &Sym2,
    b0: &Sym2,
    h: Real,
    m_top: Real,
    m_bottom: Real,
    mu: Real,
) -> (Sym2, Sym2) {
    project_through_thickness(h, |z| {
        let m = moisture_at(z, h, m_top, m_bottom);
        let s = 1.0 + mu * m;
        reference_metric(a0, b0, z) * (s * s)
    })
}

/// Piecewise-constant bilayer: top half swells by `1 + mu_top m_top`, bottom half by
/// `1 + mu_bottom m_bottom`.
pub fn bilayer(
    a0: &Sym2,
    b0: &Sym2,
    h: Real,
    m_top: Real,
    m_bottom: Real,
    mu_top: Real,
    mu_bottom: Real,
) -> (Sym2, Sym2) {
    project_through_thickness(h, |z| {
        let s = if z > 0.0 {
            1.0 + mu_top * m_top
        } else {
            1.0 + mu_bottom * m_bottom
        };
        reference_metric(a0, b0, z) * (s * s)
    })
}

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
    let a = sym_to_mat(a0);
    let dv = crate::math::Vec2::new(d[0], d[1]);
    // d⊥ ⟂ d in the metric a⁰: rotate a⁰d by 90° in the plane.
    let ad = a * dv;
    let dp = crate::math::Vec2::new(-ad.y, ad.x);
    let p = Mat2::new(dv.x, dp.x, dv.y, dp.y);
    let pinv = p.try_inverse().unwrap_or_else(Mat2::identity);
    project_through_thickness(h, |z| {
        let m = moisture_at(z, h, m_top, m_bottom);
        let mz = Mat2::new(1.0 + mu * m, 0.0, 0.0, 1.0 + mu_perp * m);
        pinv.transpose() * mz * p.transpose() * reference_metric(a0, b0, z) * p * mz * pinv
    })
}

/// Moisture at height `z`, linear between `m_bottom` at `−h/2` and `m_top` at `+h/2`.
#[inline]
fn moisture_at(z: Real, h: Real, m_top: Real, m_bottom: Real) -> Real {
    0.5 * (m_top + m_bottom) + (m_top - m_bottom) * z / h
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &Sym2, b: &Sym2, tol: Real) -> bool {
        (a - b).amax() <= tol * (1.0 + b.amax())
    }

    #[test]
    fn equal_moisture_keeps_a_flat_sheet_flat() {
        let a0 = Sym2::new(1.0, 0.2, 0.8);
        let (a, b) = linear_swelling(&a0, &Sym2::zeros(), 0.01, 0.3, 0.3, 0.05);
        assert!(close(&a, &(a0 * 1.015f64.powi(2)), 1e-14));
        assert!(b.amax() < 1e-14);
    }

    #[test]
    fn wetter_top_bulges_toward_the_normal() {
        let a0 = Sym2::new(1.0, 0.0, 1.0);
        let (_, b) = linear_swelling(&a0, &Sym2::zeros(), 0.01, 0.4, 0.0, 0.1);
        assert!(b[0] > 0.0 && b[2] > 0.0);
        let (_, b) = linear_swelling(&a0, &Sym2::zeros(), 0.01, 0.0, 0.4, 0.1);
        assert!(b[0] < 0.0 && b[2] < 0.0);
    }

    #[test]
    fn linear_swelling_matches_the_closed_form() {
        // ā = (s₀² + s₁²h²/12) a⁰ + (s₀s₁h²/3) b⁰, b̄ = s₀s₁ a⁰ + (s₀² + 3s₁²h²/20) b⁰.
        let (a0, b0) = (Sym2::new(1.0, 0.1, 0.9), Sym2::new(0.3, -0.1, 0.2));
        let (h, mt, mb, mu) = (0.02, 0.5, -0.2, 0.3);
        let s0 = 1.0 + mu * (mt + mb) / 2.0;
        let s1 = mu * (mt - mb) / h;
        let ea = a0 * (s0 * s0 + s1 * s1 * h * h / 12.0) + b0 * (s0 * s1 * h * h / 3.0);
        let eb = a0 * (s0 * s1) + b0 * (s0 * s0 + 0.15 * s1 * s1 * h * h);
        let (a, b) = linear_swelling(&a0, &b0, h, mt, mb, mu);
        assert!(close(&a, &ea, 1e-14), "{a:?} vs {ea:?}");
        assert!(close(&b, &eb, 1e-13), "{b:?} vs {eb:?}");
    }

    #[test]
    fn bilayer_is_van_rees_and_timoshenko() {
        let a0 = Sym2::new(1.0, 0.0, 1.0);
        let (h, de) = (0.002, 0.002);
        // Layers stretched by 1 ± Δε/2: μ = 1, m± = ±Δε/2.
        let (a, b) = bilayer(&a0, &Sym2::zeros(), h, de / 2.0, -de / 2.0, 1.0, 1.0);
        let (gp, gm) = ((1.0 + de / 2.0).powi(2), (1.0 - de / 2.0).powi(2));
        assert!(close(&a, &(a0 * ((gp + gm) / 2.0)), 1e-14));
        assert!(close(&b, &(a0 * (3.0 * (gp - gm) / (4.0 * h))), 1e-13));
        // Timoshenko, equal layers: κ = 3Δε/(2h) (to O(Δε²)).
        let kappa = b[0] / a[0];
        assert!((kappa / (1.5 * de / h) - 1.0).abs() < 1e-5, "{kappa}");
    }

    #[test]
    fn isotropic_growth_scales_both_forms() {
        let (a0, b0) = (Sym2::new(1.0, 0.1, 0.9), Sym2::new(0.3, -0.1, 0.2));
        let (a, b) = isotropic(&a0, &b0, 0.1);
        let f = 0.2f64.exp();
        assert!(close(&a, &(a0 * f), 1e-15) && close(&b, &(b0 * f), 1e-15));
        // The projection of e^{2s}(a⁰ + 2z b⁰) agrees.
        let (pa, pb) = project_through_thickness(0.05, |z| {
            (sym_to_mat(&a0) + sym_to_mat(&b0) * (2.0 * z)) * f
        });
        assert!(close(&pa, &a, 1e-14) && close(&pb, &b, 1e-13));
    }

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
