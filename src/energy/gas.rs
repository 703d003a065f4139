//! An enclosed gas (seed 002 §5): a closed surface holding a fixed amount of ideal gas, a
//! prescribed pressure, or a prescribed volume, as one global term with an exact gradient and
//! Hessian.
//!
//! **Volume.** `V(x) = Σ_f x₀·(x₁ × x₂)/6` over every face, the exact volume of the polyhedron
//! (the seed's Eq. 13 is the same sum written with face areas and normals); it is invariant under
//! rigid motions when the surface is closed ([`crate::mesh::closed`]).
//!
//! **Energy of each control**, `s` the dial, `p_e` the external pressure (Pa):
//! * *amount* (seed 002 Eq. 12–14): a gas with `pV = n` (isothermal, `n` in J = Pa·m³, the
//!   `nRT` of the seed) or `pV^γ = n V_ref^(γ−1)` (adiabatic: the gas has pressure `n/V_ref` at
//!   the reference volume), `n(s) = n₀ + s (n₁ − n₀)` from `n₀ = p_e V_ref` (the gas at the outside
//!   pressure, nothing inflated) to `n₁` = `gas.amount`:
//!   `E = −n ln(V/V_ref) + p_e V` (isothermal), `E = p V/(γ − 1) + p_e V` (adiabatic), so that
//!   `∂E/∂V = −(p − p_e)` with `p(V)` the gas law;
//! * *pressure*: `E = −s p₁ (V − V_ref)`, `p₁` the gauge pressure (a follower load);
//! * *volume*: the constraint `V = V*(s) = V_ref + s (V₁ − V_ref)` with the gauge pressure as its
//!   multiplier `λ`, enforced by an augmented Lagrangian
//!   `E = −λ (V − V*) + ρ/2 (V − V*)²`; after each converged solve the multiplier takes
//!   Newton's step on `V(λ) = V*`, `λ ← λ − (V − V*)/(dV/dλ)`, `dV/dλ = ∇Vᵀ H⁻¹ ∇V` from the
//!   solve's factor, and the solve repeats until `|V − V*| ≤ 10⁻¹⁰ V*`
//!   ([`crate::energy::term::Multiplier`]). The penalty `ρ = 100 E h/(R V_ref)` (largest E h,
//!   `R` the radius of the sphere of volume V_ref) is 150 (1 − ν) times the stiffness
//!   `dp/dV = 2 E h/(3 (1 − ν) R V)` of a spherical membrane's volume at rest: even the plain
//!   update `λ ← λ − ρ (V − V*)` would converge by a factor of about that per update, and it
//!   makes the Hessian positive definite past a pressure limit point, where the sparse part alone
//!   has a negative eigenvalue along the breathing mode.
//!
//! **Derivatives.** With `E = G(V)`: `∇E = G'(V) ∇V` and
//! `∇²E = G'(V) ∇²V + G''(V) ∇V ∇Vᵀ`, where `−G'` is the gauge pressure acting on the skin
//! (`p − p_e`, `s p₁` or `λ − ρ (V − V*)`) and `G''` is `p/V` (isothermal), `γ p/V` (adiabatic),
//! 0 (pressure) or `ρ` (volume). The first part is sparse (per face, [`crate::geometry::cone_volume`];
//! zero 3×3 diagonal blocks) and keeps the derivative of the face areas and normals that the
//! seed's Eq. 16 drops; the second is a dense rank-one part, handed to Newton as a
//! [`LowRank`] and solved by Sherman–Morrison on the sparse factor, never densified. The
//! per-face split of `∇²V` depends on the origin, so it is never projected face by face; the
//! Gauss–Newton Hessian keeps only the rank-one part (seed 002 Eq. 16).
//!
//! Units: V in m³, pressures in Pa, E in J, gradient N, Hessian N/m. DOF order per face (9):
//! `x[v0], x[v1], x[v2]`.

use crate::body::Body;
use crate::elements::{assemble_elements, ElementMap, Want};
use crate::energy::term::{
    LowRank, LowRankPart, Multiplier, Predictor, Reports, Stateful, Stencil, Term,
};
use crate::energy::HessianProjection;
use crate::energy::Potential;
use crate::math::{Real, Vec3};
use crate::mesh::MeshError;
use crate::settings::{GasControl, GasProcess};

/// The gas term.
pub struct Gas {
    control: GasControl,
    process: GasProcess,
    /// Heat capacity ratio γ (adiabatic).
    gamma: Real,
    /// External pressure p_e (Pa).
    p_ext: Real,
    /// Enclosed volume of the reference mesh (m³).
    v_ref: Real,
    /// Amount at dial 1 (J), pressure at dial 1 (Pa) or volume at dial 1 (m³).
    target: Real,
    /// Volume control: penalty ρ (Pa/m³).
    rho: Real,
}

/// The gas's state at positions `x` and dial `s`.
#[derive(Clone, Copy, Debug)]
pub struct GasState {
    /// Enclosed volume (m³).
    pub volume: Real,
    /// Gauge pressure acting on the skin, `−G'(V)` (Pa).
    pub gauge: Real,
    /// `G''(V)`, the coefficient of the rank-one part (Pa/m³).
    pub stiffness: Real,
    /// Energy `G(V)` (J).
    pub energy: Real,
}

impl Gas {
    /// The enclosed volume at `x` (m³), summed in face order.
    pub fn volume(body: &Body, x: &[Vec3]) -> Real {
        crate::mesh::closed::enclosed_volume(x, &body.mesh.faces)
    }

    /// The amount at dial `s` (amount control, J).
    fn amount(&self, s: Real) -> Real {
        let n0 = self.p_ext * self.v_ref;
        n0 + s * (self.target - n0)
    }

    /// The target volume at dial `s` (volume control, m³).
    fn volume_target(&self, s: Real) -> Real {
        self.v_ref + s * (self.target - self.v_ref)
    }

    /// The state at volume `v`, dial `s` and, under volume control, multiplier `lambda` (Pa).
    pub fn state_at(&self, v: Real, s: Real, lambda: Real) -> GasState {
        match self.control {
            GasControl::Amount => {
                let n = self.amount(s);
                let (p, energy, k) = match self.process {
                    GasProcess::Isothermal => {
                        let p = n / v;
                        (p, -n * (v / self.v_ref).ln(), p / v)
                    }
                    GasProcess::Adiabatic => {
                        let g = self.gamma;
                        let p = n / self.v_ref * (self.v_ref / v).powf(g);
                        (p, p * v / (g - 1.0), g * p / v)
                    }
                };
                GasState {
                    volume: v,
                    gauge: p - self.p_ext,
                    stiffness: k,
                    energy: energy + self.p_ext * v,
                }
            }
            GasControl::Pressure => {
                let p = s * self.target;
                GasState {
                    volume: v,
                    gauge: p,
                    stiffness: 0.0,
                    energy: -p * (v - self.v_ref),
                }
            }
            GasControl::Volume => {
                let c = v - self.volume_target(s);
                GasState {
                    volume: v,
                    gauge: lambda - self.rho * c,
                    stiffness: self.rho,
                    energy: -lambda * c + 0.5 * self.rho * c * c,
                }
            }
            GasControl::None => GasState {
                volume: v,
                gauge: 0.0,
                stiffness: 0.0,
                energy: 0.0,
            },
        }
    }

    /// The state at positions `x` under potential `pot`.
    pub fn state(&self, pot: &Potential, x: &[Vec3]) -> GasState {
        self.state_at(Self::volume(pot.body, x), pot.dial, Self::multiplier(pot))
    }

    /// Volume control: the multiplier λ (gauge pressure, Pa) that `pot` is evaluated with (the
    /// gas's [`Stateful`] state).
    pub fn multiplier(pot: &Potential) -> Real {
        pot.term_state("gas").first().copied().unwrap_or(0.0)
    }

    /// The penalty ρ of volume control (Pa/m³).
    pub fn penalty(&self) -> Real {
        self.rho
    }

    /// `∇V` over the DOFs the solver moves (zero on the non-vertex DOFs, fixed vertices and
    /// pinned DOFs).
    fn volume_gradient(pot: &Potential, x: &[Vec3]) -> Vec<Real> {
        let mut g = vec![Vec3::zeros(); x.len()];
        crate::mesh::closed::add_enclosed_volume_gradient(x, &pot.body.mesh.faces, &mut g);
        let mut u = vec![0.0; pot.pattern.n];
        for (v, gv) in g.iter().enumerate() {
            u[3 * v..3 * v + 3].copy_from_slice(gv.as_slice());
        }
        pot.mask_fixed(&mut u);
        u
    }
}

impl Term for Gas {
    fn name(&self) -> &'static str {
        "gas"
    }

    fn stateful(&self) -> Option<&dyn Stateful> {
        Some(self)
    }

    fn stencil(&self, body: &Body) -> Stencil {
        Stencil::faces(&body.mesh, 0..body.num_faces())
    }

    fn eval(
        &self,
        pot: &Potential,
        map: &ElementMap,
        x: &[Vec3],
        _phi: &[Real],
        want: Want,
        projection: HessianProjection,
        grad: &mut [Real],
        values: &mut [Real],
    ) -> Real {
        let st = self.state(pot, x);
        if want == Want::Energy {
            return st.energy;
        }
        // The sparse part −(gauge) ∇²V (dropped by Gauss–Newton, as in the seed's Eq. 16);
        // never projected face by face.
        let w = -st.gauge;
        let keep_h = projection != HessianProjection::GaussNewton;
        let faces = &pot.body.mesh.faces;
        assemble_elements::<9, 3, _>(
            map,
            |f, _, g, h| {
                let xs = faces[f].map(|v| x[v]);
                let h = if keep_h {
                    h
                } else {
                    if let Some(h) = h {
                        h.fill(0.0);
                    }
                    None
                };
                crate::geometry::cone_volume(&xs, w, g, h);
                0.0
            },
            pot.node_fixed,
            HessianProjection::None,
            want,
            grad,
            values,
            &pot.pattern.col_ptr,
        );
        st.energy
    }

    /// Only a prescribed volume has a multiplier to update.
    fn updates(&self) -> Option<&dyn Multiplier> {
        (self.control == GasControl::Volume).then_some(self)
    }

    /// Only a controlled gas predicts (amount, pressure or volume control).
    fn predictor(&self) -> Option<&dyn Predictor> {
        (self.control != GasControl::None).then_some(self)
    }

    fn low_rank(&self) -> Option<&dyn LowRankPart> {
        Some(self)
    }

    fn reports(&self) -> Option<&dyn Reports> {
        Some(self)
    }
}

impl Reports for Gas {
    fn observables(&self, pot: &Potential, x: &[Vec3], _phi: &[Real]) -> Vec<(String, Real)> {
        let st = self.state(pot, x);
        vec![
            ("gas_pressure".into(), st.gauge),
            ("gas_volume".into(), st.volume),
        ]
    }

    fn face_fields(&self, pot: &Potential, x: &[Vec3], _phi: &[Real]) -> Vec<(String, Vec<Real>)> {
        let st = self.state(pot, x);
        vec![("pressure".into(), vec![st.gauge; pot.body.num_faces()])]
    }
}

impl Stateful for Gas {
    /// The multiplier λ (Pa) of volume control, which warm-starts the next solve; 0 at the
    /// start.
    fn initial_state(&self) -> Vec<Real> {
        vec![0.0]
    }
}

impl LowRankPart for Gas {
    fn low_rank(&self, pot: &Potential, x: &[Vec3], _phi: &[Real], out: &mut Vec<LowRank>) {
        let st = self.state(pot, x);
        if st.stiffness != 0.0 {
            out.push(LowRank {
                c: st.stiffness,
                u: Self::volume_gradient(pot, x),
            });
        }
    }
}

impl Predictor for Gas {
    /// Euler's predictor along the equilibrium path: the load's change moves the equilibrium by
    /// `dx = H⁻¹∇V · α`, with `α = Δn/V` (amount: the pressure's change at fixed volume), `Δp`
    /// (pressure) or `ΔV*/s`, `s = ∇Vᵀ H⁻¹ ∇V` (volume, whose multiplier moves by
    /// `ΔV* (1/s − ρ)`: the penalty carries the rest).
    fn predict(
        &self,
        pot: &Potential,
        from: Real,
        x: &mut [Vec3],
        _phi: &[Real],
        own: &mut [Real],
        solve: &mut dyn FnMut(&mut [Real]) -> bool,
    ) {
        let ds = pot.dial - from;
        if ds == 0.0 || self.control == GasControl::None {
            return;
        }
        let u = Self::volume_gradient(pot, x);
        let mut y = u.clone();
        if !solve(&mut y) {
            return;
        }
        let s: Real = u.iter().zip(&y).map(|(a, b)| a * b).sum();
        if !(s.is_finite() && s > 0.0) {
            return;
        }
        let v = Self::volume(pot.body, x);
        let alpha = match self.control {
            GasControl::Amount => (self.amount(pot.dial) - self.amount(from)) / v,
            GasControl::Pressure => ds * self.target,
            GasControl::Volume => {
                let dv = self.volume_target(pot.dial) - self.volume_target(from);
                own[0] += dv * (1.0 / s - self.rho);
                dv / s
            }
            GasControl::None => 0.0,
        };
        if !alpha.is_finite() {
            return;
        }
        for (i, p) in x.iter_mut().enumerate() {
            *p += Vec3::new(y[3 * i], y[3 * i + 1], y[3 * i + 2]) * alpha;
        }
    }
}

impl Multiplier for Gas {
    /// Volume control: while the volume is off by more than 10⁻¹⁰ V*, Newton's update of the
    /// multiplier, `λ ← λ − (V − V*)/s` with `s = ∇Vᵀ H⁻¹ ∇V = dV/dλ` at the equilibrium
    /// (H the whole Hessian, penalty included, so `0 < s < 1/ρ`); without a factor, the
    /// augmented-Lagrangian update `λ ← λ − ρ (V − V*)`.
    fn update(
        &self,
        pot: &Potential,
        x: &[Vec3],
        _phi: &[Real],
        own: &mut [Real],
        sensitivity: &mut dyn FnMut(&[Real]) -> Option<Real>,
    ) -> bool {
        if self.control != GasControl::Volume {
            return false;
        }
        let v = Self::volume(pot.body, x);
        let target = self.volume_target(pot.dial);
        let c = v - target;
        if c.abs() <= 1e-10 * target.abs() {
            return false;
        }
        let u = Self::volume_gradient(pot, x);
        let s = sensitivity(&u)
            .filter(|s| s.is_finite() && *s > 0.0 && *s <= 1.0 / self.rho)
            .unwrap_or(1.0 / self.rho);
        own[0] -= c / s;
        true
    }
}

/// The gas term of a scene (`None` unless `gas.control` is set). The mesh must be a closed,
/// consistently oriented 2-manifold with outward normals (errors name the first open edge, or
/// the fix for an inward mesh), and volume control must ask for a positive volume.
pub fn term(body: &Body, g: &crate::config::gas::Gas) -> Result<Option<Box<dyn Term>>, MeshError> {
    if g.control == GasControl::None {
        return Ok(None);
    }
    let v_ref = crate::mesh::closed::check_closed_outward(&body.mesh, &body.topo)?;
    let target = match g.control {
        GasControl::Amount => g.amount,
        GasControl::Pressure => g.pressure,
        _ => g.volume,
    };
    // Penalty of volume control: 100 E h / (R V_ref) (module doc).
    let eh = body
        .young
        .iter()
        .zip(&body.thickness)
        .map(|(e, h)| e * h)
        .fold(0.0, Real::max);
    let radius = (3.0 * v_ref / (4.0 * std::f64::consts::PI)).cbrt();
    let rho = 100.0 * eh / (radius * v_ref);
    Ok(Some(Box::new(Gas {
        control: g.control,
        process: g.process,
        gamma: g.gamma,
        p_ext: g.external_pressure,
        v_ref,
        target,
        rho,
    })))
}
