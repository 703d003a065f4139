//! Ground contact with Coulomb friction, as terms of the incremental potential (seed 000 §3:
//! "F_ext encapsulates contact forces"; MorphoShell's glass slides, seed 001, are the stiff-spring
//! ancestor).
//!
//! **Normal contact: smoothed penalty.** The ground is the plane through `P` with unit normal
//! `n` (pointing to the sheet's side). Vertex `v`'s gap is `g_v = n·(x_v − P) − h_v/2` (the
//! sheet's surface, not its mid-surface, touches the ground; `h_v` is the mean thickness of the
//! faces around `v`) and its penetration `p_v = max(0, −g_v)`. The energy is
//!
//! `E_c = Σ_v k A_v ψ(p_v)`, `ψ(p) = p³/(6δ)` for `p ≤ δ`, `p²/2 − δp/2 + δ²/6` beyond,
//!
//! with `A_v` the vertex's reference area (one third of its faces'), `k` the stiffness (Pa/m,
//! contact pressure per unit penetration) and `δ` the smoothing length (m). ψ is C² (ψ, ψ′ and
//! ψ″ = min(p/δ, 1) are continuous), so Newton sees a smooth, convex term. Under a contact
//! pressure σ the penetration is `√(2δσ/k)` while σ < kδ/2, and `σ/k + δ/2` beyond: the
//! documented tolerance. Defaults: `k = E/h`, the pressure that compresses the sheet through its
//! whole thickness by a strain of one (so a penetration p squeezes the sheet by the strain p/h,
//! as a rigid ground would), and `δ = h/100`.
//!
//! **Friction: lagged, smoothed Coulomb (the incremental-potential form of Li et al. 2020,
//! "Incremental Potential Contact", §5).** Over a step from `x⁰`, vertex `v` slides by
//! `u_v = T(x_v − x⁰_v)`, `T = I − n nᵀ`. With the normal force `λ_v` held at its value from the
//! previous friction iterate ("lagged"), the dissipation potential
//!
//! `D = Σ_v μ λ_v f₀(‖u_v‖)`, `f₀(s) = −s³/(3ε²) + s²/ε + ε/3` for `s < ε`, `s` beyond,
//!
//! has gradient `μ λ_v f₁(s) û` with `f₁ = f₀′ = min(2s/ε − s²/ε², 1)`: exactly Coulomb's μλ
//! opposite the slip once the slip over the step exceeds `ε = ε_v Δt` (ε_v the slip speed), and a
//! stiff spring (sticking that creeps at most at ε_v) below. Its Hessian
//! `μλ (f₁′ ûûᵀ + f₁/s (T − ûûᵀ))` is positive semi-definite. The integrator re-solves a step
//! with the updated `λ` until the normal forces agree (see [`crate::integrate`]). Friction needs
//! a step (a slip over a time); static solves treat the ground as frictionless.
//!
//! Units: positions m, k Pa/m, δ and ε m, λ N, energies J. DOF order: the 3 coordinates of each
//! vertex (the ground acts on vertices only; edge DOFs are untouched).

pub mod broad;
pub mod ccd;
pub mod distance;

use crate::math::{Real, Vec3};

/// The ground plane and its contact law.
#[derive(Clone, Debug)]
pub struct Ground {
    /// A point on the plane (m).
    pub point: Vec3,
    /// Unit normal toward the sheet.
    pub normal: Vec3,
    /// Penalty stiffness k (Pa/m).
    pub stiffness: Real,
    /// Smoothing length δ (m).
    pub smoothing: Real,
    /// Coulomb coefficient μ.
    pub friction: Real,
    /// Slip speed ε_v (m/s).
    pub slip_speed: Real,
    /// Reference area per vertex A_v (m²).
    pub area: Vec<Real>,
    /// Half thickness per vertex h_v/2 (m).
    pub half_thickness: Vec<Real>,
}

/// `(ψ, ψ′, ψ″)` of the smoothed penalty at penetration `p ≥ 0` (module doc).
#[inline]
pub fn penalty(p: Real, delta: Real) -> (Real, Real, Real) {
    if p <= 0.0 {
        (0.0, 0.0, 0.0)
    } else if p <= delta {
        (p * p * p / (6.0 * delta), p * p / (2.0 * delta), p / delta)
    } else {
        (
            p * p / 2.0 - delta * p / 2.0 + delta * delta / 6.0,
            p - delta / 2.0,
            1.0,
        )
    }
}

/// `(b, b′, b″)` of IPC's log barrier at gap `g` with activation distance `ĝ` (Li et al. 2020,
/// "Incremental Potential Contact", eq. 6, here on the distance rather than its square):
///
/// `b(g) = −(g − ĝ)² ln(g/ĝ)` for `0 < g < ĝ`, 0 beyond, `+∞` at `g ≤ 0`,
///
/// `b′ = −2(g − ĝ) ln(g/ĝ) − (g − ĝ)²/g` (≤ 0), `b″ = −2 ln(g/ĝ) − 4(g − ĝ)/g + (g − ĝ)²/g²`
/// (> 0). `b` and `b′` vanish at `ĝ` and `b″` is continuous there only up to its value `0`
/// from the left (C² in the energy: `b″(ĝ⁻) = 0`). Units: `g`, `ĝ` m, `b` m², `b′` m, `b″`
/// dimensionless; multiplied by a stiffness (Pa/m) and an area (m²) it is an energy (J).
#[inline]
pub fn barrier(g: Real, g_hat: Real) -> (Real, Real, Real) {
    if g >= g_hat {
        (0.0, 0.0, 0.0)
    } else if g <= 0.0 {
        (Real::INFINITY, -Real::INFINITY, Real::INFINITY)
    } else {
        let (u, l) = (g - g_hat, (g / g_hat).ln());
        (
            -u * u * l,
            -2.0 * u * l - u * u / g,
            -2.0 * l - 4.0 * u / g + u * u / (g * g),
        )
    }
}

/// `(f₀, f₁ = f₀′, f₁′)` of the smoothed friction at slip `s ≥ 0` over the step (module doc).
#[inline]
pub fn friction_profile(s: Real, eps: Real) -> (Real, Real, Real) {
    if s >= eps {
        (s, 1.0, 0.0)
    } else {
        let r = s / eps;
        (
            eps * (-r * r * r / 3.0 + r * r + 1.0 / 3.0),
            2.0 * r - r * r,
            (2.0 - 2.0 * r) / eps,
        )
    }
}

impl Ground {
    /// Penetration of vertex `v` at `x` (m, ≥ 0 in contact).
    #[inline]
    pub fn penetration(&self, v: usize, x: &Vec3) -> Real {
        (self.half_thickness[v] - self.normal.dot(&(x - self.point))).max(0.0)
    }

    /// Normal contact force on every vertex, `λ_v = k A_v ψ′(p_v)` (N).
    pub fn normal_forces(&self, x: &[Vec3]) -> Vec<Real> {
        x.iter()
            .enumerate()
            .map(|(v, xv)| {
                self.stiffness * self.area[v] * penalty(self.penetration(v, xv), self.smoothing).1
            })
            .collect()
    }

    /// Normal-contact energy of vertex `v`, its gradient and its 3×3 Hessian block (module
    /// doc); `None` out of contact.
    #[inline]
    pub fn normal_term(&self, v: usize, x: &Vec3) -> Option<(Real, Vec3, [[Real; 3]; 3])> {
        let p = self.penetration(v, x);
        if p <= 0.0 {
            return None;
        }
        let (psi, dpsi, ddpsi) = penalty(p, self.smoothing);
        let ka = self.stiffness * self.area[v];
        let n = self.normal;
        let mut h = [[0.0; 3]; 3];
        for (a, row) in h.iter_mut().enumerate() {
            for (b, e) in row.iter_mut().enumerate() {
                *e = ka * ddpsi * n[a] * n[b];
            }
        }
        Some((ka * psi, -n * (ka * dpsi), h))
    }

    /// Friction potential of a vertex with lagged normal force `lambda` (N) that started the
    /// step at `x0`, slip smoothing `eps` (m): energy, gradient and 3×3 Hessian block.
    #[inline]
    pub fn friction_term(
        &self,
        lambda: Real,
        x: &Vec3,
        x0: &Vec3,
        eps: Real,
    ) -> (Real, Vec3, [[Real; 3]; 3]) {
        friction_potential(self.friction * lambda, &self.normal, &(x - x0), eps)
    }
}

/// The smoothed Coulomb dissipation `w f₀(‖u‖)` of a vertex moved by `d` over the step across a
/// surface of unit normal `n`, `u = (I − nnᵀ) d` its slip and `w = μ λ` (N) the friction bound:
/// energy (J), gradient `w f₁(s)/s u` (N) and the 3×3 Hessian block
/// `w (f₁′ ûûᵀ + f₁/s (T − ûûᵀ))` (N/m, positive semi-definite); module doc for `f₀`, `f₁`.
#[inline]
pub fn friction_potential(w: Real, n: &Vec3, d: &Vec3, eps: Real) -> (Real, Vec3, [[Real; 3]; 3]) {
    let u = d - n * n.dot(d);
    let s = u.norm();
    let (f0, f1, df1) = friction_profile(s, eps);
    // f₁/s → 2/ε as s → 0 (the stiff sticking spring).
    let f1_over_s = if s > 0.0 { f1 / s } else { 2.0 / eps };
    let uhat = if s > 0.0 { u / s } else { Vec3::zeros() };
    let mut h = [[0.0; 3]; 3];
    for (a, row) in h.iter_mut().enumerate() {
        for (b, e) in row.iter_mut().enumerate() {
            let t = Real::from(u8::from(a == b)) - n[a] * n[b];
            let uu = uhat[a] * uhat[b];
            *e = w * (df1 * uu + f1_over_s * (t - uu));
        }
    }
    (w * f0, u * (w * f1_over_s), h)
}
