//! Design variables: per-face numbers `p_f` → the face's rest data `r_f = (ā, b̄, h̄)`
//! ([`crate::energy::sensitivity::REST_DATA`]) through a rest-form law, with the law's exact
//! Jacobian `∂r_f/∂p_f`.
//!
//! * **Growth** (`s`, one per face), the isotropic laws of [`crate::rest::laws`]:
//!   `isotropic`: `(ā, b̄, h̄) = (e^{2s} a⁰, e^s b⁰, e^s h)`, so `∂r/∂s = (2ā, b̄, h̄)`;
//!   `isotropic_in_plane`: `(e^{2s} a⁰, e^{2s} b⁰, h)`, `∂r/∂s = (2ā, 2b̄, 0)`;
//!   `isotropic_metric_only`: `(e^{2s} a⁰, b⁰, h)`, `∂r/∂s = (2ā, 0, 0)`.
//! * **Director** (θ, one per face), the liquid-crystal law ([`crate::rest::lce`]):
//!   `ā = Tᵀ(λ² d dᵀ + λ^{−2ν} d⊥ d⊥ᵀ)T`, `b̄ = 0`, `h̄ = h`, with `d = (cos θ, sin θ)`,
//!   `d⊥ = (−sin θ, cos θ)`, so `∂ā/∂θ = (λ² − λ^{−2ν}) Tᵀ(d⊥ dᵀ + d d⊥ᵀ)T`.
//! * **Forms** (six per face): ā and b̄ in reference Cartesian coordinates, pulled back by the
//!   face's frame `T` (`ā = Tᵀ ā_c T`, linear), `h̄ = h`.
//!
//! Units: s dimensionless, θ in rad, Cartesian ā dimensionless, Cartesian b̄ in 1/m.

use crate::config::design::Variable;
use crate::config::growth::GrowthLaw;
use crate::energy::sensitivity::REST_DATA;
use crate::math::{Mat2, Real, Sym2, Vec2};
use crate::rest::{pull_back, reference_frame};

/// The chain from one face's design numbers to its rest data.
#[derive(Clone, Debug)]
pub enum Chain {
    /// The growth factor under one of the isotropic laws, from the reference forms.
    Growth {
        /// The law.
        law: GrowthLaw,
        /// The reference forms `(a⁰, b⁰)` per face.
        reference: Vec<(Sym2, Sym2)>,
    },
    /// The director angle with the face's λ, ν and frame.
    Director {
        /// `(λ, ν)` per face.
        stretch: Vec<(Real, Real)>,
        /// The reference frame `T` per face.
        frames: Vec<Mat2>,
    },
    /// The Cartesian rest forms.
    Forms {
        /// The reference frame `T` per face.
        frames: Vec<Mat2>,
    },
}

/// One face's rest data and their Jacobian: `forms = (ā, b̄)`, the thickness ratio `h̄/h`, and
/// `jac[k]` = `∂r/∂p_k` in the order of [`REST_DATA`] (the thickness entry per unit reference
/// thickness: multiply by h).
#[derive(Clone, Debug)]
pub struct FaceRest {
    /// `(ā, b̄)` (barycentric, m², m).
    pub forms: (Sym2, Sym2),
    /// `h̄/h`.
    pub ratio: Real,
    /// `∂r/∂p_k`, one row per design number.
    pub jac: Vec<[Real; REST_DATA]>,
}

fn sym_row(a: Sym2, b: Sym2, h: Real) -> [Real; REST_DATA] {
    [a[0], a[1], a[2], b[0], b[1], b[2], h]
}

fn outer(u: Vec2, v: Vec2) -> Sym2 {
    // The symmetric part of u vᵀ + v uᵀ, halved: (u vᵀ + v uᵀ)/2.
    Sym2::new(u.x * v.x, 0.5 * (u.x * v.y + u.y * v.x), u.y * v.y)
}

impl Chain {
    /// The design numbers per face.
    pub fn per_face(&self) -> usize {
        match self {
            Chain::Forms { .. } => 6,
            _ => 1,
        }
    }

    /// The variable this chain designs.
    pub fn variable(&self) -> Variable {
        match self {
            Chain::Growth { .. } => Variable::Growth,
            Chain::Director { .. } => Variable::Director,
            Chain::Forms { .. } => Variable::Forms,
        }
    }

    /// The chain for growth under `law` from the reference forms.
    pub fn growth(law: GrowthLaw, reference: Vec<(Sym2, Sym2)>) -> Chain {
        Chain::Growth { law, reference }
    }

    /// The frames of a flat mesh's faces.
    pub fn frames(mesh: &crate::mesh::Mesh) -> Vec<Mat2> {
        (0..mesh.faces.len())
            .map(|f| reference_frame(mesh, f))
            .collect()
    }

    /// Face `f`'s rest data at its design numbers `p`.
    pub fn face(&self, f: usize, p: &[Real]) -> FaceRest {
        match self {
            Chain::Growth { law, reference } => {
                let (a0, b0) = reference[f];
                let e = p[0].exp();
                let abar = a0 * (e * e);
                let (bbar, ratio, db, dh) = match law {
                    GrowthLaw::IsotropicInPlane => (b0 * (e * e), 1.0, 2.0, 0.0),
                    GrowthLaw::IsotropicMetricOnly => (b0, 1.0, 0.0, 0.0),
                    _ => (b0 * e, e, 1.0, 1.0),
                };
                FaceRest {
                    forms: (abar, bbar),
                    ratio,
                    jac: vec![sym_row(abar * 2.0, bbar * db, ratio * dh)],
                }
            }
            Chain::Director { stretch, frames } => {
                let (lambda, nu) = stretch[f];
                let t = &frames[f];
                let (c, s) = (p[0].cos(), p[0].sin());
                let (d, dp) = (Vec2::new(c, s), Vec2::new(-s, c));
                let (l2, lp) = (lambda * lambda, lambda.powf(-2.0 * nu));
                let abar = pull_back(t, &outer(d, d)) * l2 + pull_back(t, &outer(dp, dp)) * lp;
                let dabar = pull_back(t, &(outer(dp, d) * 2.0)) * (l2 - lp);
                FaceRest {
                    forms: (abar, Sym2::zeros()),
                    ratio: 1.0,
                    jac: vec![sym_row(dabar, Sym2::zeros(), 0.0)],
                }
            }
            Chain::Forms { frames } => {
                let t = &frames[f];
                let ac = Sym2::new(p[0], p[1], p[2]);
                let bc = Sym2::new(p[3], p[4], p[5]);
                let jac = (0..6)
                    .map(|k| {
                        let e = pull_back(t, &Sym2::ith(k % 3, 1.0));
                        if k < 3 {
                            sym_row(e, Sym2::zeros(), 0.0)
                        } else {
                            sym_row(Sym2::zeros(), e, 0.0)
                        }
                    })
                    .collect();
                FaceRest {
                    forms: (pull_back(t, &ac), pull_back(t, &bc)),
                    ratio: 1.0,
                    jac,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each chain's Jacobian against central differences of its own forms (O(ε²) ≈ 1e-12).
    #[test]
    fn chain_jacobians_match_differences() {
        let t = Mat2::new(0.3, 0.1, -0.05, 0.25);
        let a0 = pull_back(&t, &Sym2::new(1.0, 0.0, 1.0));
        let b0 = Sym2::new(0.02, -0.01, 0.03);
        let chains = [
            (
                Chain::growth(GrowthLaw::Isotropic, vec![(a0, b0)]),
                vec![0.3],
            ),
            (
                Chain::growth(GrowthLaw::IsotropicInPlane, vec![(a0, b0)]),
                vec![-0.2],
            ),
            (
                Chain::growth(GrowthLaw::IsotropicMetricOnly, vec![(a0, b0)]),
                vec![0.1],
            ),
            (
                Chain::Director {
                    stretch: vec![(0.8, 0.5)],
                    frames: vec![t],
                },
                vec![0.7],
            ),
            (
                Chain::Forms { frames: vec![t] },
                vec![1.1, 0.2, 0.9, 3.0, -1.0, 2.0],
            ),
        ];
        for (chain, p) in chains {
            let at = chain.face(0, &p);
            for k in 0..p.len() {
                let eps = 1e-6;
                let row = |e: Real| {
                    let mut q = p.clone();
                    q[k] += e;
                    let r = chain.face(0, &q);
                    sym_row(r.forms.0, r.forms.1, r.ratio)
                };
                let (hi, lo) = (row(eps), row(-eps));
                for i in 0..REST_DATA {
                    let fd = (hi[i] - lo[i]) / (2.0 * eps);
                    assert!(
                        (fd - at.jac[k][i]).abs() <= 1e-9 * (1.0 + fd.abs()),
                        "{chain:?} number {k} entry {i}: {} against {fd}",
                        at.jac[k][i]
                    );
                }
            }
        }
    }

    /// The director chain gives the liquid-crystal law's own metric.
    #[test]
    fn the_director_chain_is_the_lce_law() {
        let t = Mat2::new(0.3, 0.1, -0.05, 0.25);
        let chain = Chain::Director {
            stretch: vec![(0.85, 0.5)],
            frames: vec![t],
        };
        let got = chain.face(0, &[0.4]).forms.0;
        let law = crate::rest::lce::LceFace::new(&t, 0.4, 0.85, 0.5).metric(1.0);
        assert!((got - law).amax() < 1e-15 * law.amax(), "{got:?} {law:?}");
    }
}
