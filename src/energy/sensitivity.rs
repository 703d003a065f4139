//! Rest sensitivities: how the shell's gradient moves when a face's rest data move, contracted
//! with an adjoint vector. Inverse design needs them: at an equilibrium `g(x*, r) = 0` of rest
//! data `r`, an objective `J(x*)` has `dJ/dr = −λᵀ ∂g/∂r` with `H λ = ∂J/∂x` (the adjoint
//! method), and `λᵀ ∂g/∂r` is what this module computes, face by face.
//!
//! ## The contraction
//! A face's energy is `W(a(x), b(x); r)` with `r = (ā₁₁, ā₁₂, ā₂₂, b̄₁₁, b̄₁₂, b̄₂₂, h̄)`
//! ([`REST_DATA`] numbers). Its gradient is `g = Jaᵀ W_a + G W_b` ([`super::shell`]), so with
//! the directional derivatives of the forms along the face's part of `λ`,
//! `δa = Ja λ` and `δb = Gᵀ λ`,
//!
//! `λᵀ ∂g/∂r = ∂φ/∂r`,   `φ(r) = W_a(a; r)·δa + W_b(b; r)·δb`,
//!
//! since `a`, `b`, `δa`, `δb` do not depend on `r`. For the Koiter density
//! ([`super::material::KoiterDensity`]), `W = w_s (a − ā)ᵀC(a − ā) + w_b (b − b̄)ᵀC(b − b̄)` with
//! `w_s = A h̄ f σ / 4`, `w_b = A h̄³/12`, `A = √det ā / 2` and `C(ā)` the St Venant–Kirchhoff
//! matrix of `Ā = ā⁻¹` ([`super::material::sv_matrix`]):
//!
//! `φ = φ_s + φ_b`, `φ_s = 2 w_s δaᵀ C (a − ā)`, `φ_b = 2 w_b δbᵀ C (b − b̄)`, and
//!
//! * `∂φ/∂b̄_k = −2 w_b (C δb)_k`;
//! * `∂φ/∂h̄ = (φ_s + 3 φ_b)/h̄`;
//! * `∂φ/∂ā_k = ½ t_k (φ_s + φ_b) + 2 w_s C'_k(δa, a − ā) + 2 w_b C'_k(δb, b − b̄) − 2 w_s (C δa)_k`,
//!
//! with `t = (Ā₁₁, 2Ā₁₂, Ā₂₂)` (`∂ ln √det ā/∂ā = t/2`) and `C'_k(u, v)` the derivative of the
//! bilinear form `uᵀC v = α/2 tr(ĀU) tr(ĀV) + β tr(ĀUĀV)` along `dĀ = −Ā E_k Ā`, `E_k` the
//! symmetric basis matrices of the `[11, 12, 22]` coordinates (`E₁₂` has both off-diagonal
//! entries 1, as `ā₁₂` enters the matrix twice).
//!
//! Units: `λ` in m/N (positions) and 1/(N·m) (edge angles), so `λᵀ ∂g/∂r` is in 1/m² (per ā
//! entry), 1/m (per b̄ entry) and 1/m (per h̄). DOF order of `λ`: the global one.

use crate::body::Lame2d;
use crate::math::{sym_det, sym_to_mat, Mat2, Real, Sym2};

/// The rest data of one face the sensitivities are taken with respect to:
/// `(ā₁₁, ā₁₂, ā₂₂, b̄₁₁, b̄₁₂, b̄₂₂, h̄)` (m², m, m).
pub const REST_DATA: usize = 7;

/// `λᵀ ∂g/∂r` of one face, in the order of [`REST_DATA`].
pub type RestAdjoint = [Real; REST_DATA];

/// The symmetric basis matrix of coordinate `k` of `[11, 12, 22]`.
fn basis(k: usize) -> Mat2 {
    match k {
        0 => Mat2::new(1.0, 0.0, 0.0, 0.0),
        1 => Mat2::new(0.0, 1.0, 1.0, 0.0),
        _ => Mat2::new(0.0, 0.0, 0.0, 1.0),
    }
}

/// The rest data of one Koiter face and its current forms: what
/// [`koiter_rest_adjoint`] differentiates.
#[derive(Clone, Copy, Debug)]
pub struct KoiterFace {
    /// ā (m², barycentric).
    pub abar: Sym2,
    /// b̄ (m).
    pub bbar: Sym2,
    /// The rest thickness h̄ (m).
    pub h: Real,
    /// The plane-stress Lamé parameters (Pa).
    pub lame: Lame2d,
    /// The stretching weight's factor `f σ` (the stretching convention times the potential's
    /// stretch scale).
    pub stretch: Real,
    /// Whether the face has bending energy.
    pub bending: bool,
}

/// `∂φ/∂r` of the module doc for one Koiter face at forms `a`, `b`, along `δa`, `δb`
/// (barycentric `[11, 12, 22]`): the face's `λᵀ ∂g/∂r` in the order of [`REST_DATA`].
pub fn koiter_rest_adjoint(
    k: &KoiterFace,
    a: &Sym2,
    b: &Sym2,
    da: &Sym2,
    db: &Sym2,
) -> RestAdjoint {
    let det = sym_det(&k.abar);
    let mut out = [0.0; REST_DATA];
    if det.is_nan() || det <= 0.0 || !det.is_finite() {
        return out;
    }
    let area = 0.5 * det.sqrt();
    let ws = area * k.h / 4.0 * k.stretch;
    let wb = if k.bending {
        area * k.h * k.h * k.h / 12.0
    } else {
        0.0
    };
    let c = super::material::sv_matrix(&k.abar, k.lame);
    let (ma, mb) = (a - k.abar, b - k.bbar);
    let phi_s = 2.0 * ws * da.dot(&(c * ma));
    let phi_b = 2.0 * wb * db.dot(&(c * mb));
    let inv = Mat2::new(k.abar[2], -k.abar[1], -k.abar[1], k.abar[0]) / det;
    let t = [inv[(0, 0)], 2.0 * inv[(0, 1)], inv[(1, 1)]];
    let (alpha, beta) = (k.lame.alpha, k.lame.beta);
    // The derivative of uᵀCv along dĀ.
    let dform = |u: &Mat2, v: &Mat2, d: &Mat2| {
        let (au, av) = (inv * u, inv * v);
        0.5 * alpha * ((d * u).trace() * av.trace() + au.trace() * (d * v).trace())
            + beta * ((d * u * inv * v).trace() + (au * d * v).trace())
    };
    let (mam, mbm, dam, dbm) = (
        sym_to_mat(&ma),
        sym_to_mat(&mb),
        sym_to_mat(da),
        sym_to_mat(db),
    );
    let cda = c * da;
    let cdb = c * db;
    for q in 0..3 {
        let d = -(inv * basis(q) * inv);
        out[q] =
            0.5 * t[q] * (phi_s + phi_b) + 2.0 * ws * dform(&dam, &mam, &d) - 2.0 * ws * cda[q];
        if wb != 0.0 {
            out[q] += 2.0 * wb * dform(&dbm, &mbm, &d);
        }
        out[3 + q] = -2.0 * wb * cdb[q];
    }
    out[6] = (phi_s + 3.0 * phi_b) / k.h;
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::material::{DensityDerivs, FaceDensity, KoiterDensity};

    /// `φ(r)` through the Koiter density itself: `W_a·δa + W_b·δb`.
    fn phi(k: &KoiterFace, a: &Sym2, b: &Sym2, da: &Sym2, db: &Sym2) -> Real {
        let (ws, wb) = KoiterDensity::weights(&k.abar, k.h, k.stretch);
        let dens = KoiterDensity {
            c: crate::energy::material::sv_matrix(&k.abar, k.lame),
            stretch: [(ws, k.abar), (0.0, Sym2::zeros())],
            bend: [
                (if k.bending { wb } else { 0.0 }, k.bbar),
                (0.0, Sym2::zeros()),
            ],
            stiffen: 0.0,
        };
        let mut d = DensityDerivs::default();
        dens.eval(a, b, &mut d);
        d.ga.dot(da) + d.gb.dot(db)
    }

    /// Every entry against central differences of the density's own derivatives, for a
    /// sheared, curved face (the differences' error is O(ε²) ≈ 1e-10 relative here).
    #[test]
    fn the_rest_adjoint_matches_differences_of_the_density() {
        for bending in [true, false] {
            let k = KoiterFace {
                abar: Sym2::new(1.3e-4, 0.4e-4, 0.9e-4),
                bbar: Sym2::new(2.0e-3, -0.5e-3, 1.0e-3),
                h: 1.5e-3,
                lame: Lame2d {
                    alpha: 0.8e6,
                    beta: 0.6e6,
                },
                stretch: 1.0,
                bending,
            };
            let (a, b) = (
                Sym2::new(1.1e-4, 0.3e-4, 1.0e-4),
                Sym2::new(-1.0e-3, 0.7e-3, 2.5e-3),
            );
            let (da, db) = (Sym2::new(0.3, -0.7, 0.2), Sym2::new(-2.0, 0.4, 1.1));
            let got = koiter_rest_adjoint(&k, &a, &b, &da, &db);
            let scale = [1e-4, 1e-4, 1e-4, 1e-3, 1e-3, 1e-3, 1e-3];
            for (q, &s) in scale.iter().enumerate() {
                let eps = 1e-5 * s;
                let moved = |e: Real| {
                    let mut m = k;
                    match q {
                        0..=2 => m.abar[q] += e,
                        3..=5 => m.bbar[q - 3] += e,
                        _ => m.h += e,
                    }
                    phi(&m, &a, &b, &da, &db)
                };
                let fd = (moved(eps) - moved(-eps)) / (2.0 * eps);
                let norm = got
                    .iter()
                    .zip(&scale)
                    .map(|(g, s)| (g * s).abs())
                    .fold(0.0, Real::max);
                assert!(
                    (fd - got[q]).abs() * s <= 1e-8 * norm,
                    "bending {bending}, entry {q}: {} against {fd}",
                    got[q]
                );
            }
        }
    }
}
