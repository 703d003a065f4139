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
//! * **Bbar** (three per face): b̄ alone in reference Cartesian coordinates, each face's ā kept.
//! * **Swelling** (`ε⁺`, `ε⁻`, two per face), the bilayer law ([`crate::rest::laws::bilayer`])
//!   with layers that keep their thickness. Each layer stretches by `1 + α ε` along the machine
//!   direction and `1 + γ ε` across it, where `(α, γ)` is the face's own `(μ, μ⊥)` over the
//!   larger of them in size (`(1, 1)` for a layer that swells alike in every direction, or has
//!   no coefficient): `ε` is the layer's strain in its direction of largest swelling. The
//!   layer's metric is then quadratic in `ε`, and the projection's weights and heights do not
//!   depend on it, so the forms are exactly `r = r₀ + Σ± (ε± L± + ε±² Q±)` with
//!   `L = (r(1) − r(−1))/2`, `Q = (r(1) + r(−1))/2 − r₀` from the law's forms at `ε = ±1` of one
//!   layer (the printed layer, which does not swell, is in `r₀`), and `∂r/∂ε± = L± + 2ε± Q±`.
//!   The through-thickness swelling `λ` of the face's own moisture divides `b̄` and sets
//!   `h̄ = λ h`, both fixed.
//!   Gel layers (`isotropic_layers`), whose thickness grows by `s± = 1 + ε±` too: the law's
//!   forms and `h̄/h` with its exact stretch derivatives at every evaluation ([`Gel`]).
//! * **Thickness** (`h̄`, one per face): the rest forms are the scene's own, `∂h̄/∂h̄ = 1`.
//!
//! Units: s dimensionless, θ in rad, Cartesian ā dimensionless, Cartesian b̄ in 1/m, ε±
//! dimensionless, h̄ in m.

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
    /// The Cartesian b̄ alone, with each face's ā kept.
    Bbar {
        /// The reference frame `T` per face.
        frames: Vec<Mat2>,
        /// The kept ā per face (barycentric, m²).
        abar: Vec<Sym2>,
    },
    /// The bilayer's layer strains: per face `r₀`, `L⁺`, `Q⁺`, `L⁻`, `Q⁻` (forms, with `b̄`
    /// already over λ) and the fixed thickness ratio λ.
    Swelling {
        /// The five bases per face.
        basis: Vec<[(Sym2, Sym2); 5]>,
        /// Each layer's `(α, γ)` per face, top and bottom.
        shape: Vec<[(Real, Real); 2]>,
        /// Gel layers (`isotropic_layers`), whose forms come from the law itself; `None` for
        /// layers that keep their thickness (the bases above).
        gel: Option<Gel>,
        /// `h̄/h` per face.
        ratio: Vec<Real>,
    },
    /// The rest thickness, with the scene's own forms.
    Thickness {
        /// The forms per face.
        forms: Vec<(Sym2, Sym2)>,
        /// The reference thickness `h` per face (m).
        reference: Vec<Real>,
        /// The scene's growth law's thickness ratio per face (1 without one): the written
        /// reference thickness is `h̄` over it, and the mass follows the written thickness.
        law_ratio: Vec<Real>,
    },
}

/// The swelling chain of gel layers (`growth.isotropic_layers`): each layer's thickness grows
/// by its in-plane stretch `s± = 1 + ε±`, so the heights and weights of the law's projection
/// move with the stretches and the forms are not quadratic in them. The forms, the thickness
/// ratio and their exact derivatives come from the law
/// ([`crate::rest::laws::bilayer::bilayer_jacobian`]) at every evaluation.
#[derive(Clone, Debug)]
pub struct Gel {
    /// The layers.
    pub laminate: crate::config::growth::Laminate,
    /// Per face: the reference forms `(a⁰, b⁰)` (m², m), the reference thickness (m) and the
    /// printed layer.
    pub faces: Vec<(Sym2, Sym2, Real, Option<crate::rest::laws::bilayer::Print>)>,
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
            Chain::Bbar { .. } => 3,
            Chain::Swelling { .. } => 2,
            _ => 1,
        }
    }

    /// The variable this chain designs.
    pub fn variable(&self) -> Variable {
        match self {
            Chain::Growth { .. } => Variable::Growth,
            Chain::Director { .. } => Variable::Director,
            Chain::Forms { .. } => Variable::Forms,
            Chain::Bbar { .. } => Variable::Bbar,
            Chain::Swelling { .. } => Variable::Swelling,
            Chain::Thickness { .. } => Variable::Thickness,
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
            Chain::Bbar { frames, abar } => {
                let t = &frames[f];
                let bc = Sym2::new(p[0], p[1], p[2]);
                let jac = (0..3)
                    .map(|k| sym_row(Sym2::zeros(), pull_back(t, &Sym2::ith(k, 1.0)), 0.0))
                    .collect();
                FaceRest {
                    forms: (abar[f], pull_back(t, &bc)),
                    ratio: 1.0,
                    jac,
                }
            }
            Chain::Swelling { gel: Some(g), .. } => {
                use crate::rest::laws::bilayer::{bilayer_jacobian, Stretch};
                let (a0, b0, h, print) = g.faces[f];
                let (top, bottom) = (Stretch::iso(1.0 + p[0]), Stretch::iso(1.0 + p[1]));
                let ((abar, bbar, ratio), jac) =
                    bilayer_jacobian(&a0, &b0, h, top, bottom, [1.0, 0.0], &g.laminate, print);
                FaceRest {
                    forms: (abar, bbar),
                    ratio,
                    jac: jac.iter().map(|j| sym_row(j.0, j.1, j.2)).collect(),
                }
            }
            Chain::Swelling { basis, ratio, .. } => {
                let [(a0, b0), (lt, mt), (qt, nt), (lb, mb), (qb, nb)] = basis[f];
                let (et, eb) = (p[0], p[1]);
                FaceRest {
                    forms: (
                        a0 + lt * et + qt * (et * et) + lb * eb + qb * (eb * eb),
                        b0 + mt * et + nt * (et * et) + mb * eb + nb * (eb * eb),
                    ),
                    ratio: ratio[f],
                    jac: vec![
                        sym_row(lt + qt * (2.0 * et), mt + nt * (2.0 * et), 0.0),
                        sym_row(lb + qb * (2.0 * eb), mb + nb * (2.0 * eb), 0.0),
                    ],
                }
            }
            Chain::Thickness {
                forms, reference, ..
            } => FaceRest {
                forms: forms[f],
                ratio: p[0] / reference[f],
                jac: vec![sym_row(Sym2::zeros(), Sym2::zeros(), 1.0 / reference[f])],
            },
        }
    }

    /// Face `f`'s design numbers whose rest forms are nearest the target forms `(a*, b*)`
    /// (barycentric, m², m): the minimiser over the box `[lower, upper]` of the rest-form
    /// mismatch `½|ā − a*|² + ½ w |b̄ − b*|²` in the target's own metric,
    /// `|M|² = tr(a*⁻¹ M a*⁻¹ M)`, with `w = h²/12` (Koiter's bending-to-stretching ratio, `h`
    /// in m). Projected Levenberg–Marquardt from `start` on the chain's exact Jacobian; a
    /// director, whose mismatch is not convex in θ, also from `start + kπ/4`, `k = 1, 2, 3`,
    /// keeping the best. Returns the numbers and the mismatch reached (dimensionless).
    pub fn fit(
        &self,
        f: usize,
        start: &[Real],
        target: &(Sym2, Sym2),
        w: Real,
        (lower, upper): (Real, Real),
    ) -> (Vec<Real>, Real) {
        let inv = crate::math::sym_to_mat(&target.0)
            .try_inverse()
            .unwrap_or_else(Mat2::zeros);
        // The metric on symmetric matrices, `Q_ij = tr(A E_i A E_j)` over the basis of Sym2.
        let basis = [0, 1, 2].map(|i| inv * crate::math::sym_to_mat(&Sym2::ith(i, 1.0)));
        let q = nalgebra::Matrix3::from_fn(|i, j| (basis[i] * basis[j]).trace());
        let norm = |m: &Sym2| 0.5 * m.dot(&(q * m));
        let mismatch = |p: &[Real]| {
            let r = self.face(f, p);
            let (da, db) = (r.forms.0 - target.0, r.forms.1 - target.1);
            (norm(&da) + w * norm(&db), r, da, db)
        };
        let clamp = |x: Real| x.clamp(lower, upper);
        let k = start.len();
        let starts: Vec<Vec<Real>> = match self {
            Chain::Director { .. } => (0..4)
                .map(|j| vec![clamp(start[0] + j as Real * std::f64::consts::FRAC_PI_4)])
                .collect(),
            _ => vec![start.iter().map(|&x| clamp(x)).collect()],
        };
        let mut best: Option<(Vec<Real>, Real)> = None;
        for mut p in starts {
            let (mut e, mut r, mut da, mut db) = mismatch(&p);
            let mut mu = 1e-3;
            for _ in 0..200 {
                let mut h = nalgebra::DMatrix::<Real>::zeros(k, k);
                let mut g = nalgebra::DVector::<Real>::zeros(k);
                let ja: Vec<Sym2> = r.jac.iter().map(|j| Sym2::new(j[0], j[1], j[2])).collect();
                let jb: Vec<Sym2> = r.jac.iter().map(|j| Sym2::new(j[3], j[4], j[5])).collect();
                for i in 0..k {
                    g[i] = ja[i].dot(&(q * da)) + w * jb[i].dot(&(q * db));
                    for l in 0..k {
                        h[(i, l)] = ja[i].dot(&(q * ja[l])) + w * jb[i].dot(&(q * jb[l]));
                    }
                }
                let scale = (0..k).fold(0.0 as Real, |m, i| m.max(h[(i, i)]));
                if scale == 0.0 {
                    break;
                }
                let mut damped = h.clone();
                for i in 0..k {
                    damped[(i, i)] += mu * (h[(i, i)] + 1e-12 * scale);
                }
                let Some(step) = damped.lu().solve(&(-&g)) else {
                    mu *= 10.0;
                    continue;
                };
                let trial: Vec<Real> = p
                    .iter()
                    .zip(step.iter())
                    .map(|(a, d)| clamp(a + d))
                    .collect();
                let moved = p
                    .iter()
                    .zip(&trial)
                    .fold(0.0 as Real, |m, (a, b)| m.max((a - b).abs()));
                let (e1, r1, da1, db1) = mismatch(&trial);
                if e1 < e {
                    (p, e, r, da, db) = (trial, e1, r1, da1, db1);
                    mu = (mu / 3.0).max(1e-12);
                } else {
                    mu *= 4.0;
                }
                let size = p.iter().fold(1.0 as Real, |m, x| m.max(x.abs()));
                if moved <= 1e-14 * size || mu > 1e12 {
                    break;
                }
            }
            if best.as_ref().is_none_or(|b| e < b.1) {
                best = Some((p, e));
            }
        }
        best.expect("at least one start")
    }

    /// The swelling chain of a bilayer face: `r₀`, `L⁺`, `Q⁺`, `L⁻`, `Q⁻` (see the module
    /// doc) from the law's forms at `ε = 0` and at `ε = ±1` of each layer, over the face's
    /// through-thickness swelling `lambda`. `shape` is each layer's `(α, γ)` (top, bottom) and
    /// `d` the machine direction (barycentric).
    #[allow(clippy::too_many_arguments)]
    pub fn swelling_basis(
        a0: &Sym2,
        b0: &Sym2,
        h: Real,
        laminate: &crate::config::growth::Laminate,
        print: Option<crate::rest::laws::bilayer::Print>,
        lambda: Real,
        shape: [(Real, Real); 2],
        d: [Real; 2],
    ) -> [(Sym2, Sym2); 5] {
        use crate::rest::laws::bilayer::{bilayer, Stretch};
        let at = |et: Real, eb: Real| {
            let (top, bottom) = (Stretch::of(shape[0], et), Stretch::of(shape[1], eb));
            let (a, b, _) = bilayer(a0, b0, h, top, bottom, d, laminate, print);
            (a, b / lambda)
        };
        let r0 = at(0.0, 0.0);
        let split = |plus: (Sym2, Sym2), minus: (Sym2, Sym2)| {
            [
                ((plus.0 - minus.0) * 0.5, (plus.1 - minus.1) * 0.5),
                (
                    (plus.0 + minus.0) * 0.5 - r0.0,
                    (plus.1 + minus.1) * 0.5 - r0.1,
                ),
            ]
        };
        let [lt, qt] = split(at(1.0, 0.0), at(-1.0, 0.0));
        let [lb, qb] = split(at(0.0, 1.0), at(0.0, -1.0));
        [r0, lt, qt, lb, qb]
    }

    /// A bilayer layer's coefficient of largest swelling: whichever of `(μ, μ⊥)` (along and
    /// across the machine direction) is larger in size, with its sign (per unit moisture). The
    /// layer's strain `ε` is this times its moisture.
    pub fn layer_scale(mu: (Real, Real)) -> Real {
        if mu.0.abs() >= mu.1.abs() {
            mu.0
        } else {
            mu.1
        }
    }

    /// A bilayer layer's `(α, γ)` from its coefficients `(μ, μ⊥)` along and across the machine
    /// direction: both over [`Chain::layer_scale`], or `(1, 1)` when both are 0.
    pub fn layer_shape(mu: (Real, Real)) -> (Real, Real) {
        let m = Chain::layer_scale(mu);
        if m == 0.0 {
            (1.0, 1.0)
        } else {
            (mu.0 / m, mu.1 / m)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One chain of each kind on one face, with design numbers away from the neutral ones.
    fn sample_chains() -> Vec<(Chain, Vec<Real>)> {
        let t = Mat2::new(0.3, 0.1, -0.05, 0.25);
        let a0 = pull_back(&t, &Sym2::new(1.0, 0.0, 1.0));
        let b0 = Sym2::new(0.02, -0.01, 0.03);
        [
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
            (
                Chain::Swelling {
                    basis: vec![Chain::swelling_basis(
                        &a0,
                        &b0,
                        0.01,
                        &crate::config::growth::Laminate {
                            top_fraction: 0.3,
                            modulus_ratio: 2.0,
                            isotropic: false,
                        },
                        Some(crate::rest::laws::bilayer::Print {
                            thickness: 0.001,
                            modulus_ratio: 5.0,
                        }),
                        1.1,
                        [(1.0, 0.25), (-0.5, 1.0)],
                        [0.6, -0.2],
                    )],
                    ratio: vec![1.1],
                    shape: vec![[(1.0, 0.25), (-0.5, 1.0)]],
                    gel: None,
                },
                vec![0.04, -0.02],
            ),
            (
                Chain::Swelling {
                    basis: Vec::new(),
                    ratio: Vec::new(),
                    shape: vec![[(1.0, 1.0); 2]],
                    gel: Some(Gel {
                        laminate: crate::config::growth::Laminate {
                            top_fraction: 0.3,
                            modulus_ratio: 2.0,
                            isotropic: true,
                        },
                        faces: vec![(
                            a0,
                            b0,
                            0.01,
                            Some(crate::rest::laws::bilayer::Print {
                                thickness: 0.001,
                                modulus_ratio: 5.0,
                            }),
                        )],
                    }),
                },
                vec![0.04, -0.02],
            ),
            (
                Chain::Bbar {
                    frames: vec![t],
                    abar: vec![a0],
                },
                vec![3.0, -1.0, 2.0],
            ),
            (
                Chain::Thickness {
                    forms: vec![(a0, b0)],
                    reference: vec![0.02],
                    law_ratio: vec![1.0],
                },
                vec![0.015],
            ),
        ]
        .into()
    }

    /// Each chain's Jacobian against central differences of its own forms (O(ε²) ≈ 1e-12).
    #[test]
    fn chain_jacobians_match_differences() {
        for (chain, p) in sample_chains() {
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

    /// The fit recovers every chain's numbers from the forms they make, from the neutral
    /// start (a director up to a half turn, the same director), to round-off; with an upper
    /// bound below the true growth it stops on the bound. A thickness does not change the forms,
    /// so its fit is not asked for (`design.start = "target"` refuses it).
    #[test]
    fn the_fit_recovers_each_chains_numbers_from_their_forms() {
        for (chain, p) in sample_chains() {
            if matches!(chain, Chain::Thickness { .. }) {
                continue;
            }
            let target = chain.face(0, &p).forms;
            let start = match chain {
                Chain::Forms { .. } => vec![1.0, 0.0, 1.0, 0.0, 0.0, 0.0],
                _ => vec![0.0; p.len()],
            };
            let w = 0.01 * 0.01 / 12.0;
            let (got, e) = chain.fit(0, &start, &target, w, (-10.0, 10.0));
            assert!(e < 1e-24, "{chain:?}: mismatch {e:e} at {got:?}");
            for (a, b) in got.iter().zip(&p) {
                let off = match chain {
                    Chain::Director { .. } => {
                        let d = (a - b).rem_euclid(std::f64::consts::PI);
                        d.min(std::f64::consts::PI - d)
                    }
                    _ => (a - b).abs(),
                };
                assert!(
                    off < 1e-9 * (1.0 + b.abs()),
                    "{chain:?}: {got:?} against {p:?}"
                );
            }
        }
        let (chain, p) = &sample_chains()[0];
        let target = chain.face(0, p).forms;
        let (got, e) = chain.fit(0, &[0.0], &target, 1e-5, (-1.0, 0.2));
        assert_eq!(got, vec![0.2]);
        assert!(e > 0.0);
    }

    /// The swelling chain gives the bilayer law's own forms at any strains, for layers that
    /// swell alike in every direction and for anisotropic ones.
    #[test]
    fn the_swelling_chain_is_the_bilayer_law() {
        use crate::rest::laws::bilayer::{bilayer, Stretch};
        let a0 = Sym2::new(1.2, 0.1, 0.9);
        let b0 = Sym2::new(0.3, 0.0, -0.1);
        let lam = crate::config::growth::Laminate {
            top_fraction: 0.4,
            modulus_ratio: 3.0,
            isotropic: false,
        };
        let print = Some(crate::rest::laws::bilayer::Print {
            thickness: 0.002,
            modulus_ratio: 4.0,
        });
        let d = [0.4, 0.9];
        for mu in [[(0.3, 0.3), (-0.2, -0.2)], [(0.3, 0.0), (0.05, -0.2)]] {
            let shape = [Chain::layer_shape(mu[0]), Chain::layer_shape(mu[1])];
            let chain = Chain::Swelling {
                basis: vec![Chain::swelling_basis(
                    &a0, &b0, 0.01, &lam, print, 1.0, shape, d,
                )],
                ratio: vec![1.0],
                shape: vec![shape],
                gel: None,
            };
            for (mt, mb) in [(0.05, -0.03), (0.2, 0.1), (-0.1, 0.0)] {
                // The scene's own strains: ε = (largest coefficient) × moisture.
                let eps = |m: (Real, Real), x: Real| x * Chain::layer_scale(m);
                let got = chain.face(0, &[eps(mu[0], mt), eps(mu[1], mb)]).forms;
                let (top, bottom) = (Stretch::of(mu[0], mt), Stretch::of(mu[1], mb));
                let (a, b, _) = bilayer(&a0, &b0, 0.01, top, bottom, d, &lam, print);
                assert!((got.0 - a).amax() < 1e-14 * a.amax(), "{got:?} {a:?}");
                assert!((got.1 - b).amax() < 1e-12 * b.amax(), "{got:?} {b:?}");
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
