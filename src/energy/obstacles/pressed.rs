//! A force-controlled obstacle (`force` in its `[[obstacles]]` table): a rigid shape pushed
//! along the unit direction `ê` of a prescribed force, whose offset `q` (m) along `ê` is a
//! global DOF of the solve ([`crate::energy::term::GlobalDof`]), so that where it comes to rest
//! is part of the equilibrium.
//!
//! **Energy.** With `f(y) = k A_v ψ(h_v/2 − d(y))` the contact of vertex `v` against the
//! shape at rest (the fixed obstacles' law, [`super`]), the obstacle offset by `q ê` gives
//!
//! `E = Σ_v f(x_v − q ê) − s F q + [M/(2Δt²) (q − q̂)²]`,
//!
//! `s` the dial clamped to [0, 1], `F` the force's magnitude (N), the last part the obstacle's
//! inertia in dynamics (`M` its mass, kg; `q̂ = q_n + Δt q̇_n`). Per vertex element, with
//! `g = ∇f = −k A ψ′(p) ∇d` and `K = ∇²f = k A (ψ″ ∇d∇dᵀ − ψ′ ∇²d)`:
//!
//! `∂E/∂x_v = g`, `∂E/∂q = −ê·g`, `∂²E/∂x_v² = K`, `∂²E/∂x_v∂q = −K ê`, `∂²E/∂q² = êᵀ K ê`;
//!
//! the force's element adds `−sF + M (q − q̂)/Δt²` and `M/Δt²`. At equilibrium `∂E/∂q = 0`:
//! the sheet's push on the obstacle along `ê` equals `s F`. Newton moves `q` by at most half the
//! sheet's mean thickness per iteration (out of contact nothing holds it back in statics).
//!
//! Units: m, N, J, kg. DOF order per element: `x_v` (3), then `q` (1); the force's element has
//! `q` only (its vertex slot is absent).

use super::{Distance, Obstacles, Solid};
use crate::body::Body;
use crate::elements::{assemble_elements, ElementMap, Want};
use crate::energy::projection::HessianProjection;
use crate::energy::term::{GlobalDof, GlobalDofs, Reports, Stencil, Term};
use crate::energy::Potential;
use crate::math::{Mat3, Real, SMat, SVec, Vec3};
use crate::mesh::topology::NONE;

/// One force-controlled obstacle.
pub struct Pressed {
    /// Its index among the `[[obstacles]]` (for the log columns).
    pub index: usize,
    /// Its shape at offset 0.
    pub body: Solid,
    /// Unit direction of the force.
    pub direction: Vec3,
    /// Magnitude of the force at dial 1 (N).
    pub force: Real,
    /// Mass (kg; 0 when none is given: statics).
    pub mass: Real,
    /// Penalty stiffness k (Pa/m).
    pub stiffness: Real,
    /// Smoothing length δ (m).
    pub smoothing: Real,
    /// Per-vertex areas and half thicknesses (shared with the fixed obstacles' data).
    pub sheet: Obstacles,
    /// Largest Newton step of the offset (m).
    pub max_step: Real,
    /// Its global node (set by [`GlobalDofs::bind`]).
    pub node: usize,
}

impl Pressed {
    /// `(E, g, K)` of vertex `v` at `x` against the obstacle at offset `q`; `None` out of
    /// contact.
    #[inline]
    fn contact(&self, v: usize, x: &Vec3, q: Real) -> Option<(Real, Vec3, Mat3)> {
        let (d, n, hd) = self.body.distance(&(x - self.direction * q));
        let p = self.sheet.half_thickness[v] - d;
        if p <= 0.0 {
            return None;
        }
        Some(super::penalty_term(
            self.stiffness * self.sheet.area[v],
            self.smoothing,
            p,
            &n,
            &hd,
        ))
    }

    /// Element `e`'s energy, gradient and Hessian in the module's DOF order.
    #[allow(clippy::too_many_arguments)]
    fn element(
        &self,
        pot: &Potential,
        nodes: &[usize],
        x: &[Vec3],
        phi: &[Real],
        grad: Option<&mut SVec<4>>,
        hess: Option<&mut SMat<4, 4>>,
    ) -> Real {
        let k = self.node - x.len();
        let q = phi[k];
        let mut g = SVec::<4>::zeros();
        let mut h = SMat::<4, 4>::zeros();
        let e = if nodes[0] == NONE {
            let (e, dq, ddq) = push(pot, k, q, self.force, self.mass);
            g[3] = dq;
            h[(3, 3)] = ddq;
            e
        } else {
            let v = nodes[0];
            match self.contact(v, &x[v], q) {
                None => 0.0,
                Some((e, gv, kv)) => {
                    let u = self.direction;
                    let ku = kv * u;
                    g.fixed_rows_mut::<3>(0).copy_from(&gv);
                    g[3] = -u.dot(&gv);
                    h.fixed_view_mut::<3, 3>(0, 0).copy_from(&kv);
                    h.fixed_view_mut::<3, 1>(0, 3).copy_from(&(-ku));
                    h.fixed_view_mut::<1, 3>(3, 0).copy_from(&(-ku).transpose());
                    h[(3, 3)] = u.dot(&ku);
                    e
                }
            }
        };
        if let Some(out) = grad {
            out.copy_from(&g);
        }
        if let Some(out) = hess {
            out.copy_from(&h);
        }
        e
    }
}

/// The force's element of a force-controlled obstacle whose offset `q` (m) is scalar DOF `k`:
/// `E = −s F q + M/(2Δt²) (q − q̂)²` (module doc; the inertia only in dynamics and with a mass),
/// with its derivatives `(E, ∂E/∂q, ∂²E/∂q²)` (J, N, N/m).
pub(crate) fn push(
    pot: &Potential,
    k: usize,
    q: Real,
    force: Real,
    mass: Real,
) -> (Real, Real, Real) {
    let s = pot.dial.clamp(0.0, 1.0);
    let (mut e, mut g, mut h) = (-s * force * q, -s * force, 0.0);
    if let (Some(inr), true) = (pot.inertia.as_ref(), mass > 0.0) {
        if let Some(&qhat) = inr.dofs_hat.get(k) {
            let m = mass * inr.inv_dt2;
            e += 0.5 * m * (q - qhat) * (q - qhat);
            g += m * (q - qhat);
            h = m;
        }
    }
    (e, g, h)
}

impl GlobalDofs for Pressed {
    fn dofs(&self) -> Vec<GlobalDof> {
        vec![GlobalDof {
            name: format!("obstacle{}_offset", self.index),
            length: 1.0,
            max_step: self.max_step,
            mass: self.mass,
        }]
    }

    fn bind(&mut self, first_node: usize) {
        self.node = first_node;
    }
}

impl Term for Pressed {
    fn name(&self) -> &'static str {
        "pressed_obstacles"
    }

    fn global_dofs(&mut self) -> Option<&mut dyn GlobalDofs> {
        Some(self)
    }

    /// One element per vertex that has an area (`[v, q]`), then the force's (`[·, q]`).
    fn stencil(&self, body: &Body) -> Stencil {
        let p = &body.mesh.positions;
        let (mut nodes, mut anchors) = (Vec::new(), Vec::new());
        for (v, &a) in self.sheet.area.iter().enumerate() {
            if a > 0.0 {
                nodes.extend_from_slice(&[v, self.node]);
                anchors.push(p[v]);
            }
        }
        nodes.extend_from_slice(&[NONE, self.node]);
        anchors.push(p.first().copied().unwrap_or_else(Vec3::zeros));
        Stencil {
            slot_dofs: vec![3, 1],
            nodes,
            anchors,
        }
    }

    fn eval(
        &self,
        pot: &Potential,
        map: &ElementMap,
        x: &[Vec3],
        phi: &[Real],
        want: Want,
        projection: HessianProjection,
        grad: &mut [Real],
        values: &mut [Real],
    ) -> Real {
        assemble_elements::<4, 2, _>(
            map,
            |_, nodes, g, h| self.element(pot, nodes, x, phi, g, h),
            pot.node_fixed,
            projection,
            want,
            grad,
            values,
            &pot.pattern.col_ptr,
        )
    }

    fn reports(&self) -> Option<&dyn Reports> {
        Some(self)
    }
}

impl Reports for Pressed {
    /// The force on the sheet (N), the smallest gap (m) and the offset `q` (m).
    fn observables(&self, _pot: &Potential, x: &[Vec3], phi: &[Real]) -> Vec<(String, Real)> {
        let q = phi[self.node - x.len()];
        let (mut f, mut gap) = (Vec3::zeros(), Real::INFINITY);
        for (v, xv) in x.iter().enumerate() {
            if self.sheet.area[v] == 0.0 {
                continue;
            }
            let (d, _, _) = self.body.distance(&(xv - self.direction * q));
            gap = gap.min(d - self.sheet.half_thickness[v]);
            if let Some((_, g, _)) = self.contact(v, xv, q) {
                f -= g;
            }
        }
        let i = self.index;
        let mut out: Vec<(String, Real)> = ["x", "y", "z"]
            .iter()
            .zip(f.iter())
            .map(|(k, c)| (format!("obstacle{i}_force_{k}"), *c))
            .collect();
        out.push((format!("obstacle{i}_gap"), gap));
        out.push((format!("obstacle{i}_offset"), q));
        out
    }
}
