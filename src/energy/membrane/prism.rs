//! Seed 002's three-prism membrane element (§4): a triangle with a thickness, deformed by the
//! constant 3D deformation gradient
//!
//! `F = [e₁₂ e₁₃ d h] [ē₁₂ ē₁₃ d̄ h̄]⁻¹` (Eq. 4),
//!
//! `d`, `d̄` the unit normals, `h`, `h̄` the current and rest thickness, with a 3D strain energy
//! density ψ(F) per unit rest volume, `W = V̄ ψ`, `V̄ = h̄ Ā` (Eq. 5 with a constant F).
//!
//! **Invariants.** `d ⟂ e₁₂, e₁₃` and `d̄ ⟂ ē₁₂, ē₁₃`, so in the rest basis
//! `FᵀF = M⁻ᵀ blockdiag(a, h²) M⁻¹` with `M = [ē₁₂ ē₁₃ d̄ h̄]`, and `C = FᵀF` has the eigenvalues
//! of `blockdiag(ā⁻¹a, (h/h̄)²)`: the in-plane stretch tensor `C₂ = ā⁻¹a` of the face's first
//! fundamental form (barycentric, as every membrane here) and `C₃₃ = c = (h/h̄)²`, uncoupled.
//! Every 3D invariant is a function of `u = tr C₂ = t·a` (`t = (Ā¹¹, 2Ā¹², Ā²²)`, `Ā = ā⁻¹`),
//! `δ = det a` (`det C₂ = δ/det ā`) and `c`, so the element is a membrane law `W(a)` and composes
//! with any bending model (balloons use none). Tests rebuild F from the vertices by Eq. 4 and
//! compare.
//!
//! **Densities** (3D Lamé parameters `μ = E/(2(1+ν))`, `λ = Eν/((1+ν)(1−2ν))`):
//! * St Venant–Kirchhoff (Eqs. 6–7): `ψ = μ E:E + λ/2 tr²E`, `E = (C − I)/2`, so
//!   `E:E = ¼(u² − 2u + 2 − 2δ/det ā) + ¼(c − 1)²`, `tr E = (u + c − 3)/2`;
//! * neo-Hookean: `ψ = μ/2 (I₁ − 3) − μ ln J + λ/2 ln²J`, `I₁ = u + c`, `J² = c δ/det ā`.
//!
//! **Thickness**, two ways (`material.prism.thickness`):
//! * `"incompressible"` (default): `h = h̄ Ā/A`, i.e. `c = det ā/δ` and `J = 1`, inside the energy:
//!   the skin's volume `Σ A h` is preserved to round-off and the Hessian is that of the energy
//!   minimised. The neo-Hookean prism is then exactly the incompressible neo-Hookean membrane
//!   (`λ` drops out); the St Venant–Kirchhoff one keeps `λ/2 tr²E`, so it needs ν < ½;
//! * `"pbd"`: the seed's way. `h` is a per-face parameter during each implicit step, and after the
//!   step a position-based projection (§7, Algorithm 2; [`Prism::project`]) moves the vertices and
//!   one virtual vertex per face, `x₄ = centroid + h d`, to restore the skin's volume
//!   `V_b = Σ ½ e₁₄·(e₁₂ × e₁₃)` (Eq. 26), and reads `h` back from the virtual vertices. Needs
//!   ν < ½ and dynamics.
//!
//! **Derivatives.** With `ψ(u, δ)` (and `c(δ)` = `det ā/δ` or constant):
//! `∂W/∂a = V̄ (ψ_u t + ψ_δ ∇δ)`,
//! `∂²W/∂a² = V̄ (ψ_uu t tᵀ + ψ_uδ (t ∇δᵀ + ∇δ tᵀ) + ψ_δδ ∇δ ∇δᵀ + ψ_δ ∇²δ)`,
//! `∇δ = (a₂₂, −2a₁₂, a₁₁)`, `∇²δ = [[0, 0, 1], [0, −2, 0], [1, 0, 0]]` (in `[a₁₁, a₁₂, a₂₂]`).
//! Units: W in J, a in m², μ and λ in Pa.

use super::{bending_wells, psd3, psd_ga, Membrane, MembraneLaw, WithKoiterBending};
use crate::body::Body;
use crate::energy::Potential;
use crate::math::{sym_det, sym_to_mat, Mat3, Real, SVec, Sym2, Vec3};
use crate::settings::{PrismLaw, PrismThickness};

/// The 3D St Venant–Kirchhoff or neo-Hookean prism membrane of one face.
#[derive(Clone, Copy, Debug)]
pub struct PrismFace {
    /// The density law.
    pub law: PrismLaw,
    /// `V̄ = h̄ √det ā / 2` times the energy scale (m³).
    pub vol: Real,
    /// 3D Lamé μ (Pa).
    pub mu: Real,
    /// 3D Lamé λ (Pa); unused by the incompressible neo-Hookean prism.
    pub lambda: Real,
    /// `t = (Ā¹¹, 2Ā¹², Ā²²)`.
    pub t: SVec<3>,
    /// `det ā` (m⁴).
    pub det_abar: Real,
    /// `None`: incompressible thickness, `c = det ā/δ`; `Some(c)`: `c = (h/h̄)²` given.
    pub c: Option<Real>,
}

/// ψ and its derivatives in `(u, δ)`: `[ψ, ψ_u, ψ_δ, ψ_uu, ψ_uδ, ψ_δδ]`.
type Psi = [Real; 6];

impl PrismFace {
    /// The law for rest metric `ā`, rest thickness `h̄`, Young's modulus and Poisson's ratio
    /// (3D Lamé parameters), thickness mode `c`, energy × `scale`.
    pub fn new(
        law: PrismLaw,
        abar: &Sym2,
        h: Real,
        young: Real,
        poisson: Real,
        c: Option<Real>,
        scale: Real,
    ) -> Self {
        let det_abar = sym_det(abar);
        let ai = sym_to_mat(abar).try_inverse().unwrap_or_default();
        let mu = young / (2.0 * (1.0 + poisson));
        let lambda = if poisson < 0.5 {
            young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson))
        } else {
            0.0
        };
        PrismFace {
            law,
            vol: h * 0.5 * det_abar.max(0.0).sqrt() * scale,
            mu,
            lambda,
            t: SVec::<3>::new(ai[(0, 0)], 2.0 * ai[(0, 1)], ai[(1, 1)]),
            det_abar,
            c,
        }
    }

    /// ψ(u, δ) and its derivatives (module doc).
    #[inline]
    fn psi(&self, u: Real, d: Real) -> Psi {
        let (mu, lam, da) = (self.mu, self.lambda, self.det_abar);
        // c(δ) and its derivatives.
        let (c, c1, c2) = match self.c {
            None => (da / d, -da / (d * d), 2.0 * da / (d * d * d)),
            Some(c) => (c, 0.0, 0.0),
        };
        match self.law {
            PrismLaw::Stvk => {
                let tr = u + c - 3.0; // 2 tr E
                let psi = mu
                    * (0.25 * (u * u - 2.0 * u + 2.0 - 2.0 * d / da)
                        + 0.25 * (c - 1.0) * (c - 1.0))
                    + lam / 8.0 * tr * tr;
                let pu = 0.5 * mu * (u - 1.0) + 0.25 * lam * tr;
                let pd = mu * (-0.5 / da + 0.5 * (c - 1.0) * c1) + 0.25 * lam * tr * c1;
                let puu = 0.5 * mu + 0.25 * lam;
                let pud = 0.25 * lam * c1;
                let pdd = 0.5 * mu * (c1 * c1 + (c - 1.0) * c2) + 0.25 * lam * (c1 * c1 + tr * c2);
                [psi, pu, pd, puu, pud, pdd]
            }
            PrismLaw::NeoHookean => match self.c {
                // J = 1: ψ = μ/2 (u + det ā/δ − 3).
                None => [
                    0.5 * mu * (u + c - 3.0),
                    0.5 * mu,
                    0.5 * mu * c1,
                    0.0,
                    0.0,
                    0.5 * mu * c2,
                ],
                Some(c) => {
                    let lj = 0.5 * (c * d / da).ln();
                    let psi = 0.5 * mu * (u + c - 3.0) - mu * lj + 0.5 * lam * lj * lj;
                    let pd = (-mu + lam * lj) / (2.0 * d);
                    let pdd = lam / (4.0 * d * d) + (mu - lam * lj) / (2.0 * d * d);
                    [psi, 0.5 * mu, pd, 0.0, 0.0, pdd]
                }
            },
        }
    }
}

impl MembraneLaw for PrismFace {
    #[inline]
    fn eval(&self, a: &Sym2, derivs: Option<(&mut Sym2, &mut Mat3)>) -> Real {
        let (d, gd, hd) = super::neo_hookean::det_derivs(a);
        let u = self.t.dot(a);
        let [psi, pu, pd, puu, pud, pdd] = self.psi(u, d);
        if let Some((ga, haa)) = derivs {
            let t = &self.t;
            *ga = (t * pu + gd * pd) * self.vol;
            *haa = (t * t.transpose() * puu
                + (t * gd.transpose() + gd * t.transpose()) * pud
                + gd * gd.transpose() * pdd
                + hd * pd)
                * self.vol;
        }
        self.vol * psi
    }

    fn psd(&self, a: &Sym2, ga: &mut Sym2, haa: &mut Mat3) {
        let (mut g, mut h) = (Sym2::zeros(), Mat3::zeros());
        self.eval(a, Some((&mut g, &mut h)));
        *ga = psd_ga(&g);
        *haa = psd3(&h);
    }
}

/// The prism membrane material. In the `"pbd"` mode its shell term carries the current
/// thickness of each face (m) as its state ([`crate::energy::term::Stateful`]).
pub struct Prism {
    /// The density law.
    pub law: PrismLaw,
    /// Incompressible thickness or the seed's position-based volume preservation.
    pub mode: PrismThickness,
    /// Projections per step of the position-based mode (1 in the seed).
    pub iterations: usize,
    /// Poisson's ratio ν.
    pub poisson: Real,
    /// The rest thickness of each face (m): the `"pbd"` mode's initial state.
    rest_thickness: Vec<Real>,
    /// Mass density ρ (kg/m³), for the projection's weights.
    density: Real,
}

impl Prism {
    /// The material of a scene with the constants `p` (`[material.prism]`): the current
    /// thickness starts at the rest thickness.
    pub fn new(body: &Body, p: &crate::config::material::PrismSettings) -> Self {
        Prism {
            law: p.law,
            mode: p.thickness,
            iterations: p.pbd_iterations,
            poisson: body.poisson,
            rest_thickness: body.thickness.clone(),
            density: body.density,
        }
    }

    /// The current thickness of face `f` in the `"pbd"` mode (m) that `pot` is evaluated with.
    #[inline]
    fn h(pot: &Potential, f: usize) -> Real {
        pot.term_state(crate::energy::shell::NAME)
            .get(f)
            .copied()
            .unwrap_or(Real::NAN)
    }

    /// The current thickness of every face at positions `x` (m): `h̄ Ā/A` (incompressible) or
    /// the position-based state.
    pub fn current_thickness(&self, pot: &Potential, x: &[Vec3]) -> Vec<Real> {
        let sc = pot.body;
        (0..sc.num_faces())
            .map(|f| match self.mode {
                PrismThickness::Pbd => Self::h(pot, f),
                PrismThickness::Incompressible => {
                    let (abar, _) = pot.rest_forms(f);
                    let t = sc.mesh.faces[f];
                    let a = crate::geometry::first_fundamental_form(&t.map(|v| x[v]));
                    pot.thickness(f) * (sym_det(&abar) / sym_det(&a)).max(0.0).sqrt()
                }
            })
            .collect()
    }

    /// The skin's volume `Σ A h` over its rest volume `Σ Ā h̄` (dimensionless).
    pub fn volume_ratio(&self, pot: &Potential, x: &[Vec3]) -> Real {
        let sc = pot.body;
        let h = self.current_thickness(pot, x);
        let (mut now, mut rest) = (0.0, 0.0);
        for (f, hf) in h.iter().enumerate() {
            let (abar, _) = pot.rest_forms(f);
            let t = sc.mesh.faces[f];
            let [p0, p1, p2] = t.map(|v| x[v]);
            now += 0.5 * (p1 - p0).cross(&(p2 - p0)).norm() * hf;
            rest += 0.5 * sym_det(&abar).max(0.0).sqrt() * pot.thickness(f);
        }
        now / rest
    }

    /// Seed 002 §7, Algorithm 2: one virtual vertex per face, `x₄ = centroid + h d`; the skin's
    /// volume `V_b = Σ ½ e₁₄·(e₁₂ × e₁₃)` (Eq. 26) with the constraint `C = V_b − V_b⁰` (Eq. 24,
    /// `V_b⁰ = Σ Ā h̄`) projected by the position-based step of Müller et al. 2007,
    /// `Δx_i = −(n w_i/Σ_j w_j) C/Σ_j|∇_j C|² ∇_i C` (the seed's Eq. 27 with its second `w_i`
    /// dropped, which makes it dimensionally inconsistent), with `∇C` of Eq. 28, weights
    /// `w = 1/m'` from the masses of Eq. 19 (1/6 of a prism's mass to each of its three vertices,
    /// 1/2 to its virtual vertex; fixed vertices do not move), `n` the number of points. Then
    /// `h` is read back as the height of `x₄` over its moved face. `iterations` projections
    /// (1 in the seed). Moves `x` and the thickness state `own` (from the state `pot` holds);
    /// returns `C/V_b⁰` before the first projection. A thickness that comes out non-positive or
    /// non-finite (the prism turned inside out: `det F ≤ 0`) is an error naming the face, and
    /// the state is left as it was.
    pub fn project(
        &self,
        pot: &Potential,
        x: &mut [Vec3],
        own: &mut [Real],
    ) -> Result<Real, crate::energy::term::StateError> {
        let sc = pot.body;
        let faces = &sc.mesh.faces;
        let nf = faces.len();
        let nv = x.len();
        let rho = self.density;
        let rest_vol: Vec<Real> = (0..nf)
            .map(|f| 0.5 * sym_det(&pot.rest_forms(f).0).max(0.0).sqrt() * pot.thickness(f))
            .collect();
        let v0: Real = rest_vol.iter().sum();
        // Weights: real vertices then virtual ones.
        let mut m = vec![0.0; nv];
        for (f, t) in faces.iter().enumerate() {
            for &v in t {
                m[v] += rho * rest_vol[f] / 6.0;
            }
        }
        let w: Vec<Real> = (0..nv)
            .map(|v| {
                if sc.fixed[v] || m[v] <= 0.0 {
                    0.0
                } else {
                    1.0 / m[v]
                }
            })
            .chain(rest_vol.iter().map(|&vol| 2.0 / (rho * vol)))
            .collect();
        let n_points = (nv + nf) as Real;
        let w_sum: Real = w.iter().sum();
        let mut h: Vec<Real> = (0..nf).map(|f| Self::h(pot, f)).collect();
        let mut first = 0.0;
        for it in 0..self.iterations.max(1) {
            // Virtual vertices at the current thickness.
            let mut x4: Vec<Vec3> = (0..nf)
                .map(|f| {
                    let [p0, p1, p2] = faces[f].map(|v| x[v]);
                    let d = (p1 - p0).cross(&(p2 - p0)).normalize();
                    (p0 + p1 + p2) / 3.0 + d * h[f]
                })
                .collect();
            let mut grad = vec![Vec3::zeros(); nv + nf];
            let mut vb = 0.0;
            for f in 0..nf {
                let [p1, p2, p3] = faces[f].map(|v| x[v]);
                let p4 = x4[f];
                let (e12, e13, e14) = (p2 - p1, p3 - p1, p4 - p1);
                vb += 0.5 * e14.dot(&e12.cross(&e13));
                let (e23, e24) = (p3 - p2, p4 - p2);
                grad[faces[f][0]] += 0.5 * e24.cross(&e23);
                grad[faces[f][1]] += 0.5 * e13.cross(&e14);
                grad[faces[f][2]] += 0.5 * e14.cross(&e12);
                grad[nv + f] += 0.5 * e12.cross(&e13);
            }
            let c = vb - v0;
            if it == 0 {
                first = c / v0;
            }
            let g2: Real = grad.iter().map(|g| g.norm_squared()).sum();
            if g2 <= 0.0 || c == 0.0 {
                break;
            }
            let s = c / g2;
            for (i, g) in grad.iter().enumerate() {
                let dx = g * (-(n_points * w[i] / w_sum) * s);
                if i < nv {
                    x[i] += dx;
                } else {
                    x4[i - nv] += dx;
                }
            }
            for (f, p4) in x4.iter().enumerate() {
                let [p0, p1, p2] = faces[f].map(|v| x[v]);
                let d = (p1 - p0).cross(&(p2 - p0)).normalize();
                h[f] = (p4 - (p0 + p1 + p2) / 3.0).dot(&d);
            }
        }
        if let Some(f) = h.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(crate::energy::term::StateError {
                face: f,
                reason: format!(
                    "the position-based projection turned the prism inside out (thickness {}; \
                     rest thickness {})",
                    crate::math::human(h[f]),
                    crate::math::human(pot.thickness(f))
                ),
            });
        }
        own.copy_from_slice(&h);
        Ok(first)
    }

    /// Checks a thickness state (a restart): one positive finite value per face.
    pub fn check_thickness(&self, h: &[Real]) -> Result<(), crate::energy::term::StateError> {
        if h.len() != self.rest_thickness.len() {
            return Err(crate::energy::term::StateError {
                face: h.len().min(self.rest_thickness.len()),
                reason: format!(
                    "the thickness state has {} values for {} faces",
                    h.len(),
                    self.rest_thickness.len()
                ),
            });
        }
        for (f, &v) in h.iter().enumerate() {
            if !(v.is_finite() && v > 0.0) {
                return Err(crate::energy::term::StateError {
                    face: f,
                    reason: format!(
                        "thickness {} is not a positive finite number",
                        crate::math::human(v)
                    ),
                });
            }
        }
        Ok(())
    }
}

impl Membrane for Prism {
    type Density = WithKoiterBending<PrismFace>;
    #[inline]
    fn density(&self, pot: &Potential, f: usize) -> Self::Density {
        let (abar, _) = pot.rest_forms(f);
        let sc = pot.body;
        let h0 = pot.thickness(f);
        let c = match self.mode {
            PrismThickness::Incompressible => None,
            PrismThickness::Pbd => {
                let r = Self::h(pot, f) / h0;
                Some(r * r)
            }
        };
        WithKoiterBending {
            law: PrismFace::new(
                self.law,
                &abar,
                h0,
                sc.young[f] * pot.modulus(f),
                self.poisson,
                c,
                pot.stretch_scale,
            ),
            koiter: bending_wells(pot, f),
        }
    }

    /// `thickness`: the current thickness (m).
    fn face_fields(&self, pot: &Potential, x: &[Vec3]) -> Vec<(String, Vec<Real>)> {
        vec![("thickness".into(), self.current_thickness(pot, x))]
    }

    /// `skin_volume_ratio`: the skin's volume over its rest volume.
    fn observables(&self, pot: &Potential, x: &[Vec3]) -> Vec<(String, Real)> {
        vec![("skin_volume_ratio".into(), self.volume_ratio(pot, x))]
    }

    fn projects(&self) -> bool {
        self.mode == PrismThickness::Pbd
    }

    fn project(
        &self,
        pot: &Potential,
        x: &mut [Vec3],
        own: &mut [Real],
    ) -> Result<Option<Real>, crate::energy::term::StateError> {
        match self.mode {
            PrismThickness::Pbd => Prism::project(self, pot, x, own).map(Some),
            PrismThickness::Incompressible => Ok(None),
        }
    }

    fn state_field(&self) -> Option<&'static str> {
        (self.mode == PrismThickness::Pbd).then_some("thickness")
    }

    /// `"pbd"`: the rest thickness of each face (m).
    fn initial_state(&self) -> Option<Vec<Real>> {
        (self.mode == PrismThickness::Pbd).then(|| self.rest_thickness.clone())
    }

    fn check_state(&self, state: &[Real]) -> Result<(), crate::energy::term::StateError> {
        self.check_thickness(state)
    }

    fn restore(
        &self,
        field: Option<&[Real]>,
        own: &mut [Real],
    ) -> Result<Option<String>, crate::energy::term::StateError> {
        match field {
            Some(h) => {
                self.check_thickness(h)?;
                own.copy_from_slice(h);
                Ok(None)
            }
            None => Ok(Some(
                "the frame has no 'thickness': the position-based thickness restarts at the rest \
                 thickness"
                    .into(),
            )),
        }
    }
}
