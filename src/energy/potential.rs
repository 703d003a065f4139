//! The potential minimised by one Newton solve:
//!
//! `Φ(x) = E_elastic(x; ā(s), b̄(s)) + E_damp(x; a_prev, b_prev) + Σ_i m_i/(2Δt²)|x_i − x̂_i|²
//!        − Σ_i m_i g·x_i + E_ground(x) + D_friction(x; x_n, λ)`
//!
//! Statics use only the elastic, gravity and (frictionless) ground terms. Dynamics (implicit Euler, seed 000 §3) add
//! inertia with `x̂ = x_n + Δt v_n` (its minimiser satisfies `M(v_{n+1} − v_n)/Δt = F(x_{n+1})`)
//! and the Kelvin–Voigt damping potential. Only the terms a scene enables are assembled.
//!
//! With an edge-DOF bending model, Φ also depends on the edge angles φ (massless: they carry no
//! inertia, so each implicit step sets them quasi-statically, as the bending they describe is a
//! through-thickness rotation whose inertia is O(h²) smaller than the translational one).

use crate::body::Body;
use crate::elements::pattern::Pattern;
use crate::elements::Want;
use crate::energy::material::sv_matrix;
use crate::energy::term::{GlobalDof, LowRank, Term, TermStates};
use crate::energy::{HessianProjection, KoiterDensity};
use crate::math::{Real, Sym2, Vec3};
use rayon::prelude::*;

/// Inertia of an implicit-Euler step.
#[derive(Clone, Copy, Debug)]
pub struct Inertia<'a> {
    /// 1/Δt² (1/s²).
    pub inv_dt2: Real,
    /// Predicted positions x_n + Δt v_n (m).
    pub xhat: &'a [Vec3],
    /// Predicted scalar DOFs q_n + Δt q̇_n (the global DOFs' inertia; empty: at rest).
    pub dofs_hat: &'a [Real],
}

/// Kelvin–Voigt damping of seed 000: the elastic form with targets at the previous step's
/// forms and weights × η/Δt.
#[derive(Clone, Copy, Debug)]
pub struct Damping<'a> {
    /// η/Δt (dimensionless).
    pub eta_over_dt: Real,
    /// Previous step's first fundamental forms.
    pub a_prev: &'a [Sym2],
    /// Previous step's second fundamental forms.
    pub b_prev: &'a [Sym2],
}

/// Friction over one step (dynamics with a frictional ground or obstacle; see
/// [`crate::contact`]).
#[derive(Clone, Copy, Debug)]
pub struct Friction<'a> {
    /// Positions at the start of the step (m).
    pub x_prev: &'a [Vec3],
    /// Dial at the start of the step (a moving obstacle's slip is relative to it).
    pub dial_prev: Real,
    /// Lagged normal force per vertex against the ground (N; empty without a frictional
    /// ground).
    pub normal_force: &'a [Real],
    /// Positions of the friction iterate the obstacles' normal forces and normals are lagged
    /// at (m), ...
    pub x_lag: &'a [Vec3],
    /// ... at this dial.
    pub dial_lag: Real,
    /// Slip smoothing ε = ε_v Δt (m).
    pub eps: Real,
}

/// The potential of one solve: the context every term's kernel receives. A scene makes one
/// with [`Potential::new`] ([`crate::model`]).
#[derive(Clone, Copy)]
pub struct Potential<'a> {
    /// The sheet.
    pub body: &'a Body,
    /// The terms, in assembly order.
    pub terms: &'a [Box<dyn Term>],
    /// The global DOFs the terms declared, in node order after the edge nodes.
    pub globals: &'a [GlobalDof],
    /// True for held DOF nodes ([`crate::model::Scene::node_fixed`]).
    pub node_fixed: &'a [bool],
    /// The Hessian pattern.
    pub pattern: &'a Pattern,
    /// Dial factor s ∈ [0, 1] of the rest forms.
    pub dial: Real,
    /// Inertia (dynamics only).
    pub inertia: Option<Inertia<'a>>,
    /// Damping (dynamics with η > 0 only).
    pub damping: Option<Damping<'a>>,
    /// Gravitational acceleration (m/s²).
    pub gravity: Vec3,
    /// Multiplier on the elastic stretching weight (1 except during the static solver's
    /// membrane continuation).
    pub stretch_scale: Real,
    /// Per-face rest forms `(ā, b̄)` that replace the dialled ones (moisture-driven growth).
    pub rest_override: Option<&'a [(Sym2, Sym2)]>,
    /// Per-face rest thickness over the reference thickness that replaces the dialled one
    /// (a thermal shrink through the thickness).
    pub thickness_override: Option<&'a [Real]>,
    /// Per-face factor on the elastic moduli (softening with temperature or moisture); `None`
    /// keeps the body's.
    pub modulus_override: Option<&'a [Real]>,
    /// Lumped vertex masses (kg): the scene's, or moisture-dependent ones.
    pub mass: &'a [Real],
    /// Friction against the ground and the obstacles (their normal contact terms are on
    /// whenever the scene has them).
    pub friction: Option<Friction<'a>>,
    /// Per-face Koiter densities computed once for a fixed dial (the explicit driver's waiting
    /// phase, where millions of gradient evaluations share one rest state); `None` computes
    /// them per evaluation.
    pub frozen: Option<&'a [KoiterDensity]>,
    /// The explicit driver's fused step ([`crate::elements::OwnedNodes`]): an element term's
    /// gradient hands each part's node sums to it instead of writing the gradient vector
    /// ([`crate::elements::assemble_elements_owned`]). `None` everywhere else.
    pub owned: Option<&'a crate::elements::OwnedNodes<'a>>,
    /// The force scale F of the residual (N): the body's, `max(E h) × mean edge`, or in
    /// statics the applied loads' when smaller ([`Potential::load_scale`]).
    pub force_scale: Real,
    /// How fast the dial moves (1/s): the explicit driver's while it dials, 0 elsewhere (what
    /// moves with the dial then moves at its displacement × this rate).
    pub dial_rate: Real,
    /// The positions at which the elements of the terms whose elements change were gathered
    /// (the driver's solver sets them; empty: the positions evaluated): a contact term tells
    /// there which pairs it gathered.
    pub taken_at: &'a [Vec3],
    /// The scalar DOFs at the same state as [`Potential::taken_at`] (a force-controlled mesh
    /// obstacle's offset places its vertices there).
    pub taken_dofs: &'a [Real],
    /// The stateful terms' states the potential is evaluated with ([`crate::solve::State::terms`]): the
    /// scene's initial states unless a driver sets its own.
    pub states: &'a TermStates,
}

impl<'a> Potential<'a> {
    /// The state of the stateful term named `name` ([`crate::energy::term::Stateful`]).
    #[inline]
    pub fn term_state(&self, name: &str) -> &'a [Real] {
        self.states.get(name)
    }

    /// The rest forms `(ā, b̄)` of face `f` at this potential's dial (or override).
    #[inline]
    pub fn rest_forms(&self, f: usize) -> (Sym2, Sym2) {
        match self.rest_override {
            Some(r) => r[f],
            None => self.body.rest.at(f, self.dial),
        }
    }

    /// The rest thickness of face `f` at this potential's dial (m): the reference thickness,
    /// scaled by a growth law that grows it ([`crate::rest::RestForms::thickness_ratio`]).
    #[inline(always)]
    pub fn thickness(&self, f: usize) -> Real {
        let sc = self.body;
        if let Some(t) = self.thickness_override {
            return sc.thickness[f] * t[f];
        }
        match sc.grown_thickness.get(f) {
            None => sc.thickness[f],
            Some(&r) => sc.thickness[f] * sc.rest.thickness_ratio(r, self.dial),
        }
    }

    /// The factor on face `f`'s elastic moduli: 1, or the softening's ([`Self::modulus_override`]).
    #[inline(always)]
    pub fn modulus(&self, f: usize) -> Real {
        self.modulus_override.map_or(1.0, |m| m[f])
    }

    /// Face `f`'s plane-stress Lamé parameters, softened by [`Self::modulus`].
    #[inline(always)]
    pub fn lame(&self, f: usize) -> crate::body::Lame2d {
        let l = self.body.lame[f];
        match self.modulus_override {
            None => l,
            Some(m) => crate::body::Lame2d {
                alpha: l.alpha * m[f],
                beta: l.beta * m[f],
            },
        }
    }

    /// Koiter elastic (+ damping) density of face `f`.
    #[inline(always)]
    pub fn density(&self, f: usize) -> KoiterDensity {
        if let Some(d) = self.frozen {
            return d[f];
        }
        let sc = self.body;
        let (abar, bbar) = self.rest_forms(f);
        let (ws, wb) = KoiterDensity::weights(&abar, self.thickness(f), sc.stretch_factor);
        let ws = ws * self.stretch_scale;
        // A pure membrane has no bending energy (b ≡ 0, whatever b̄ the mesh's shape gives).
        let wb = if sc.has_bending { wb } else { 0.0 };
        let mut d = KoiterDensity {
            c: sv_matrix(&abar, self.lame(f)),
            stretch: [(ws, abar), (0.0, Sym2::zeros())],
            bend: [(wb, bbar), (0.0, Sym2::zeros())],
            stiffen: crate::energy::stiffening::coefficient(
                sc.bend_stiffening,
                0.5 * crate::math::sym_det(&abar).max(0.0).sqrt(),
                self.lame(f).beta,
                self.thickness(f),
            ),
        };
        if let Some(dm) = &self.damping {
            d.stretch[1] = (ws * dm.eta_over_dt, dm.a_prev[f]);
            d.bend[1] = (wb * dm.eta_over_dt, dm.b_prev[f]);
        }
        d
    }

    /// Evaluates Φ at positions `x` and edge DOFs `phi` (empty without them) and, as wanted, its
    /// gradient (len `pattern.n`) and exact Hessian values (pattern order). Fixed nodes get zero
    /// gradient and a unit-scaled identity block.
    pub fn eval(
        &self,
        x: &[Vec3],
        phi: &[Real],
        want: Want,
        grad: &mut [Real],
        values: &mut [Real],
    ) -> Real {
        self.eval_projected(x, phi, want, HessianProjection::None, grad, values)
    }

    /// The relative residual of a gradient: `max(‖g_x‖∞, ‖g_φ‖∞ / ℓ, maxₖ |g_k| / ℓ_k) / F`,
    /// with `F` the potential's force scale ([`Potential::force_scale`]), `ℓ` the mean edge length (an edge DOF's gradient is a
    /// moment, N·m) and `ℓ_k` global DOF k's declared length
    /// ([`crate::energy::term::GlobalDof::length`]).
    pub fn residual(&self, grad: &[Real]) -> Real {
        let nx = 3 * self.pattern.num_vertices;
        let ne = nx + self.body.num_edge_dofs();
        let gx = grad[..nx].iter().fold(0.0 as Real, |m, v| m.max(v.abs()));
        let gp = grad[nx..ne].iter().fold(0.0 as Real, |m, v| m.max(v.abs()));
        let gg = grad[ne..]
            .iter()
            .zip(self.globals)
            .fold(0.0 as Real, |m, (v, g)| m.max(v.abs() / g.length));
        let f = self.force_scale.max(Real::MIN_POSITIVE);
        gx.max(gp / self.body.mean_edge).max(gg) / f
    }

    /// The largest fraction of a Newton step `step` (DOF order) from the positions `x` that
    /// moves no global DOF by more than its [`crate::energy::term::GlobalDof::max_step`] and
    /// that every term bounding the steps allows ([`crate::energy::term::StepLimit`]; 1 when
    /// none would bound it), and whether a term asks to gather its elements again first.
    pub fn step_bound(
        &self,
        x: &[Vec3],
        phi: &[Real],
        step: &[Real],
    ) -> crate::energy::term::StepBound {
        let ne = 3 * self.pattern.num_vertices + self.body.num_edge_dofs();
        let globals = step[ne..]
            .iter()
            .zip(self.globals)
            .fold(1.0, |a: Real, (d, g)| {
                if d.abs() * a > g.max_step {
                    g.max_step / d.abs()
                } else {
                    a
                }
            });
        self.terms
            .iter()
            .zip(&self.pattern.maps)
            .filter_map(|(t, map)| Some(t.step_limit()?.max_fraction(self, map, x, phi, step)))
            .fold(
                crate::energy::term::StepBound {
                    fraction: globals,
                    regather: false,
                },
                |a, b| crate::energy::term::StepBound {
                    fraction: a.fraction.min(b.fraction),
                    regather: a.regather || b.regather,
                },
            )
    }

    /// The largest fraction of the jump from `from` at dial `from_dial` to `to` at this
    /// potential's dial, the scalar DOFs `phi` held, that every term that bounds the steps
    /// allows ([`crate::energy::term::StepLimit::jump_fraction`]).
    pub fn jump_fraction(&self, from: &[Vec3], to: &[Vec3], phi: &[Real], from_dial: Real) -> Real {
        self.terms
            .iter()
            .filter_map(|t| {
                Some(
                    t.step_limit()?
                        .jump_fraction(self, from, to, phi, from_dial),
                )
            })
            .fold(1.0, Real::min)
    }

    /// Lowers `bounds[v]` (m) to how far vertex `v` may move from `x`, where the changing
    /// terms' elements were gathered, for every term that bounds the steps
    /// ([`crate::energy::term::StepLimit::displacement_bounds`]).
    pub fn displacement_bounds(&self, x: &[Vec3], bounds: &mut [Real]) {
        for (t, map) in self.terms.iter().zip(&self.pattern.maps) {
            if let Some(l) = t.step_limit() {
                l.displacement_bounds(self, map, x, bounds);
            }
        }
    }

    /// How far the dial may move from this potential's, the positions held at `x`, where the
    /// changing terms' elements were gathered, before what moves with it (a mesh obstacle)
    /// could bring an element below its floor, for every term that bounds the steps
    /// ([`crate::energy::term::StepLimit::dial_room`]; `+∞` when nothing moves).
    pub fn dial_room(&self, x: &[Vec3]) -> Real {
        self.terms
            .iter()
            .zip(&self.pattern.maps)
            .filter_map(|(t, map)| Some(t.step_limit()?.dial_room(self, map, x)))
            .fold(Real::INFINITY, Real::min)
    }

    /// Whether every term that bounds the steps admits the state `(x, phi)`
    /// ([`crate::energy::term::StepLimit::admits`]).
    pub fn admits(&self, x: &[Vec3], phi: &[Real]) -> bool {
        self.terms
            .iter()
            .zip(&self.pattern.maps)
            .all(|(t, map)| t.step_limit().is_none_or(|l| l.admits(self, map, x, phi)))
    }

    /// As [`Potential::eval`], with the element Hessians projected as `projection` says.
    pub fn eval_projected(
        &self,
        x: &[Vec3],
        phi: &[Real],
        want: Want,
        projection: HessianProjection,
        grad: &mut [Real],
        values: &mut [Real],
    ) -> Real {
        let sc = self.body;
        if want != Want::Energy {
            // Within a team's hot loop, rayon's workers stay asleep: waking one would take a
            // core from the team's spinning helpers.
            crate::team::with_active(|team| match team {
                Some(_) => grad.fill(0.0),
                None => grad.par_chunks_mut(1 << 14).for_each(|c| c.fill(0.0)),
            });
        }
        if want == Want::Hessian {
            values.par_chunks_mut(1 << 14).for_each(|c| c.fill(0.0));
        }
        let mut e = 0.0;
        for (term, map) in self.terms.iter().zip(&self.pattern.maps) {
            e += term.eval(self, map, x, phi, want, projection, grad, values);
        }
        if want != Want::Energy {
            for &d in &sc.pinned_dofs {
                grad[d] = 0.0;
            }
            sc.project_skew(grad);
        }
        if want == Want::Hessian {
            for &k in self.pattern.pinned_entries() {
                values[k] = 0.0;
            }
            let n = self.pattern.n;
            let mut sum = 0.0;
            let mut cnt = 0usize;
            for i in 0..n {
                let d = values[self.pattern.diag(i)];
                if d != 0.0 {
                    sum += d.abs();
                    cnt += 1;
                }
            }
            let scale = if cnt > 0 { sum / cnt as Real } else { 1.0 };
            for (u, &fx) in self.node_fixed.iter().enumerate() {
                if fx {
                    let (d0, k) = self.pattern.node_dofs(u);
                    for c in 0..k {
                        values[self.pattern.diag(d0 + c)] = scale;
                    }
                }
            }
            for &d in &sc.pinned_dofs {
                values[self.pattern.diag(d)] = scale;
            }
            self.pattern
                .project_skew(values, &|u| sc.skew_projector(u), scale);
        }
        e
    }

    /// The dense low-rank Hessian parts of every term at `(x, phi)`, zero on fixed nodes and
    /// pinned DOFs.
    pub fn low_rank(&self, x: &[Vec3], phi: &[Real]) -> Vec<LowRank> {
        let mut out = Vec::new();
        for t in self.terms.iter().filter_map(|t| t.low_rank()) {
            t.low_rank(self, x, phi, &mut out);
        }
        for lr in &mut out {
            self.mask_fixed(&mut lr.u);
        }
        out
    }

    /// Zeroes the entries of a DOF vector on fixed nodes and pinned DOFs (the DOFs the
    /// solver does not move).
    pub fn mask_fixed(&self, v: &mut [Real]) {
        for (u, &fx) in self.node_fixed.iter().enumerate() {
            if fx {
                let (d0, k) = self.pattern.node_dofs(u);
                v[d0..d0 + k].fill(0.0);
            }
        }
        for &d in &self.body.pinned_dofs {
            v[d] = 0.0;
        }
        self.body.project_skew(v);
    }

    /// The applied loads' force scale at `(x, phi)` (N): the largest component of their forces
    /// on the free DOFs of the vertices ([`crate::energy::term::Term::applied_load`]), 0
    /// without loads. A static solve measures its residual against it when it is below the
    /// body's scale, so that a load small against the sheet's stiffness is still solved to the
    /// tolerance relative to itself.
    pub fn load_scale(&self, x: &[Vec3], phi: &[Real]) -> Real {
        let mut g = self.gradient_of(x, phi, false, |t| t.applied_load());
        for &d in &self.body.pinned_dofs {
            g[d] = 0.0;
        }
        self.body.project_skew(&mut g);
        g[..3 * self.pattern.num_vertices]
            .iter()
            .fold(0.0, |m: Real, v| m.max(v.abs()))
    }

    /// The applied loads' forces at `(x, phi)` (N, DOF order): `−∂/∂x` of the load terms
    /// ([`crate::energy::term::Term::applied_load`]) with nothing held.
    pub fn applied_forces(&self, x: &[Vec3], phi: &[Real]) -> Vec<Real> {
        let mut g = self.gradient_of(x, phi, true, |t| t.applied_load());
        g.iter_mut().for_each(|v| *v = -*v);
        g
    }

    /// The support reactions at `(x, phi)`: per vertex, the force the supports exert on it (N),
    /// `∂Φ/∂x` evaluated with nothing held, on the held vertices and the held components of the
    /// others ([`crate::body::Body::pinned_dofs`]), its part along the held directions at a
    /// skew vertex (`(I − P) ∂Φ/∂x`, [`crate::body::Body::skew`]), zero elsewhere. At an
    /// equilibrium the
    /// reactions and the applied loads sum to zero (every term but the loads is invariant under
    /// translations), and so do their moments (the edge rotations a clamp holds are relative
    /// to the faces and carry no moment of their own).
    pub fn reactions(&self, x: &[Vec3], phi: &[Real]) -> Vec<Vec3> {
        let nv = self.pattern.num_vertices;
        let g = self.gradient_of(x, phi, true, |_| true);
        let mut held = vec![[false; 3]; nv];
        for (v, h) in held.iter_mut().enumerate() {
            if self.node_fixed[v] {
                *h = [true; 3];
            }
        }
        for &d in &self.body.pinned_dofs {
            held[d / 3][d % 3] = true;
        }
        let mut r: Vec<Vec3> = (0..nv)
            .map(|v| Vec3::from_fn(|k, _| if held[v][k] { g[3 * v + k] } else { 0.0 }))
            .collect();
        // A skew vertex: the part of its force along the directions it is held in.
        for s in &self.body.skew {
            let v = s.vertex;
            let f = Vec3::new(g[3 * v], g[3 * v + 1], g[3 * v + 2]);
            r[v] = f - s.free * f;
        }
        r
    }

    /// The couple (N·m, about the origin) that the supports exert through the boundary
    /// rotations they set in space (clamps and symmetry planes with edge DOFs,
    /// [`crate::body::Body::edge_normal`]): `−Σ_v x_v × ∂E/∂x_v` over the shell's energy,
    /// which is invariant under rigid rotations of the positions except through those set
    /// normals. Zero when none is set. The held vertices' forces
    /// ([`Potential::reactions`]), their moments, this couple and the applied loads balance.
    pub fn rotation_couple(&self, x: &[Vec3], phi: &[Real]) -> Vec3 {
        if self.body.edge_normal.is_empty() {
            return Vec3::zeros();
        }
        let g = self.gradient_of(x, phi, true, |t| t.name() == crate::energy::shell::NAME);
        -x.iter()
            .enumerate()
            .map(|(v, p)| p.cross(&Vec3::new(g[3 * v], g[3 * v + 1], g[3 * v + 2])))
            .sum::<Vec3>()
    }

    /// The gradient at `(x, phi)` (DOF order, `pattern.n` entries) of the terms that `keep`
    /// selects: with nothing held when `nothing_held` (the held DOFs then carry the forces
    /// the supports balance), else with this potential's held nodes. Pinned DOFs and skew
    /// vertices' held directions are not zeroed.
    fn gradient_of(
        &self,
        x: &[Vec3],
        phi: &[Real],
        nothing_held: bool,
        keep: impl Fn(&dyn Term) -> bool,
    ) -> Vec<Real> {
        let free = vec![false; self.node_fixed.len()];
        let pot = if nothing_held {
            Potential {
                node_fixed: &free,
                owned: None,
                ..*self
            }
        } else {
            *self
        };
        let mut g = vec![0.0; self.pattern.n];
        for (term, map) in self.terms.iter().zip(&self.pattern.maps) {
            if keep(term.as_ref()) {
                term.eval(
                    &pot,
                    map,
                    x,
                    phi,
                    Want::Gradient,
                    HessianProjection::None,
                    &mut g,
                    &mut [],
                );
            }
        }
        g
    }

    /// Energies by term name at `(x, phi)` (each term's [`crate::energy::term::energies`]).
    pub fn energies(&self, x: &[Vec3], phi: &[Real]) -> Vec<(&'static str, Real)> {
        let mut out = Vec::new();
        for (t, map) in self.terms.iter().zip(&self.pattern.maps) {
            out.extend(crate::energy::term::energies(t.as_ref(), self, map, x, phi));
        }
        out
    }
}
