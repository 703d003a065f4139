//! Membrane materials: the stretching energy of a face as a function of its first fundamental
//! form `a` (barycentric, m²), one file each. Every material composes with every bending model
//! through [`crate::energy::shell`]; the bending energy is always the Koiter plate term
//! `h³/12 ‖ā⁻¹(b − b̄)‖²_SV √det ā / 2` with the plane-stress Lamé parameters of the face's E, ν,
//! and the Kelvin–Voigt damping of seed 000 §3 keeps its Koiter form for every material.
//!
//! * [`koiter`]: St Venant–Kirchhoff / Koiter (seed 000), the default;
//! * [`neo_hookean`]: incompressible neo-Hookean rubber;
//! * [`mooney_rivlin`]: incompressible Mooney–Rivlin rubber;
//! * [`gent`]: incompressible Gent rubber (limited chain extensibility);
//! * [`baraff_witkin`]: seed 003's strain-limiting Baraff–Witkin cloth;
//! * [`prism`]: seed 002's three-prism element with a thickness (3D St Venant–Kirchhoff or
//!   neo-Hookean), incompressible or with the seed's position-based volume preservation.

pub mod baraff_witkin;
pub mod gent;
pub mod koiter;
pub mod mooney_rivlin;
pub mod neo_hookean;
pub mod prism;

use crate::energy::material::{DensityDerivs, FaceDensity, KoiterDensity};
use crate::energy::term::StateError;
use crate::energy::Potential;
use crate::math::{Mat3, Real, Sym2, Vec3};

/// A membrane material: gives each face's energy density at a potential's rest state.
pub trait Membrane: Send + Sync + 'static {
    /// The per-face density (membrane + Koiter bending + damping).
    type Density: FaceDensity;
    /// The density of face `f`.
    fn density(&self, pot: &Potential, f: usize) -> Self::Density;

    /// Per-face fields for the frames (default: none).
    fn face_fields(&self, _pot: &Potential, _x: &[Vec3]) -> Vec<(String, Vec<Real>)> {
        Vec::new()
    }

    /// Quantities for `log.csv` (default: none).
    fn observables(&self, _pot: &Potential, _x: &[Vec3]) -> Vec<(String, Real)> {
        Vec::new()
    }

    /// Whether the membrane projects the state after each accepted implicit step (default:
    /// no); its shell term then declares [`crate::energy::term::Projection`] with
    /// [`Membrane::project`].
    fn projects(&self) -> bool {
        false
    }

    /// The projection of the state `own` (see [`crate::energy::term::Projection`]; default:
    /// none).
    fn project(
        &self,
        _pot: &Potential,
        _x: &mut [Vec3],
        _own: &mut [Real],
    ) -> Result<Option<Real>, StateError> {
        Ok(None)
    }

    /// The name of the per-face field that shows the membrane's state, one value per face
    /// (default: none, a stateless membrane).
    fn state_field(&self) -> Option<&'static str> {
        None
    }

    /// The state at the start of a run, one value per face, when the membrane has one: its
    /// shell term then declares [`crate::energy::term::Stateful`] and
    /// [`crate::energy::term::Tracked`] (default: none).
    fn initial_state(&self) -> Option<Vec<Real>> {
        None
    }

    /// The rest data of face `f` for the rest sensitivities
    /// ([`crate::energy::sensitivity`]), or an error naming why the material has none
    /// (default: none; the Koiter membrane has them).
    fn rest_face(
        &self,
        _pot: &Potential,
        _f: usize,
    ) -> Result<crate::energy::sensitivity::KoiterFace, String> {
        Err(
            "its rest sensitivities are derived for the Koiter membrane only \
             (material.membrane = \"koiter\")"
                .into(),
        )
    }

    /// Checks a state read from a restart (default: anything goes).
    fn check_state(&self, _state: &[Real]) -> Result<(), StateError> {
        Ok(())
    }

    /// Restores the state `own` from a restart frame's field (`None` when absent).
    fn restore(
        &self,
        _field: Option<&[Real]>,
        _own: &mut [Real],
    ) -> Result<Option<String>, StateError> {
        Ok(None)
    }
}

/// A hyperelastic membrane law of one face, `W(a)` (J), with its derivatives in `a`.
pub trait MembraneLaw: Copy {
    /// `W(a)`; sets `ga = ∂W/∂a` and `haa = ∂²W/∂a²` when `derivs`.
    fn eval(&self, a: &Sym2, derivs: Option<(&mut Sym2, &mut Mat3)>) -> Real;
    /// Positive semi-definite Hessian data at `a`: `haa⁺` (3×3) and `ga⁺`, the coefficient of
    /// `Σ_k ∇²a_k` kept (its 2×2 form `[[2g0, g1], [g1, 2g2]]` positive semi-definite).
    fn psd(&self, a: &Sym2, ga: &mut Sym2, haa: &mut Mat3);
}

/// A membrane law plus the Koiter bending and damping wells (whose stretching well 0 has weight
/// 0: the law replaces it).
#[derive(Clone, Copy, Debug)]
pub struct WithKoiterBending<L> {
    /// The membrane law.
    pub law: L,
    /// Bending (and damping) wells.
    pub koiter: KoiterDensity,
}

impl<L: MembraneLaw> FaceDensity for WithKoiterBending<L> {
    #[inline]
    fn uses_b(&self) -> bool {
        self.koiter.uses_b()
    }

    #[inline]
    fn eval(&self, a: &Sym2, b: &Sym2, d: &mut DensityDerivs) -> Real {
        let e = self.koiter.eval(a, b, d);
        let (mut ga, mut haa) = (Sym2::zeros(), Mat3::zeros());
        let w = self.law.eval(a, Some((&mut ga, &mut haa)));
        d.ga += ga;
        d.haa += haa;
        e + w
    }

    #[inline]
    fn eval_gradient(&self, a: &Sym2, b: &Sym2, d: &mut DensityDerivs) -> Real {
        let e = self.koiter.eval_gradient(a, b, d);
        let (mut ga, mut haa) = (Sym2::zeros(), Mat3::zeros());
        let w = self.law.eval(a, Some((&mut ga, &mut haa)));
        d.ga += ga;
        e + w
    }

    fn gauss_newton(&self, a: &Sym2, b: &Sym2, d: &mut DensityDerivs) {
        let mut dk = DensityDerivs::default();
        self.koiter.eval(a, b, &mut dk);
        let (mut ga, mut haa) = (Sym2::zeros(), Mat3::zeros());
        self.law.psd(a, &mut ga, &mut haa);
        d.haa = dk.haa + haa;
        d.ga_psd = ga;
    }

    fn elastic_parts(&self, a: &Sym2, b: &Sym2) -> (Real, Real) {
        (self.law.eval(a, None), self.koiter.elastic_parts(a, b).1)
    }
}

/// The Koiter density of face `f` with its elastic stretching well switched off (the bending
/// and damping wells of every non-Koiter material).
#[inline]
pub fn bending_wells(pot: &Potential, f: usize) -> KoiterDensity {
    let mut d = pot.density(f);
    d.stretch[0].0 = 0.0;
    d
}

/// The positive semi-definite part of a `ga` coefficient: its 2×2 form
/// `M = [[2g0, g1], [g1, 2g2]]` (the Hessian of `Σ_k g_k a_k` in the edge vectors, ⊗ I₃) with
/// negative eigenvalues clamped to 0, in closed form.
pub fn psd_ga(g: &Sym2) -> Sym2 {
    let (m00, m01, m11) = (2.0 * g[0], g[1], 2.0 * g[2]);
    let tr = m00 + m11;
    let det = m00 * m11 - m01 * m01;
    if m00 >= 0.0 && m11 >= 0.0 && det >= 0.0 {
        return *g;
    }
    let disc = (0.25 * (m00 - m11) * (m00 - m11) + m01 * m01).sqrt();
    let l1 = 0.5 * tr + disc; // the larger eigenvalue
    if l1 <= 0.0 {
        return Sym2::zeros();
    }
    // Eigenvector of l1: (m01, l1 − m00) or (l1 − m11, m01).
    let (vx, vy) = if (l1 - m00).abs() + m01.abs() > (l1 - m11).abs() + m01.abs() {
        (m01, l1 - m00)
    } else {
        (l1 - m11, m01)
    };
    let n2 = vx * vx + vy * vy;
    if n2 == 0.0 {
        return Sym2::new(0.5 * m00.max(0.0), 0.0, 0.5 * m11.max(0.0));
    }
    let s = l1 / n2;
    Sym2::new(0.5 * s * vx * vx, s * vx * vy, 0.5 * s * vy * vy)
}

/// Clamps the negative eigenvalues of a symmetric 3×3 matrix to 0 (cyclic Jacobi, no
/// allocation).
pub fn psd3(m: &Mat3) -> Mat3 {
    let (vals, vecs) = crate::energy::projection::jacobi_eigen(m);
    if vals.iter().all(|&l| l >= 0.0) {
        return *m;
    }
    let mut out = Mat3::zeros();
    for k in 0..3 {
        if vals[k] > 0.0 {
            let v = vecs.column(k);
            out += v * v.transpose() * vals[k];
        }
    }
    out
}

/// The stretch λ* at which a thin sphere of `material` inflated by a gas reaches its pressure
/// maximum (the limit point of pressure control), or `None` when its pressure rises
/// monotonically (St Venant–Kirchhoff) or the law has no closed form here (Baraff–Witkin, the
/// prism element). For an incompressible membrane in equibiaxial stretch λ (λ₃ = λ⁻²) the
/// pressure is `p = (H/R) W′(λ)/λ²` with `W` per unit reference volume (Beatty 1987, "Topics in
/// finite elasticity", §8), so up to a constant:
///
/// * neo-Hookean: `1/λ − 1/λ⁷` (λ* = 7^(1/6));
/// * Mooney–Rivlin: `(c₁ + c₂λ²)(1/λ − 1/λ⁷)`;
/// * Gent: `(1/λ − 1/λ⁷)/(1 − (2λ² + λ⁻⁴ − 3)/J_m)`.
///
/// The first local maximum on a scan of λ ∈ (1, 50] in steps of 1e-3, refined by golden
/// section to 1e-10.
pub fn thin_sphere_limit_stretch(
    material: &crate::config::material::MembraneMaterial,
) -> Option<Real> {
    use crate::config::material::MembraneMaterial as M;
    let base = |l: Real| 1.0 / l - l.powi(-7);
    let p: Box<dyn Fn(Real) -> Real> = match *material {
        M::NeoHookean => Box::new(base),
        M::MooneyRivlin { c1, c2 } => Box::new(move |l| (c1 + c2 * l * l) * base(l)),
        M::Gent { jm } => Box::new(move |l| {
            let d = 1.0 - (2.0 * l * l + l.powi(-4) - 3.0) / jm;
            if d > 0.0 {
                base(l) / d
            } else {
                Real::INFINITY
            }
        }),
        _ => return None,
    };
    let dl = 1e-3;
    let mut l = 1.0 + dl;
    while l < 50.0 {
        let (a, b, c) = (p(l - dl), p(l), p(l + dl));
        if !c.is_finite() {
            return None;
        }
        if b > a && b >= c {
            // Golden section on [l − dl, l + dl].
            let g = (5f64.sqrt() - 1.0) / 2.0;
            let (mut lo, mut hi) = (l - dl, l + dl);
            while hi - lo > 1e-10 {
                let (m1, m2) = (hi - g * (hi - lo), lo + g * (hi - lo));
                if p(m1) < p(m2) {
                    lo = m1;
                } else {
                    hi = m2;
                }
            }
            return Some(0.5 * (lo + hi));
        }
        l += dl;
    }
    None
}

#[cfg(test)]
mod limit_tests {
    use super::thin_sphere_limit_stretch;
    use crate::config::material::MembraneMaterial as M;

    #[test]
    fn thin_sphere_limit_stretches_match_their_closed_forms() {
        let nh = thin_sphere_limit_stretch(&M::NeoHookean).unwrap();
        assert!((nh - 7f64.powf(1.0 / 6.0)).abs() < 1e-8, "{nh}");
        // c₂/c₁ = 0.1: maximum at 1.47607 (and a minimum at 3.14262).
        let mr = thin_sphere_limit_stretch(&M::MooneyRivlin { c1: 1.0, c2: 0.1 }).unwrap();
        assert!((mr - 1.476070).abs() < 1e-6, "{mr}");
        // Gent with J_m = 30: maximum near 1.445.
        let g = thin_sphere_limit_stretch(&M::Gent { jm: 30.0 }).unwrap();
        assert!((g - 1.445).abs() < 2e-3, "{g}");
        assert_eq!(thin_sphere_limit_stretch(&M::Koiter), None);
    }
}
