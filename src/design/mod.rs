//! Inverse design: the per-face rest-form variables that make a sheet's static equilibrium take
//! a target shape, by exact adjoint sensitivities and projected L-BFGS.
//!
//! ## The sensitivities
//! A design `p` (numbers per face, [`variables`]) gives each face its rest data
//! `r_f(p_f) = (ā, b̄, h̄)`; the equilibrium `x*(p)` solves `g(x*, r) = 0`. For the objective
//! `J(p) = J_d(x*(p)) + J_s(p)` ([`objective`]), differentiating `g = 0` gives
//! `H dx*/dp = −∂g/∂r · ∂r/∂p`, so
//!
//! `dJ/dp_f = −(∂r_f/∂p_f)ᵀ (λᵀ ∂g/∂r_f) + ∂J_s/∂p_f`,   `H λ = ∂J_d/∂x`,
//!
//! with `H` the exact Hessian at `x*` (its sparse part factorised once, the rank-one gas part by
//! Woodbury, held DOFs and rigid pins masked: their rows of `H` are the identity and of the
//! right-hand side zero) and `λᵀ ∂g/∂r_f` from the shell kernels
//! ([`crate::energy::sensitivity`]). Edge DOFs and other scalar DOFs are part of `x` with a zero
//! right-hand side. One design iteration is thus the equilibrium's re-solve (Newton, warm
//! started from the last accepted equilibrium), one Hessian assembly and factorisation, one
//! solve and one pass over the faces.
//!
//! ## Stability and branches
//! The factorisation of the exact Hessian doubles as the stability check: a design whose
//! equilibrium is not a minimum (the flat sheet once its metric asks it to buckle) is pushed
//! toward the target, `x ← x + η (Rᵀ(y − t) − x)` (the target seen in the shape's own frame,
//! η = 0.05, 0.2, 0.5), and solved again. A trial design whose equilibrium cannot be found or
//! stays unstable is refused, and the optimiser cuts its step ([`lbfgs`]): the design moves by
//! continuation, never further than the equilibrium follows.

pub mod curvature;
pub mod gauss_newton;
pub mod lbfgs;
pub mod objective;
pub mod run;
pub mod surface;
pub mod variables;

use crate::assembly::{Pattern, Want};
use crate::energy::{HessianProjection, Potential};
use crate::math::{Real, Sym2, Vec3};
use crate::model::Scene;
use crate::solve::low_rank::Woodbury;
use crate::solve::newton::Workspace;
use crate::solve::{newton, LinearSolver, NewtonOptions, State};
use objective::{Shape, Smoothness, Sobolev};
use std::time::Instant;
use variables::Chain;

/// The push toward the target that frees an unstable equilibrium, as fractions of the way.
const ESCAPES: [Real; 3] = [0.05, 0.2, 0.5];

/// The smallest continuation step between two designs' rest data.
const MIN_CONTINUATION_STEP: Real = 1.0 / 1024.0;

/// The static potential of `scene` on `pattern` at rest data `(forms, ratio, mass)`: the rest
/// forms, thickness ratios and lumped masses of a design replace the scene's, at dial 1, with the
/// scene's gravity.
fn potential<'p>(
    scene: &'p Scene,
    pattern: &'p Pattern,
    gravity: Vec3,
    (forms, ratio, mass): (&'p [(Sym2, Sym2)], &'p [Real], &'p [Real]),
) -> Potential<'p> {
    Potential {
        rest_override: Some(forms),
        thickness_override: Some(ratio),
        mass,
        gravity,
        ..Potential::new(scene, pattern)
    }
}

/// Factorises the exact Hessian of `pot` at `state` in `lin`, with its low-rank part: the
/// Woodbury solver when the whole is positive definite (a stable equilibrium), else `None`.
fn factor_exact(pot: &Potential, lin: &mut LinearSolver, state: &State) -> Option<Woodbury> {
    let n = pot.pattern.n;
    let mut grad = vec![0.0; n];
    let mut values = vec![0.0; pot.pattern.row_idx.len()];
    pot.eval_projected(
        &state.x,
        &state.dofs,
        Want::Hessian,
        HessianProjection::None,
        &mut grad,
        &mut values,
    );
    lin.factor(&values).ok()?;
    let lr = pot.low_rank(&state.x, &state.dofs);
    let wb = Woodbury::new(lin, &lr);
    wb.keeps_positive_definite().then_some(wb)
}

/// Solves `H v = b` in place with the factorisation `lin` and its low-rank part `held`, the
/// fixed DOFs masked on both sides (their rows of `H` are the identity, their right-hand side
/// zero); false when nothing is held or the system is singular.
fn solve_held(
    pot: &Potential,
    held: Option<&Woodbury>,
    lin: &mut LinearSolver,
    v: &mut [Real],
) -> bool {
    pot.mask_fixed(v);
    let solved = held.is_some_and(|wb| wb.solve_in_place(lin, v));
    if solved {
        pot.mask_fixed(v);
    }
    solved
}

/// Where the time of the evaluations went (s).
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct DesignTiming {
    /// Newton's re-solves of the equilibrium.
    pub equilibrium: f64,
    /// The adjoint: the exact Hessian's assembly, factorisation and solve.
    pub adjoint: f64,
    /// The rest sensitivities' pass over the faces and the chain to the design.
    pub sensitivities: f64,
    /// Newton iterations of the re-solves.
    pub newton_iterations: usize,
    /// Evaluations (accepted or not).
    pub evaluations: usize,
    /// Evaluations refused (no equilibrium, or an unstable one).
    pub refused: usize,
    /// The predictor of the warm starts.
    pub predictor: f64,
}

/// An evaluated design: its equilibrium and objective parts.
#[derive(Clone, Debug)]
pub struct Evaluated {
    /// The equilibrium.
    pub state: State,
    /// The rest forms `(ā, b̄)` per face (barycentric).
    pub forms: Vec<(Sym2, Sym2)>,
    /// `h̄/h` per face.
    pub ratio: Vec<Real>,
    /// The distance term `J_d` (unweighted; 0 without it).
    pub distance: Real,
    /// The mean curvature term `J_H` (unweighted).
    pub mean: Real,
    /// The Gauss curvature term `J_K` (unweighted).
    pub gauss: Real,
    /// The target point each vertex is compared with (target frame), with a distance term.
    pub nearest: Option<Vec<Vec3>>,
    /// The smoothness term `J_s`.
    pub smoothness: Real,
    /// The alignment `(R, t)` of the shape onto the target.
    pub alignment: (crate::math::Mat3, Vec3),
}

/// An inverse-design problem on a scene: the chain, the objective and the equilibrium solver.
pub struct Problem<'s> {
    scene: &'s Scene,
    /// The design chain.
    pub chain: Chain,
    /// The shape terms.
    pub shape: Shape,
    /// The smoothness term.
    pub smoothness: Smoothness,
    /// The Sobolev metric of the optimiser's steps (`None`: the plain gradient).
    pub metric: Option<Sobolev>,
    pattern: Pattern,
    lin: LinearSolver,
    ws: Workspace,
    opts: NewtonOptions,
    gravity: Vec3,
    /// The last accepted evaluation (the warm start).
    pub current: Option<Evaluated>,
    /// The design of [`Problem::current`].
    current_p: Vec<Real>,
    trial: Option<(Evaluated, Vec<Real>)>,
    /// The low-rank (Woodbury) part of the exact Hessian factorised in `lin`, prepared by the
    /// stability check and reused by the adjoint and the predictor at the same equilibrium.
    held: Option<Woodbury>,
    /// Whether `lin` and `held` are the factorisation at the current equilibrium.
    factor_current: bool,
    /// The last predictor: a design change and the equilibrium's first-order response to it.
    predicted: Option<(Vec<Real>, Vec<Real>)>,
    /// Time and counts.
    pub timing: DesignTiming,
}

impl<'s> Problem<'s> {
    /// The problem of `scene` with `chain`, the shape terms and `smoothness`.
    pub fn new(
        scene: &'s Scene,
        chain: Chain,
        shape: Shape,
        smoothness: Smoothness,
    ) -> Result<Self, String> {
        let pattern = Pattern::for_scene(scene);
        let mut lin = LinearSolver::new(&pattern).map_err(|e| e.to_string())?;
        lin.analyse().map_err(|e| e.to_string())?;
        let ws = Workspace::new(&pattern);
        let st = &scene.settings.solver;
        Ok(Problem {
            scene,
            chain,
            shape,
            smoothness,
            metric: None,
            pattern,
            lin,
            ws,
            opts: NewtonOptions {
                tol: st.tolerance,
                max_iter: st.max_newton_iterations,
                projection: st.hessian_projection,
                chord: false,
            },
            gravity: Vec3::from(scene.settings.loads.gravity),
            current: None,
            current_p: Vec::new(),
            trial: None,
            held: None,
            factor_current: false,
            predicted: None,
            timing: DesignTiming::default(),
        })
    }

    /// The rest data of every face at design `p`, with the Jacobians.
    fn rest(&self, p: &[Real]) -> Vec<variables::FaceRest> {
        let k = self.chain.per_face();
        (0..self.scene.body.num_faces())
            .map(|f| self.chain.face(f, &p[k * f..k * (f + 1)]))
            .collect()
    }

    /// The lumped vertex masses at thickness ratios `ratio`: the scene's, except for a designed
    /// thickness in a scene with weight, where each face's share `ρ A_f h̄_f/(3 ρ_law)` follows
    /// the thickness written (the reference thickness `h̄/ρ_law` the law scales).
    fn mass(&self, ratio: &[Real]) -> std::borrow::Cow<'s, [Real]> {
        let body = &self.scene.body;
        let Some((dm, law_ratio)) = self.mass_per_thickness() else {
            return std::borrow::Cow::Borrowed(&body.mass[..]);
        };
        let mut m = body.mass.clone();
        for (f, face) in body.mesh.faces.iter().enumerate() {
            // The change from the scene's own thickness h ρ_law.
            let dh = body.thickness[f] * (ratio[f] - law_ratio[f]);
            for &v in face {
                m[v] += dm[f] * dh;
            }
        }
        std::borrow::Cow::Owned(m)
    }

    /// `∂m_v/∂h̄_f = ρ A_f/(3 ρ_law)` per face (the same for its three vertices), for a
    /// designed thickness in a scene with weight, with the law's thickness ratios `ρ_law`;
    /// else `None`.
    fn mass_per_thickness(&self) -> Option<(Vec<Real>, &[Real])> {
        let Chain::Thickness { law_ratio, .. } = &self.chain else {
            return None;
        };
        let body = &self.scene.body;
        if body.density == 0.0 || self.gravity == Vec3::zeros() {
            return None;
        }
        let dm = (0..body.mesh.faces.len())
            .map(|f| body.density * body.mesh.face_area(f) / (3.0 * law_ratio[f]))
            .collect();
        Some((dm, law_ratio))
    }

    /// The equilibrium at rest data `(forms, ratio)` from `state`: Newton, and the stability
    /// check by the exact Hessian's factorisation, with the escapes toward the target. On
    /// success the factorisation of the exact Hessian at the equilibrium is kept in `lin`.
    fn equilibrium(
        &mut self,
        forms: &[(Sym2, Sym2)],
        ratio: &[Real],
        state: &mut State,
    ) -> Result<(), String> {
        let mut escapes = ESCAPES.iter();
        loop {
            let clock = Instant::now();
            let mass = self.mass(ratio);
            let pot = potential(
                self.scene,
                &self.pattern,
                self.gravity,
                (forms, ratio, &mass),
            );
            let rep = newton(&pot, &mut self.lin, &mut self.ws, state, self.opts);
            self.timing.equilibrium += clock.elapsed().as_secs_f64();
            self.timing.newton_iterations += rep.iterations;
            if !rep.converged {
                return Err(format!(
                    "the equilibrium was not found ({})",
                    rep.failure_text()
                ));
            }
            let clock = Instant::now();
            self.held = factor_exact(&pot, &mut self.lin, state);
            self.timing.adjoint += clock.elapsed().as_secs_f64();
            if self.held.is_some() {
                return Ok(());
            }
            let Some(&eta) = escapes.next() else {
                return Err("the equilibrium stays unstable after pushes toward the target".into());
            };
            let seen = self.shape.eval(&state.x);
            let Some(near) = seen.nearest else {
                return Err(
                    "the equilibrium is unstable, and without a distance term there is \
                            no target to push it toward"
                        .into(),
                );
            };
            let (r, t) = seen.alignment;
            for (x, y) in state.x.iter_mut().zip(&near) {
                let seen = r.transpose() * (y - t);
                *x += (seen - *x) * eta;
            }
        }
    }

    /// The equilibrium at rest data `to` from `state`, the equilibrium at `from`: directly, or
    /// when that fails by continuation along `(1 − τ) from + τ to` (a convex combination, so ā
    /// stays positive definite), τ's step halved on a failure and doubled after a success, down
    /// to [`MIN_CONTINUATION_STEP`].
    fn continuation(
        &mut self,
        from: &(Vec<(Sym2, Sym2)>, Vec<Real>),
        to: (&[(Sym2, Sym2)], &[Real]),
        state: &mut State,
    ) -> Result<(), String> {
        let mut trial = state.clone();
        let first = match self.equilibrium(to.0, to.1, &mut trial) {
            Ok(()) => {
                *state = trial;
                return Ok(());
            }
            Err(e) => e,
        };
        let (mut tau, mut step): (Real, Real) = (0.0, 0.5);
        while tau < 1.0 {
            let next = (tau + step).min(1.0);
            let forms: Vec<(Sym2, Sym2)> = from
                .0
                .iter()
                .zip(to.0)
                .map(|(a, b)| (a.0.lerp(&b.0, next), a.1.lerp(&b.1, next)))
                .collect();
            let ratio: Vec<Real> = from
                .1
                .iter()
                .zip(to.1)
                .map(|(a, b)| (1.0 - next) * a + next * b)
                .collect();
            trial.clone_from(state);
            match self.equilibrium(&forms, &ratio, &mut trial) {
                Ok(()) => {
                    std::mem::swap(state, &mut trial);
                    tau = next;
                    step *= 2.0;
                }
                Err(e) => {
                    step *= 0.5;
                    if step < MIN_CONTINUATION_STEP {
                        return Err(format!(
                            "{first}; continuation from the last design stalled at {:.4} of the \
                             way ({e})",
                            tau
                        ));
                    }
                }
            }
        }
        // The last blend was `to` itself: the factorisation held is the equilibrium's.
        Ok(())
    }

    /// The first-order response of the current equilibrium to the design change `dp`,
    /// `δx = −H⁻¹ ∂g/∂p δp`, with `∂g/∂p δp` by central differences of the gradient over the
    /// rest data at `p ± ε δp` (a predictor needs no more) and `H` the factorisation held at the
    /// current equilibrium. Along one direction the response scales: a shorter step of the line
    /// search reuses it. `None` when there is no current factorisation.
    fn predict(&mut self, p: &[Real]) -> Option<Vec<Real>> {
        if self.current.is_none() || self.current_p.len() != p.len() {
            return None;
        }
        let dp: Vec<Real> = p.iter().zip(&self.current_p).map(|(a, b)| a - b).collect();
        let norm = |v: &[Real]| v.iter().map(|x| x * x).sum::<Real>().sqrt();
        let n = norm(&dp);
        if n == 0.0 {
            return None;
        }
        if let Some((d0, x0)) = &self.predicted {
            let alpha = dp.iter().zip(d0).map(|(a, b)| a * b).sum::<Real>()
                / d0.iter()
                    .map(|x| x * x)
                    .sum::<Real>()
                    .max(Real::MIN_POSITIVE);
            let off: Vec<Real> = dp.iter().zip(d0).map(|(a, b)| a - alpha * b).collect();
            if norm(&off) <= 1e-10 * n {
                return Some(x0.iter().map(|x| x * alpha).collect());
            }
        }
        if !self.factor_current {
            return None;
        }
        let dx = self.tangent(&dp)?;
        self.predicted = Some((dp, dx.clone()));
        Some(dx)
    }

    /// The first-order response `S v = −H⁻¹ ∂g/∂p v` of the current equilibrium to the design
    /// change `v` (m per design unit), with `∂g/∂p v` by central differences of the gradient
    /// over the rest data at `p ± ε v` and `H` the factorisation held at the current
    /// equilibrium (refactorised there when a trial replaced it). `None` without a current
    /// equilibrium, or when its Hessian is no longer positive definite.
    fn tangent(&mut self, dp: &[Real]) -> Option<Vec<Real>> {
        if !self.refactor_current() {
            return None;
        }
        let cur = self.current.as_ref()?;
        let amax = dp.iter().fold(0.0 as Real, |m, x| m.max(x.abs()));
        if amax == 0.0 {
            return Some(vec![0.0; self.pattern.n]);
        }
        let eps = 1e-6 / amax;
        let mut grads = Vec::new();
        for sign in [1.0, -1.0] {
            let q: Vec<Real> = self
                .current_p
                .iter()
                .zip(dp)
                .map(|(a, d)| a + sign * eps * d)
                .collect();
            let rest = self.rest(&q);
            let forms: Vec<(Sym2, Sym2)> = rest.iter().map(|r| r.forms).collect();
            let ratio: Vec<Real> = rest.iter().map(|r| r.ratio).collect();
            let mass = self.mass(&ratio);
            let pot = potential(
                self.scene,
                &self.pattern,
                self.gravity,
                (&forms, &ratio, &mass),
            );
            let mut g = vec![0.0; self.pattern.n];
            pot.eval(
                &cur.state.x,
                &cur.state.dofs,
                Want::Gradient,
                &mut g,
                &mut [],
            );
            grads.push(g);
        }
        let mut dx: Vec<Real> = grads[0]
            .iter()
            .zip(&grads[1])
            .map(|(a, b)| -(a - b) / (2.0 * eps))
            .collect();
        let mass = self.mass(&cur.ratio);
        let pot = potential(
            self.scene,
            &self.pattern,
            self.gravity,
            (&cur.forms, &cur.ratio, &mass),
        );
        solve_held(&pot, self.held.as_ref(), &mut self.lin, &mut dx).then_some(dx)
    }

    /// Makes `lin` and `held` the factorisation at the current equilibrium again (after a trial
    /// replaced it); false without a current equilibrium or when it is not positive definite.
    fn refactor_current(&mut self) -> bool {
        if self.factor_current {
            return true;
        }
        let Some(cur) = self.current.as_ref() else {
            return false;
        };
        let clock = Instant::now();
        let mass = self.mass(&cur.ratio);
        let pot = potential(
            self.scene,
            &self.pattern,
            self.gravity,
            (&cur.forms, &cur.ratio, &mass),
        );
        self.held = factor_exact(&pot, &mut self.lin, &cur.state);
        self.factor_current = self.held.is_some();
        self.timing.adjoint += clock.elapsed().as_secs_f64();
        self.factor_current
    }

    /// `Sᵀ u = −(∂g/∂p)ᵀ H⁻¹ u` at the current equilibrium (per design number, for `u` per DOF):
    /// the adjoint of [`Problem::tangent`], by the same pass as the gradient.
    fn pullback(&mut self, mut u: Vec<Real>) -> Option<Vec<Real>> {
        if !self.refactor_current() {
            return None;
        }
        let cur = self.current.as_ref()?;
        let mass = self.mass(&cur.ratio);
        let pot = potential(
            self.scene,
            &self.pattern,
            self.gravity,
            (&cur.forms, &cur.ratio, &mass),
        );
        if !solve_held(&pot, self.held.as_ref(), &mut self.lin, &mut u) {
            return None;
        }
        let rest = self.rest(&self.current_p);
        self.rest_gradient(&pot, &cur.state, &rest, &u).ok()
    }

    /// `−(∂r/∂p)ᵀ (λᵀ ∂g/∂r)` per design number, with the designed mass's weight: the design
    /// gradient of an adjoint state `λ` at the equilibrium `state` of `pot`.
    fn rest_gradient(
        &self,
        pot: &Potential,
        state: &State,
        rest: &[variables::FaceRest],
        lambda: &[Real],
    ) -> Result<Vec<Real>, String> {
        let mut w = vec![[0.0; crate::energy::sensitivity::REST_DATA]; rest.len()];
        for t in self.scene.terms.iter() {
            if let Some(s) = t.rest_sensitivity() {
                let part = s.rest_adjoint(pot, &state.x, &state.dofs, lambda)?;
                for (a, b) in w.iter_mut().zip(part) {
                    for (x, y) in a.iter_mut().zip(b) {
                        *x += y;
                    }
                }
            }
        }
        let k = self.chain.per_face();
        let mut grad = vec![0.0; k * rest.len()];
        for (f, r) in rest.iter().enumerate() {
            let h = self.scene.body.thickness[f];
            for (j, row) in r.jac.iter().enumerate() {
                let mut s = 0.0;
                for i in 0..6 {
                    s += row[i] * w[f][i];
                }
                s += row[6] * h * w[f][6];
                grad[k * f + j] = -s;
            }
        }
        // A designed thickness carries the weight with it: the gravity part of the residual,
        // −m_v g, has ∂/∂h̄_f = −(∂m_v/∂h̄_f) g on the face's vertices.
        if let Some((dm, _)) = self.mass_per_thickness() {
            let g = self.gravity;
            for (f, face) in self.scene.body.mesh.faces.iter().enumerate() {
                let s: Real = face
                    .iter()
                    .map(|&v| {
                        Vec3::new(lambda[3 * v], lambda[3 * v + 1], lambda[3 * v + 2]).dot(&g)
                    })
                    .sum();
                grad[f] += dm[f] * s;
            }
        }
        Ok(grad)
    }

    /// Makes the equilibrium `state` (solved again from there, which a converged state needs
    /// no step for) of design `p` the current one: the optimiser goes on from another branch,
    /// the one a forward run of the design found.
    pub fn restart_from(&mut self, p: &[Real], mut state: State) -> Result<(), String> {
        let rest = self.rest(p);
        let forms: Vec<(Sym2, Sym2)> = rest.iter().map(|r| r.forms).collect();
        let ratio: Vec<Real> = rest.iter().map(|r| r.ratio).collect();
        self.factor_current = false;
        self.predicted = None;
        self.equilibrium(&forms, &ratio, &mut state)?;
        let (_, _, e) = self.finish(p, rest, forms, ratio, state)?;
        self.current = Some(e);
        self.current_p = p.to_vec();
        self.factor_current = true;
        self.trial = None;
        Ok(())
    }

    /// Evaluates design `p`: the equilibrium from the current one (or the reference), `J` and
    /// `dJ/dp`.
    pub fn evaluate(&mut self, p: &[Real]) -> Result<(Real, Vec<Real>, Evaluated), String> {
        self.timing.evaluations += 1;
        let rest = self.rest(p);
        let forms: Vec<(Sym2, Sym2)> = rest.iter().map(|r| r.forms).collect();
        let ratio: Vec<Real> = rest.iter().map(|r| r.ratio).collect();
        let clock = Instant::now();
        let prediction = self.predict(p);
        self.timing.predictor += clock.elapsed().as_secs_f64();
        self.factor_current = false;
        if let (Some(dx), Some(c)) = (&prediction, &self.current) {
            let mut state = c.state.clone();
            state.set_step(&c.state, dx, 1.0);
            let guess = state.x.clone();
            // An equilibrium further from the prediction than the prediction is from the
            // current one is another branch: the linear response did not hold; go on from the
            // current equilibrium instead.
            let moved = |a: &[Vec3], b: &[Vec3]| {
                a.iter()
                    .zip(b)
                    .map(|(p, q)| (p - q).norm_squared())
                    .sum::<Real>()
                    .sqrt()
            };
            let predicted = moved(&guess, &c.state.x);
            if self.equilibrium(&forms, &ratio, &mut state).is_ok()
                && moved(&state.x, &guess) <= predicted
            {
                return self.finish(p, rest, forms, ratio, state);
            }
        }
        let (mut state, from) = match &self.current {
            Some(c) => (c.state.clone(), (c.forms.clone(), c.ratio.clone())),
            None => {
                let mut st = State::reference(self.scene);
                self.scene.body.prescribe(&mut st.x, 1.0);
                let b = &self.scene.body.rest;
                let forms = (0..forms.len()).map(|f| (b.abar0[f], b.bbar0[f])).collect();
                (st, (forms, vec![1.0; ratio.len()]))
            }
        };
        if let Err(e) = self.continuation(&from, (&forms, &ratio), &mut state) {
            self.timing.refused += 1;
            return Err(e);
        }
        self.finish(p, rest, forms, ratio, state)
    }

    /// `J` and `dJ/dp` at the equilibrium `state` of design `p` (whose exact Hessian `lin`
    /// holds factorised).
    fn finish(
        &mut self,
        p: &[Real],
        rest: Vec<variables::FaceRest>,
        forms: Vec<(Sym2, Sym2)>,
        ratio: Vec<Real>,
        state: State,
    ) -> Result<(Real, Vec<Real>, Evaluated), String> {
        let clock = Instant::now();
        let d = self.shape.eval(&state.x);
        let mut lambda = vec![0.0; self.pattern.n];
        for (v, g) in d.gradient.iter().enumerate() {
            lambda[3 * v..3 * v + 3].copy_from_slice(g.as_slice());
        }
        let mass = self.mass(&ratio);
        let pot = potential(
            self.scene,
            &self.pattern,
            self.gravity,
            (&forms, &ratio, &mass),
        );
        if !solve_held(&pot, self.held.as_ref(), &mut self.lin, &mut lambda) {
            self.timing.refused += 1;
            return Err("the Hessian with its low-rank part is singular at the equilibrium".into());
        }
        self.timing.adjoint += clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        let mut grad = self.rest_gradient(&pot, &state, &rest, &lambda)?;
        let js = self.smoothness.eval(p, &mut grad);
        self.timing.sensitivities += clock.elapsed().as_secs_f64();
        let value = d.value + js;
        Ok((
            value,
            grad,
            Evaluated {
                state,
                forms,
                ratio,
                distance: d.distance,
                mean: d.mean,
                gauss: d.gauss,
                smoothness: js,
                alignment: d.alignment,
                nearest: d.nearest,
            },
        ))
    }
}

impl lbfgs::Problem for Problem<'_> {
    fn eval(&mut self, p: &[Real]) -> Result<(Real, Vec<Real>), String> {
        let (v, g, e) = self.evaluate(p)?;
        self.trial = Some((e, p.to_vec()));
        Ok((v, g))
    }

    fn accept(&mut self) {
        if let Some((t, p)) = self.trial.take() {
            self.current = Some(t);
            self.current_p = p;
            // The accepted trial was the last evaluated: its factorisation is held.
            self.factor_current = true;
            self.predicted = None;
        }
    }

    fn precondition(&self, v: &mut [Real]) {
        if let Some(m) = &self.metric {
            m.solve(v);
        }
    }
}

impl gauss_newton::Model for Problem<'_> {
    fn model_product(&mut self, v: &[Real]) -> Option<Vec<Real>> {
        let (mu, term) = self.shape.distance.as_ref()?;
        let c: Vec<Real> = term.model_weights().iter().map(|w| mu * w).collect();
        let aligns = term.aligns();
        let mut u = self.tangent(v)?;
        let nv = c.len();
        let mut dx: Vec<Vec3> = (0..nv)
            .map(|k| Vec3::new(u[3 * k], u[3 * k + 1], u[3 * k + 2]))
            .collect();
        if aligns {
            // The alignment takes up the response's rigid part.
            let x = &self.current.as_ref()?.state.x;
            objective::remove_rigid_motion(x, &c, &mut dx);
        }
        u.iter_mut().for_each(|x| *x = 0.0);
        for (k, d) in dx.iter().enumerate() {
            let d = d * c[k];
            u[3 * k..3 * k + 3].copy_from_slice(d.as_slice());
        }
        let mut out = self.pullback(u)?;
        if self.smoothness.weight > 0.0 {
            // The smoothness term's Hessian along v, by central differences of its gradient
            // (exact for the quadratic term up to round-off).
            let eps = 1e-6 / lbfgs::amax(v).max(Real::MIN_POSITIVE);
            let mut hi = vec![0.0; v.len()];
            let mut lo = vec![0.0; v.len()];
            let at = |sign: Real| -> Vec<Real> {
                self.current_p
                    .iter()
                    .zip(v)
                    .map(|(a, b)| a + sign * eps * b)
                    .collect()
            };
            self.smoothness.eval(&at(1.0), &mut hi);
            self.smoothness.eval(&at(-1.0), &mut lo);
            for ((o, a), b) in out.iter_mut().zip(&hi).zip(&lo) {
                *o += (a - b) / (2.0 * eps);
            }
        }
        Some(out)
    }

    fn metric_product(&self, v: &[Real]) -> Vec<Real> {
        let mut out = vec![0.0; v.len()];
        match &self.metric {
            Some(m) => m.apply(v, &mut out),
            None => {
                let n = self.scene.body.num_faces().max(1) as Real;
                out.iter_mut().zip(v).for_each(|(o, x)| *o = x / n);
            }
        }
        out
    }

    fn response_size(&mut self, v: &[Real]) -> Option<Real> {
        let size = self.shape.distance.as_ref()?.1.size();
        let dx = self.tangent(v)?;
        let nv = self.scene.body.num_vertices();
        let worst = dx
            .chunks_exact(3)
            .take(nv)
            .map(|d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt())
            .fold(0.0 as Real, Real::max);
        Some(worst / size)
    }
}
