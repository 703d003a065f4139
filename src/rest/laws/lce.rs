//! The liquid-crystal-elastomer director law: a rest-form law for sheets programmed by a director
//! field (MorphoShell's LCE mode; Warner & Modes, Proc. R. Soc. A 2011).
//!
//! On activation a nematic elastomer contracts by λ along its director `d = (cos θ, sin θ)` (θ
//! measured from the reference x axis) and elongates by `λ^(−ν)` across it (ν the opto-thermal
//! Poisson ratio), so its rest metric in reference Cartesian coordinates is
//!
//! `ā = λ² d dᵀ + λ^(−2ν) d⊥ d⊥ᵀ`,   `d⊥ = (−sin θ, cos θ)`,
//!
//! and `b̄ = 0` (the sheet is activated uniformly through its thickness). The dial moves the
//! stretch, not the metric: `λ(s) = 1 + s (λ_target − 1)`, so every intermediate state is itself
//! an LCE metric (a linear blend of the metrics would not be). Per face, with `T` the face's
//! reference frame ([`crate::rest::reference_frame`]), the barycentric metric is
//! `ā(s) = λ(s)² P + λ(s)^(−2ν) Q` with `P = Tᵀ d dᵀ T`, `Q = Tᵀ d⊥ d⊥ᵀ T` precomputed, which
//! costs one `powf` per face and evaluation.
//!
//! Closed form used in the tests: a disk with a circumferential director (θ = φ + π/2) becomes a
//! cone. Radial lengths scale by `λ^(−ν)`, circles by λ; the cone's half-angle α from its axis
//! has `sin α = λ / λ^(−ν) = λ^(1+ν)`, and the rim's perimeter is `2πλR`.
//!
//! Units: θ in rad, λ and ν dimensionless, `ā` in m² (barycentric).

use super::{TargetLaw, Targets};
use crate::math::{Mat2, Real, Sym2, Vec2};
use crate::mesh::{Mesh, MeshError};
use crate::rest::frame::{pull_back, reference_frame};
use crate::settings::Rest;

/// The law of `rest.target = "lce"`: ā at dial 1 from the director, b̄ = 0, and the director
/// data that dials ā through the stretch.
pub struct Director;

impl TargetLaw for Director {
    fn targets(&self, mesh: &Mesh, rest: &Rest) -> Result<Targets, MeshError> {
        let lce = build(mesh, rest)?;
        Ok(Targets {
            abar: lce.iter().map(|l| l.metric(1.0)).collect(),
            bbar: vec![Sym2::zeros(); lce.len()],
            lce,
        })
    }
}

/// One face's director law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LceFace {
    /// `Tᵀ d dᵀ T` (m²).
    pub p: Sym2,
    /// `Tᵀ d⊥ d⊥ᵀ T` (m²).
    pub q: Sym2,
    /// The target stretch λ along the director.
    pub lambda: Real,
    /// The opto-thermal Poisson ratio ν.
    pub nu: Real,
}

impl LceFace {
    /// The face's law for director angle `theta` (rad), target stretch `lambda` and ratio `nu`,
    /// with reference frame `t`.
    pub fn new(t: &Mat2, theta: Real, lambda: Real, nu: Real) -> LceFace {
        let d = Vec2::new(theta.cos(), theta.sin());
        let dp = Vec2::new(-theta.sin(), theta.cos());
        let outer = |v: Vec2| Sym2::new(v.x * v.x, v.x * v.y, v.y * v.y);
        LceFace {
            p: pull_back(t, &outer(d)),
            q: pull_back(t, &outer(dp)),
            lambda,
            nu,
        }
    }

    /// The barycentric rest metric at dial `s ∈ [0, 1]`: `λ(s)² P + λ(s)^(−2ν) Q`.
    #[inline]
    pub fn metric(&self, s: Real) -> Sym2 {
        let l = 1.0 + s * (self.lambda - 1.0);
        self.p * (l * l) + self.q * l.powf(-2.0 * self.nu)
    }
}

/// The per-face laws of a flat reference mesh: (θ, λ, ν) from the settings' `[rest.lce]` when
/// given (numbers or expressions of x, y at each face's reference centroid), else from the
/// mesh's `abar_info`, which carries (θ, λ, ν) per face in this mode as in MorphoShell. Errors
/// name the face and the source: a missing director, a non-finite value, λ ≤ 0.
pub fn build(mesh: &Mesh, rest: &Rest) -> Result<Vec<LceFace>, MeshError> {
    if !mesh.is_flat_xy() {
        return Err(mesh.invalid(
            "rest.target = \"lce\" gives the director in reference Cartesian (x, y) coordinates, \
             which needs a flat reference mesh in a plane z = const",
        ));
    }
    let nf = mesh.faces.len();
    let values: Vec<[Real; 3]> = match &rest.lce {
        Some(l) => {
            let keys = ["rest.lce.theta", "rest.lce.lambda", "rest.lce.nu"];
            let e = [&l.theta, &l.lambda, &l.nu]
                .iter()
                .zip(keys)
                .map(|(f, k)| f.compile().map_err(|e| mesh.invalid(format!("{k}: {e}"))))
                .collect::<Result<Vec<_>, _>>()?;
            (0..nf)
                .map(|f| {
                    let [a, b, c] = mesh.face_positions(f);
                    let m = (a + b + c) / 3.0;
                    [
                        e[0].eval(m.x, m.y),
                        e[1].eval(m.x, m.y),
                        e[2].eval(m.x, m.y),
                    ]
                })
                .collect()
        }
        None => {
            let af = mesh.face_field("abar_info", 3)?.ok_or_else(|| {
                mesh.invalid(
                    "rest.target = \"lce\" needs the director: the per-face field 'abar_info' \
                     holding (θ, λ, ν) per face, or [rest.lce] theta, lambda, nu in the settings",
                )
            })?;
            (0..nf)
                .map(|f| {
                    let v = af.get(f);
                    [v[0], v[1], v[2]]
                })
                .collect()
        }
    };
    let source = if rest.lce.is_some() {
        "[rest.lce]"
    } else {
        "abar_info (θ, λ, ν)"
    };
    let mut out = Vec::with_capacity(nf);
    for (f, &[theta, lambda, nu]) in values.iter().enumerate() {
        if !(theta.is_finite() && lambda.is_finite() && nu.is_finite()) {
            return Err(mesh.invalid(format!(
                "{source}: face {f} has a value that is not finite: θ = {theta}, λ = {lambda}, \
                 ν = {nu}"
            )));
        }
        if lambda <= 0.0 {
            return Err(mesh.invalid(format!(
                "{source}: face {f} has the stretch λ = {lambda}; it must be positive"
            )));
        }
        // Stretches beyond 1e±6 are no material's (as for every target metric).
        let (lo, hi) = (lambda.min(lambda.powf(-nu)), lambda.max(lambda.powf(-nu)));
        if !(lo >= 1e-6 && hi <= 1e6) {
            return Err(mesh.invalid(format!(
                "{source}: face {f} asks for stretches {lo_h} to {hi_h} (λ = {lambda}, ν = {nu}), \
                 outside 1e-6..1e6",
                lo_h = crate::math::human(lo),
                hi_h = crate::math::human(hi)
            )));
        }
        out.push(LceFace::new(&reference_frame(mesh, f), theta, lambda, nu));
    }
    Ok(out)
}
