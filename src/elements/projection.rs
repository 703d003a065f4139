//! Projection of an element Hessian to the positive semi-definite cone, applied per element
//! before the scatter (so the assembled matrix is PSD and Newton's step is a descent direction
//! without a global shift).

use crate::math::{Real, SMat, SVec};

pub use crate::config::shell::HessianProjection;

/// Projects a symmetric `N×N` matrix in place: `H = V max(Λ, 0) Vᵀ` or `V |Λ| Vᵀ`, with the
/// eigensystem from [`jacobi_eigen`] (no allocation).
pub fn project<const N: usize>(h: &mut SMat<N, N>, mode: HessianProjection) {
    if !matches!(mode, HessianProjection::ClampZero | HessianProjection::Abs) {
        return;
    }
    let (vals, vecs) = jacobi_eigen(h);
    if vals.iter().all(|&l| l >= 0.0) {
        return;
    }
    let mut p = SMat::<N, N>::zeros();
    for k in 0..N {
        let l = match mode {
            HessianProjection::Abs => vals[k].abs(),
            _ => vals[k].max(0.0),
        };
        if l != 0.0 {
            let v = vecs.column(k);
            p += v * v.transpose() * l;
        }
    }
    *h = p;
}

/// Eigenvalues and eigenvectors (columns) of a symmetric `N×N` matrix by the cyclic Jacobi
/// method: sweeps of plane rotations until the off-diagonal part is below 1e-15 of the norm
/// (at most 50 sweeps). Deterministic and allocation-free.
pub fn jacobi_eigen<const N: usize>(m: &SMat<N, N>) -> (SVec<N>, SMat<N, N>) {
    let mut a = *m;
    let mut v = SMat::<N, N>::identity();
    let norm = a.iter().map(|x| x * x).sum::<Real>().sqrt();
    for _ in 0..50 {
        let mut off = 0.0;
        for p in 0..N {
            for q in p + 1..N {
                off += a[(p, q)] * a[(p, q)];
            }
        }
        if off.sqrt() <= 1e-15 * norm || off == 0.0 {
            break;
        }
        for p in 0..N {
            for q in p + 1..N {
                let apq = a[(p, q)];
                if apq == 0.0 {
                    continue;
                }
                let theta = (a[(q, q)] - a[(p, p)]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..N {
                    let (akp, akq) = (a[(k, p)], a[(k, q)]);
                    a[(k, p)] = c * akp - s * akq;
                    a[(k, q)] = s * akp + c * akq;
                }
                for k in 0..N {
                    let (apk, aqk) = (a[(p, k)], a[(q, k)]);
                    a[(p, k)] = c * apk - s * aqk;
                    a[(q, k)] = s * apk + c * aqk;
                }
                for k in 0..N {
                    let (vkp, vkq) = (v[(k, p)], v[(k, q)]);
                    v[(k, p)] = c * vkp - s * vkq;
                    v[(k, q)] = s * vkp + c * vkq;
                }
            }
        }
    }
    (SVec::<N>::from_fn(|i, _| a[(i, i)]), v)
}
