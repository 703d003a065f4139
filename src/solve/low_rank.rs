//! Solving with a sparse factor plus a dense low-rank update, never densified.
//!
//! With the sparse part `A = LLᵀ` factorised and the update `U C Uᵀ` (`C = diag(c_k)`, the
//! terms' [`LowRank`] parts), the Woodbury identity gives
//!
//! `(A + U C Uᵀ)⁻¹ r = A⁻¹r − A⁻¹U S⁻¹ Uᵀ A⁻¹ r`, `S = C⁻¹ + Uᵀ A⁻¹ U` (k×k),
//!
//! one extra solve per update vector (Sherman–Morrison for k = 1). `A` need not be positive
//! definite, only invertible: an LDLᵀ factor of an indefinite sparse part serves as well.
//!
//! The inertia of the whole matrix follows from that of `A` and `S` (Haynsworth, applied to the
//! bordered matrix `[[A, U], [Uᵀ, −C⁻¹]]` eliminated both ways):
//!
//! `n₋(A + UCUᵀ) = n₋(A) + n₊(S) − n₊(C)`, and `A + UCUᵀ` is singular exactly when `S` is.
//!
//! So with `A ≻ 0` the whole is positive definite when `S` has as many positive eigenvalues as
//! `C`; an indefinite `A` with one negative eigenvalue and one positive `c` (a gas's stiffness)
//! gives a positive definite whole when `S < 0`.

use crate::energy::term::LowRank;
use crate::linalg::LinearSolver;
use crate::math::Real;

/// The update vectors solved against the factor, and the capacitance matrix `S`.
#[derive(Clone)]
pub struct Woodbury {
    /// `A⁻¹ u_k`.
    ainv_u: Vec<Vec<Real>>,
    /// `S = C⁻¹ + Uᵀ A⁻¹ U`, `k×k` row-major.
    s: Vec<Real>,
    /// The coefficients kept (non-zero `c_k`).
    c: Vec<Real>,
    /// The vectors kept.
    u: Vec<Vec<Real>>,
}

impl Woodbury {
    /// Prepares the update on a factorised `lin` (k extra solves).
    pub fn new(lin: &mut LinearSolver, parts: &[LowRank]) -> Self {
        Self::new_with(lin, parts, None)
    }

    /// As [`Self::new`], solving `A r = r` in place in the same pass over the factor (one
    /// multi-vector solve: the sweeps are bound by reading the factor); [`Self::correct`] then
    /// finishes `(A + UCUᵀ)⁻¹ r`.
    pub fn new_with(lin: &mut LinearSolver, parts: &[LowRank], r: Option<&mut [Real]>) -> Self {
        let kept: Vec<&LowRank> = parts.iter().filter(|p| p.c != 0.0).collect();
        let k = kept.len();
        let ainv_u: Vec<Vec<Real>> = match (k, r) {
            (0, Some(r)) => {
                lin.solve_in_place(r);
                Vec::new()
            }
            (0, None) => Vec::new(),
            (_, r) => {
                let n = kept[0].u.len();
                let mut block: Vec<Real> = kept.iter().flat_map(|p| p.u.iter().copied()).collect();
                if let Some(r) = &r {
                    block.extend_from_slice(r);
                }
                lin.solve_in_place(&mut block);
                if let Some(r) = r {
                    r.copy_from_slice(&block[k * n..]);
                }
                block
                    .chunks_exact(n)
                    .take(k)
                    .map(<[Real]>::to_vec)
                    .collect()
            }
        };
        let mut s = vec![0.0; k * k];
        for i in 0..k {
            for j in 0..k {
                s[i * k + j] = dot(&kept[i].u, &ainv_u[j]);
            }
            s[i * k + i] += 1.0 / kept[i].c;
        }
        Woodbury {
            ainv_u,
            s,
            c: kept.iter().map(|p| p.c).collect(),
            u: kept.iter().map(|p| p.u.clone()).collect(),
        }
    }

    /// Whether there is no update.
    pub fn is_empty(&self) -> bool {
        self.c.is_empty()
    }

    /// Solves `(A + UCUᵀ) y = r` in place, given `A⁻¹` through `lin`. Returns false if `S` is
    /// singular (the whole matrix is).
    pub fn solve_in_place(&self, lin: &mut LinearSolver, r: &mut [Real]) -> bool {
        lin.solve_in_place(r);
        self.correct(r)
    }

    /// Turns `A⁻¹ r` (solved already, e.g. by [`Self::new_with`]) into `(A + UCUᵀ)⁻¹ r` in
    /// place. Returns false if `S` is singular.
    pub fn correct(&self, r: &mut [Real]) -> bool {
        let k = self.c.len();
        if k == 0 {
            return true;
        }
        let rhs = nalgebra::DVector::from_iterator(k, self.u.iter().map(|u| dot(u, r)));
        let s = nalgebra::DMatrix::from_row_slice(k, k, &self.s);
        let Some(z) = s.lu().solve(&rhs) else {
            return false;
        };
        if !z.iter().all(|v| v.is_finite()) {
            return false;
        }
        for (j, au) in self.ainv_u.iter().enumerate() {
            for (ri, ai) in r.iter_mut().zip(au) {
                *ri -= ai * z[j];
            }
        }
        true
    }

    /// With `A ≻ 0` factorised: whether `A + UCUᵀ ≻ 0` (module doc).
    pub fn keeps_positive_definite(&self) -> bool {
        self.negative_eigenvalues(0) == Some(0)
    }

    /// The number of negative eigenvalues of `A + UCUᵀ`, given `A`'s (`negative_a`), or `None`
    /// when the whole is singular (module doc).
    pub fn negative_eigenvalues(&self, negative_a: usize) -> Option<usize> {
        let k = self.c.len();
        if k == 0 {
            return Some(negative_a);
        }
        let s = nalgebra::DMatrix::from_row_slice(k, k, &self.s);
        let sym = (&s + s.transpose()) * 0.5;
        let eig = nalgebra::SymmetricEigen::new(sym);
        if eig.eigenvalues.iter().any(|&l| l == 0.0 || !l.is_finite()) {
            return None;
        }
        let pos_s = eig.eigenvalues.iter().filter(|&&l| l > 0.0).count();
        let pos_c = self.c.iter().filter(|&&c| c > 0.0).count();
        (negative_a + pos_s).checked_sub(pos_c)
    }
}

fn dot(a: &[Real], b: &[Real]) -> Real {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
