//! Seed 003's strain-limiting Baraff–Witkin cloth membrane.
//!
//! ## Formula (seed 003)
//! `Ψ = λ [ψ(s_u) + ψ(s_v)] + μ I₆²`, `ψ(s) = (s − 1)² + r (s − 1)³` for `s > 1`, `(s − 1)²`
//! otherwise, with `s_u = ‖F û‖`, `s_v = ‖F v̂‖`, `I₆ = ûᵀFᵀF v̂`, `F = D_s D_m⁻¹`, and the face's
//! energy `E = V Ψ`, `V = 2 t A₀`.
//!
//! ## In shellsim's terms
//! * **Thickness.** The seed's `t` is one-sided (half the sheet), so `V = 2tA₀ = h A₀` with
//!   `h = material.thickness`, the full thickness, the same volume the mass `ρ h A₀` uses.
//! * **Directions.** `û` (warp) is given per face in barycentric coordinates `c` (the
//!   projection of a reference-Cartesian direction on the rest face, see the settings), and
//!   normalised in the current rest metric: `u = c/√(cᵀāc)`. The weft is the rest-orthogonal
//!   unit direction `v = J ā u / √det ā` (`J` the quarter turn, so `(u, v)` is right-handed with
//!   the face normal). With `F = D_s D_m⁻¹` and `D_mᵀD_m = ā`, `D_sᵀD_s = a`:
//!   `s_u² = uᵀa u = ℓ_u·a`, `s_v² = ℓ_v·a`, `I₆ = uᵀ a v = m·a`, with
//!   `ℓ_u = (u₀², 2u₀u₁, u₁²)` and `m = (u₀v₀, u₀v₁ + u₁v₀, u₁v₁)`. No canonical rotation of the
//!   rest normal is needed, so no frame jump for faces facing any direction.
//! * **Constants.** λ, μ (Pa) from the settings, or from E, ν: `λ = E/2`, `μ = E/(4(1+ν))`
//!   (small strains: `Ψ ≈ λ(ε_uu² + ε_vv²) + 4μ ε_uv²`, i.e. Young's modulus E along both
//!   yarn directions with no Poisson coupling, and shear modulus `G = 2μ = E/(2(1+ν))`).
//!
//! ## Derivatives
//! `∂ψ(s)/∂a = ψ'(s) ℓ/(2s)`, `∂²ψ(s)/∂a² = (ψ''(s)/(4s²) − ψ'(s)/(4s³)) ℓℓᵀ`,
//! `∂I₆²/∂a = 2I₆ m`, `∂²I₆²/∂a² = 2mmᵀ`. The branch `s > 1` is chosen once per evaluation and
//! used for the energy, gradient and Hessian alike (ψ is C² at s = 1, not C³).
//!
//! ## Positive semi-definite Hessian (closed form)
//! `∂²Ψ/∂a²` is a sum of rank-one terms `c ℓℓᵀ` with closed-form coefficients; the projection
//! clamps each `c` at 0. The term `Σ_k (∂Ψ/∂a)_k ∇²a_k = 2G ⊗ I₃` in the edge vectors has the
//! 2×2 form `G`, projected by its closed-form eigensystem ([`super::psd_ga`]). Their sum is
//! positive semi-definite and equals the exact Hessian wherever both parts already are.
//!
//! Units: E in J, λ and μ in Pa, `a` in m².

use super::{bending_wells, psd_ga, Membrane, MembraneLaw, WithKoiterBending};
use crate::body::Body;
use crate::energy::Potential;
use crate::math::{sym_det, Mat3, Real, SVec, Sym2, Vec2};

/// The Baraff–Witkin membrane: per-face constants and warp directions.
#[derive(Clone, Debug)]
pub struct BaraffWitkin {
    /// Per face `(λ, μ)` (Pa).
    pub moduli: Vec<(Real, Real)>,
    /// The cubic strain-limiting coefficient `r` (dimensionless, ≥ 0).
    pub r: Real,
    /// Per face, the warp direction in barycentric coordinates (any length).
    pub directions: Vec<Vec2>,
}

/// `ψ(s)`, `ψ'(s)`, `ψ''(s)` on the branch of `s`.
#[inline]
pub fn psi(s: Real, r: Real) -> (Real, Real, Real) {
    let d = s - 1.0;
    if d > 0.0 {
        (
            d * d + r * d * d * d,
            2.0 * d + 3.0 * r * d * d,
            2.0 + 6.0 * r * d,
        )
    } else {
        (d * d, 2.0 * d, 2.0)
    }
}

/// The law on one face.
#[derive(Clone, Copy, Debug)]
pub struct BaraffWitkinFace {
    /// `V λ` (J).
    pub wl: Real,
    /// `V μ` (J).
    pub wm: Real,
    /// `r`.
    pub r: Real,
    /// `ℓ_u`.
    pub lu: SVec<3>,
    /// `ℓ_v`.
    pub lv: SVec<3>,
    /// `m`.
    pub m: SVec<3>,
}

impl BaraffWitkinFace {
    /// The law for rest metric `ā`, barycentric warp direction `c`, thickness `h`, constants.
    pub fn new(abar: &Sym2, c: &Vec2, h: Real, lambda: Real, mu: Real, r: Real) -> Self {
        let ab = crate::math::sym_to_mat(abar);
        let u = c / (c.dot(&(ab * c))).sqrt();
        let w = ab * u;
        let det = sym_det(abar);
        let v = Vec2::new(-w[1], w[0]) / det.sqrt();
        let vol = h * 0.5 * det.max(0.0).sqrt();
        let l = |p: &Vec2| SVec::<3>::new(p[0] * p[0], 2.0 * p[0] * p[1], p[1] * p[1]);
        BaraffWitkinFace {
            wl: vol * lambda,
            wm: vol * mu,
            r,
            lu: l(&u),
            lv: l(&v),
            m: SVec::<3>::new(u[0] * v[0], u[0] * v[1] + u[1] * v[0], u[1] * v[1]),
        }
    }

    /// The stretches `(s_u, s_v)` and the shear invariant `I₆` at `a`.
    pub fn invariants(&self, a: &Sym2) -> (Real, Real, Real) {
        (
            self.lu.dot(a).max(0.0).sqrt(),
            self.lv.dot(a).max(0.0).sqrt(),
            self.m.dot(a),
        )
    }

    /// Energy, and the rank-one coefficients `(c_u, c_v)` of `∂²/∂a²` and the gradient.
    #[inline]
    fn parts(&self, a: &Sym2) -> (Real, Sym2, [Real; 2]) {
        let (su, sv, i6) = self.invariants(a);
        let mut e = self.wm * i6 * i6;
        let mut g = self.m * (2.0 * self.wm * i6);
        let mut c = [0.0; 2];
        for (k, (s, l)) in [(su, &self.lu), (sv, &self.lv)].into_iter().enumerate() {
            let (p, p1, p2) = psi(s, self.r);
            e += self.wl * p;
            g += l * (self.wl * p1 / (2.0 * s));
            c[k] = self.wl * (p2 / (4.0 * s * s) - p1 / (4.0 * s * s * s));
        }
        (e, g, c)
    }
}

impl MembraneLaw for BaraffWitkinFace {
    #[inline]
    fn eval(&self, a: &Sym2, derivs: Option<(&mut Sym2, &mut Mat3)>) -> Real {
        let (e, g, c) = self.parts(a);
        if let Some((ga, haa)) = derivs {
            *ga = g;
            *haa = self.lu * self.lu.transpose() * c[0]
                + self.lv * self.lv.transpose() * c[1]
                + self.m * self.m.transpose() * (2.0 * self.wm);
        }
        e
    }

    fn psd(&self, a: &Sym2, ga: &mut Sym2, haa: &mut Mat3) {
        let (_, g, c) = self.parts(a);
        *ga = psd_ga(&g);
        *haa = self.lu * self.lu.transpose() * c[0].max(0.0)
            + self.lv * self.lv.transpose() * c[1].max(0.0)
            + self.m * self.m.transpose() * (2.0 * self.wm);
    }
}

impl Membrane for BaraffWitkin {
    type Density = WithKoiterBending<BaraffWitkinFace>;
    #[inline]
    fn density(&self, pot: &Potential, f: usize) -> Self::Density {
        let (abar, _) = pot.rest_forms(f);
        let (l, m) = self.moduli[f];
        let (l, m) = (l * pot.modulus(f), m * pot.modulus(f));
        let s = pot.stretch_scale;
        WithKoiterBending {
            law: BaraffWitkinFace::new(
                &abar,
                &self.directions[f],
                pot.thickness(f),
                l * s,
                m * s,
                self.r,
            ),
            koiter: bending_wells(pot, f),
        }
    }
}

/// The material of a scene: directions from the face field `warp_direction` (3 components,
/// reference Cartesian) when present, else `material.baraff_witkin.direction`, each projected on
/// its rest face; constants from `material.baraff_witkin` or from each face's E and ν.
/// A zero or non-finite direction, or one normal to a face, is an error naming the face.
pub fn from_scene(
    body: &Body,
    bw: &crate::config::material::BaraffWitkinSettings,
) -> Result<BaraffWitkin, crate::mesh::MeshError> {
    use crate::math::Vec3;
    let mesh = &body.mesh;
    let field = mesh.face_field("warp_direction", 3)?;
    let mut directions = Vec::with_capacity(mesh.faces.len());
    for f in 0..mesh.faces.len() {
        let (d, what) = match field {
            Some(df) => (
                Vec3::from_column_slice(df.get(f)),
                "face field 'warp_direction'",
            ),
            None => (Vec3::from(bw.direction), "material.baraff_witkin.direction"),
        };
        let c = crate::rest::barycentric_direction(mesh, f, &d).ok_or_else(|| {
            mesh.invalid(format!(
                "{what} at face {f} is [{}, {}, {}]: it must be finite, non-zero and not normal \
                 to the face",
                d.x, d.y, d.z
            ))
        })?;
        directions.push(Vec2::new(c[0], c[1]));
    }
    let nu = body.poisson;
    let moduli = body
        .young
        .iter()
        .map(|&e| {
            (
                bw.lambda.unwrap_or(0.5 * e),
                bw.mu.unwrap_or(e / (4.0 * (1.0 + nu))),
            )
        })
        .collect();
    Ok(BaraffWitkin {
        moduli,
        r: bw.r,
        directions,
    })
}
