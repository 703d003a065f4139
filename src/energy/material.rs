//! Material laws for the shell's in-plane (stretching) and bending strains.
//!
//! ## Plane-stress Lamé parameters
//! A thin shell is in plane stress, so its energy uses the 2D Lamé parameters
//! `α = Eν/(1−ν²)`, `β = E/(2(1+ν))` (DESIGN.md). Seed 000 prints the 3D formula
//! `α = Eν/((1+ν)(1−2ν))`, which is singular at ν = ½ (the value MorphoShell's liquid-crystal
//! runs use) and gives the wrong plate stiffness. With the 2D parameters,
//! `α/2 tr²M + β tr M² = E/(2(1−ν²)) [ν tr²M + (1−ν) tr M²] = E/(2(1−ν²)) Q(M)`, so seed 000's
//! bending term equals `D/2 Q(ā⁻¹(b − b̄))` with `D = Eh³/(12(1−ν²))` and its stretching term is
//! the standard Koiter `Eh/(8(1−ν²)) Q(ā⁻¹(a − ā))`.

use crate::math::{sym_det, Mat3, Real, Sym2};

pub use crate::body::Lame2d;
pub use crate::config::shell::StretchConvention;

/// The St Venant–Kirchhoff quadratic form in `[m11, m12, m22]` coordinates:
/// `‖ā⁻¹M‖²_SV = α/2 tr²(ā⁻¹M) + β tr((ā⁻¹M)²) = mᵀ C m`, with
/// `C = α/2 t tᵀ + β S`, `t = (Ā11, 2Ā12, Ā22)`, `S_pq = tr(Ā E_p Ā E_q)`, `Ā = ā⁻¹` and
/// `E_p` the symmetric basis matrices. Units: Pa / m⁴ (a is in m²).
pub fn sv_matrix(abar: &Sym2, lame: Lame2d) -> Mat3 {
    // Ā = ā⁻¹ = [[p, q], [q, r]] in closed form; a singular ā gives C = 0.
    let det = abar[0] * abar[2] - abar[1] * abar[1];
    if det == 0.0 || !det.is_finite() {
        return Mat3::zeros();
    }
    let (p, q, r) = (abar[2] / det, -abar[1] / det, abar[0] / det);
    // S_pq = tr(Ā E_p Ā E_q) for E_0 = [[1,0],[0,0]], E_1 = [[0,1],[1,0]], E_2 = [[0,0],[0,1]].
    let s = Mat3::new(
        p * p,
        2.0 * p * q,
        q * q,
        2.0 * p * q,
        2.0 * (q * q + p * r),
        2.0 * q * r,
        q * q,
        2.0 * q * r,
        r * r,
    );
    let t = crate::math::SVec::<3>::new(p, 2.0 * q, r);
    t * t.transpose() * (0.5 * lame.alpha) + s * lame.beta
}

/// An energy density of one face as a function of its fundamental forms `a` and `b`
/// (both `[11, 12, 22]`, in the face's barycentric coordinates). Returns the energy (J) and
/// fills the first and second derivatives with respect to `a` and `b`. Stretching and bending
/// are uncoupled (no `∂²/∂a∂b`).
pub trait FaceDensity {
    /// Whether the density depends on `b` at all (lets the kernel skip the bending geometry).
    fn uses_b(&self) -> bool;
    /// Energy and derivatives.
    fn eval(&self, a: &Sym2, b: &Sym2, d: &mut DensityDerivs) -> Real;
    /// Replaces the derivatives of [`FaceDensity::eval`] by those of the Gauss–Newton Hessian:
    /// `haa` and `hbb` positive semi-definite, and `ga_psd` the part of `ga` kept in the term
    /// `Σ_k ga_k ∇²a_k` (positive semi-definite as a 2×2 form). The default keeps `haa` and
    /// `hbb` (positive semi-definite for quadratic wells) and drops that term.
    fn gauss_newton(&self, _a: &Sym2, _b: &Sym2, d: &mut DensityDerivs) {
        d.ga_psd = Sym2::zeros();
    }
    /// The elastic (stretching, bending) energies without damping (J).
    fn elastic_parts(&self, a: &Sym2, b: &Sym2) -> (Real, Real);
    /// Energy and first derivatives only (`ga`, `gb`); the second derivatives may be left
    /// stale. The default evaluates everything.
    #[inline]
    fn eval_gradient(&self, a: &Sym2, b: &Sym2, d: &mut DensityDerivs) -> Real {
        self.eval(a, b, d)
    }
}

/// Derivatives filled by [`FaceDensity::eval`].
#[derive(Clone, Copy, Debug, Default)]
pub struct DensityDerivs {
    /// `∂W/∂a`.
    pub ga: Sym2,
    /// `∂W/∂b`.
    pub gb: Sym2,
    /// `∂²W/∂a²`.
    pub haa: Mat3,
    /// `∂²W/∂b²`.
    pub hbb: Mat3,
    /// Gauss–Newton only: the coefficient of `Σ_k ∇²a_k` kept (see [`FaceDensity::gauss_newton`]).
    pub ga_psd: Sym2,
}

/// The discrete Koiter density of seed 000 §3 (eq. for `E_elastic`), plus optional Kelvin–Voigt
/// damping of the same form:
///
/// `W = ws (a − a*)ᵀ C (a − a*) + wb (b − b*)ᵀ C (b − b*)`
///
/// * elastic: `a* = ā`, `b* = b̄`, `ws = √det ā/2 · h/4 · f`, `wb = √det ā/2 · h³/12`, where `f`
///   is 1 (Koiter) or 4 (MorphoShell's convention) and `C` from [`sv_matrix`];
/// * damping (seed 000 §3 "Viscous Damping"): `a* = a_prev`, `b* = b_prev`, both weights times
///   `η/Δt` (η a retardation time in s).
///
/// Units: J. The `√det ā / 2` is the rest area of the face.
#[derive(Clone, Copy, Debug)]
pub struct KoiterDensity {
    /// The St Venant–Kirchhoff matrix of the rest metric.
    pub c: Mat3,
    /// Up to two quadratic wells in `a`: (weight, target).
    pub stretch: [(Real, Sym2); 2],
    /// Up to two quadratic wells in `b`: (weight, target); the first (elastic) one stiffened
    /// by `stiffen`.
    pub bend: [(Real, Sym2); 2],
    /// Bend stiffening coefficient `s = 1/(A γ μ t)` of the elastic bending well (1/J; 0 = off;
    /// [`crate::energy::stiffening`]).
    pub stiffen: Real,
}

impl KoiterDensity {
    /// Rest-area weights `(ws, wb)` for thickness `h`, rest metric `ā` and stretching factor.
    pub fn weights(abar: &Sym2, h: Real, stretch_factor: Real) -> (Real, Real) {
        let area = 0.5 * sym_det(abar).max(0.0).sqrt();
        (area * h / 4.0 * stretch_factor, area * h * h * h / 12.0)
    }
}

impl FaceDensity for KoiterDensity {
    #[inline]
    fn uses_b(&self) -> bool {
        self.bend[0].0 != 0.0 || self.bend[1].0 != 0.0
    }

    #[inline]
    fn eval(&self, a: &Sym2, b: &Sym2, d: &mut DensityDerivs) -> Real {
        let mut e = 0.0;
        d.ga = Sym2::zeros();
        d.gb = Sym2::zeros();
        let mut ws = 0.0;
        let mut wb = 0.0;
        for (w, t) in &self.stretch {
            if *w != 0.0 {
                let m = a - t;
                let cm = self.c * m;
                e += w * m.dot(&cm);
                d.ga += cm * (2.0 * w);
                ws += w;
            }
        }
        d.hbb = Mat3::zeros();
        for (k, (w, t)) in self.bend.iter().enumerate() {
            if *w != 0.0 {
                let m = b - t;
                let cm = self.c * m;
                let mut g = cm * (2.0 * w);
                if k == 0 && self.stiffen != 0.0 {
                    let mut h = self.c * (2.0 * w);
                    e += crate::energy::stiffening::stiffen(
                        self.stiffen,
                        w * m.dot(&cm),
                        &mut g,
                        Some(&mut h),
                    );
                    d.hbb += h;
                } else {
                    e += w * m.dot(&cm);
                    wb += w;
                }
                d.gb += g;
            }
        }
        d.haa = self.c * (2.0 * ws);
        d.hbb += self.c * (2.0 * wb);
        e
    }

    /// The wells' energies and `ga`, `gb`, without the Hessians (the explicit dynamics' path).
    #[inline]
    fn eval_gradient(&self, a: &Sym2, b: &Sym2, d: &mut DensityDerivs) -> Real {
        let mut e = 0.0;
        d.ga = Sym2::zeros();
        d.gb = Sym2::zeros();
        for (w, t) in &self.stretch {
            if *w != 0.0 {
                let m = a - t;
                let cm = self.c * m;
                e += w * m.dot(&cm);
                d.ga += cm * (2.0 * w);
            }
        }
        for (k, (w, t)) in self.bend.iter().enumerate() {
            if *w != 0.0 {
                let m = b - t;
                let cm = self.c * m;
                let mut g = cm * (2.0 * w);
                let eb = w * m.dot(&cm);
                e += if k == 0 {
                    crate::energy::stiffening::stiffen(self.stiffen, eb, &mut g, None)
                } else {
                    eb
                };
                d.gb += g;
            }
        }
        e
    }

    #[inline]
    fn elastic_parts(&self, a: &Sym2, b: &Sym2) -> (Real, Real) {
        let (ws, ta) = self.stretch[0];
        let (wb, tb) = self.bend[0];
        let (da, db) = (a - ta, b - tb);
        let eb = wb * db.dot(&(self.c * db));
        (ws * da.dot(&(self.c * da)), eb + self.stiffen * eb * eb)
    }
}
