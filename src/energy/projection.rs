//! Projection of an element Hessian to the positive semi-definite cone, applied per element
//! before the scatter (so the assembled matrix is PSD and Newton's step is a descent direction
//! without a global shift).

use crate::math::{Real, SMat};

/// How to treat negative eigenvalues of an element Hessian.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HessianProjection {
    /// Use the exact Hessian; indefiniteness is handled by the solver's diagonal shift.
    None,
    /// Exact Hessian when it factorises, the Gauss–Newton Hessian for iterations where it does
    /// not (default: quadratic convergence near a minimum, robust far from one).
    #[default]
    Adaptive,
    /// Always the Gauss–Newton Hessian (positive semi-definite by construction).
    GaussNewton,
    /// Clamp negative eigenvalues to zero.
    ClampZero,
    /// Replace eigenvalues by their absolute values.
    Abs,
}

/// Projects a symmetric `N×N` matrix in place: `H = V max(Λ, 0) Vᵀ` or `V |Λ| Vᵀ`.
pub fn project<const N: usize>(h: &mut SMat<N, N>, mode: HessianProjection) {
    if !matches!(mode, HessianProjection::ClampZero | HessianProjection::Abs) {
        return;
    }
    let dm = nalgebra::DMatrix::<Real>::from_column_slice(N, N, h.as_slice());
    let eig = nalgebra::SymmetricEigen::new(dm);
    if eig.eigenvalues.iter().all(|&l| l >= 0.0) {
        return;
    }
    let lam = eig.eigenvalues.map(|l: Real| match mode {
        HessianProjection::Abs => l.abs(),
        _ => l.max(0.0),
    });
    let v = &eig.eigenvectors;
    let p = v * nalgebra::DMatrix::from_diagonal(&lam) * v.transpose();
    h.copy_from_slice(p.as_slice());
}
