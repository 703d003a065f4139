//! Newton's method on a [`Potential`].
//!
//! Each iteration assembles the gradient and Hessian, factorises `H + τ D` (D = mean |diagonal|,
//! τ = 0 first; on a non-positive pivot τ grows ×10 from 1e-8 until the factorisation succeeds,
//! and the shift is recorded), solves for the step, and backtracks (Armijo, c = 1e-4, halving) on
//! Φ. With the `adaptive` projection (default), an iteration whose exact Hessian is not positive
//! definite (beyond the tiny shift that free rigid-body modes need) uses the Gauss–Newton Hessian
//! instead: positive semi-definite by construction and of the right curvature scale, where a
//! global shift would degrade to gradient descent. After a Gauss–Newton iteration, the exact
//! Hessian is tried again once a full step is accepted (a sign of the quadratic region). Convergence: ‖∇Φ‖∞ ≤ tol · F over free DOFs, with F the scene's force scale (edge-DOF
//! moments divided by the mean edge length, [`Potential::residual`]). Non-finite
//! energies are treated as a failed trial point, never accepted.

use super::linear::LinearSolver;
use super::state::State;
use crate::assembly::Want;
use crate::energy::HessianProjection;
use crate::energy::Potential;
use crate::math::{Real, Vec3};
use std::time::Instant;

/// Controls of one Newton solve.
#[derive(Clone, Copy, Debug)]
pub struct NewtonOptions {
    /// Relative tolerance on ‖∇Φ‖∞ / F.
    pub tol: Real,
    /// Iteration limit.
    pub max_iter: usize,
    /// Which Hessian each iteration factorises (`solver.hessian_projection`).
    pub projection: HessianProjection,
    /// Chord (modified Newton) iterations: an iteration may solve with the factorisation of an
    /// earlier iteration of the same solve while the residual keeps contracting by
    /// [`CHORD_CONTRACTION`] per iteration (the implicit dynamics: the inertia's M/h² keeps the
    /// Hessian close to the one factorised). `false`: every iteration factorises.
    pub chord: bool,
}

/// The contraction ‖∇Φ‖ₖ₊₁ / ‖∇Φ‖ₖ a chord iteration must reach for the next one to reuse the
/// factorisation again; a weaker one, a cut line search or a step that is not a descent
/// direction makes the next iteration factorise afresh. A chord iteration costs an assembly,
/// two triangular solves and a line search, about a fifth of a Newton iteration on the balloon
/// (whose factorisation is 75% of an iteration), so one that halves the residual pays.
pub const CHORD_CONTRACTION: Real = 0.5;

/// What happened in one Newton solve.
#[derive(Clone, Debug, Default)]
pub struct NewtonReport {
    /// Whether the tolerance was reached.
    pub converged: bool,
    /// Iterations (Hessian factorisations that produced a step).
    pub iterations: usize,
    /// Final ‖∇Φ‖∞ / F.
    pub residual: Real,
    /// Final Φ (J).
    pub energy: Real,
    /// Largest relative diagonal shift τ used (0 = none).
    pub max_shift: Real,
    /// Iterations that needed a shift.
    pub shifted_iterations: usize,
    /// Iterations that fell back to the Gauss–Newton Hessian (adaptive mode).
    pub gauss_newton_iterations: usize,
    /// Iterations that solved with an earlier iteration's factorisation (chord steps).
    pub chord_iterations: usize,
    /// Iterations whose exact Hessian had an indefinite sparse part made positive definite by
    /// its low-rank part (an LDLᵀ factorisation; adaptive mode).
    pub indefinite_iterations: usize,
    /// Total step halvings in line searches.
    pub line_search_cuts: usize,
    /// Evaluations of the gradient alone, without the Hessian, because the residual was
    /// predicted below the tolerance (a converged one ends the solve; the others assemble the
    /// Hessian after all).
    pub gradient_only_checks: usize,
    /// Wall time of its parts.
    pub timing: NewtonTiming,
    /// Why it stopped, when it did not converge.
    pub failure: Option<SolveError>,
}

/// Wall time (s) of the parts of Newton solves.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct NewtonTiming {
    /// Energy, gradient and Hessian evaluations (and low-rank parts).
    pub assembly: Real,
    /// Numeric factorisations (with their shifts and inertia checks).
    pub factorisation: Real,
    /// Triangular solves (and the low-rank capacitance).
    pub solve: Real,
    /// Energy evaluations of the backtracking line search.
    pub line_search: Real,
}

impl NewtonTiming {
    /// Adds another solve's times.
    pub fn add(&mut self, o: &NewtonTiming) {
        self.assembly += o.assembly;
        self.factorisation += o.factorisation;
        self.solve += o.solve;
        self.line_search += o.line_search;
    }
}

/// Whether `newton` prints one line per iteration to stderr (`shellsim -v`).
pub static VERBOSE: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Why a Newton solve stopped without converging.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SolveError {
    /// Φ or its gradient is NaN or infinite at the current iterate.
    #[error("non-finite energy or gradient")]
    NonFinite,
    /// The Hessian has NaN or infinite entries.
    #[error("non-finite Hessian")]
    NonFiniteHessian,
    /// A vertex would leave the region in which a term's elements (contact pairs) were
    /// gathered: the driver gathers them again at the current iterate and goes on.
    #[error("a vertex would leave the reach of the contact pairs gathered for this step")]
    Regather,
    /// The iteration limit was reached.
    #[error(
        "no convergence in {iterations} Newton iterations (residual {})",
        crate::math::human(*.residual)
    )]
    NotConverged {
        /// Iterations done.
        iterations: usize,
        /// ‖∇Φ‖∞/F at the last iterate.
        residual: Real,
    },
    /// Even the largest diagonal shift left a non-positive pivot.
    #[error("Hessian could not be factorised even with a large shift")]
    Factor,
    /// The capacitance matrix of a low-rank Hessian part is singular.
    #[error("the Hessian with its low-rank part is singular")]
    LowRankSingular,
    /// The step is not a descent direction (NaN or non-negative slope).
    #[error("Newton step is not a descent direction")]
    NotDescent,
    /// No step length in 40 halvings decreased Φ enough.
    #[error(
        "line search stalled (residual {}, directional derivative {})",
        crate::math::human(*.residual),
        crate::math::human(*.slope)
    )]
    LineSearchStalled {
        /// ‖∇Φ‖∞/F.
        residual: Real,
        /// ∇Φ·d.
        slope: Real,
    },
    /// A term refused the converged state as the next accepted one (see
    /// [`crate::energy::term::Tracked::admissible`]).
    #[error("a term refused the step: {0}")]
    Refused(&'static str),
    /// A term's multiplier (a prescribed volume's pressure) did not settle.
    #[error("the multiplier of a constraint did not settle in {updates} updates")]
    MultiplierNotConverged {
        /// Updates done.
        updates: usize,
    },
    /// A projection after the step failed (an element turned inside out).
    #[error("the step's projection failed: {0}")]
    Projection(String),
    /// No reason was recorded (a converged solve asked for one).
    #[error("no failure recorded")]
    Unknown,
}

impl NewtonReport {
    /// Adds a later solve of the same step: its counts, and its outcome as the outcome.
    pub fn absorb(&mut self, later: &NewtonReport) {
        self.converged = later.converged;
        self.iterations += later.iterations;
        self.residual = later.residual;
        self.energy = later.energy;
        self.max_shift = self.max_shift.max(later.max_shift);
        self.shifted_iterations += later.shifted_iterations;
        self.gauss_newton_iterations += later.gauss_newton_iterations;
        self.chord_iterations += later.chord_iterations;
        self.indefinite_iterations += later.indefinite_iterations;
        self.line_search_cuts += later.line_search_cuts;
        self.gradient_only_checks += later.gradient_only_checks;
        self.timing.add(&later.timing);
        self.failure.clone_from(&later.failure);
    }

    /// Why it stopped, for a solve that did not converge ([`SolveError::Unknown`] if it did).
    pub fn failure_or_unknown(&self) -> SolveError {
        self.failure.clone().unwrap_or(SolveError::Unknown)
    }

    /// The failure as text (empty when it converged).
    pub fn failure_text(&self) -> String {
        self.failure
            .as_ref()
            .map(|f| f.to_string())
            .unwrap_or_default()
    }
}

/// Reusable buffers of a Newton solve.
pub struct Workspace {
    grad: Vec<Real>,
    values: Vec<Real>,
    shifted: Vec<Real>,
    step: Vec<Real>,
    trial: State,
    /// Whether the last exact model needed LDLᵀ (its sparse part was indefinite).
    indefinite: bool,
    /// Whether the last exact model tried was rejected (the Hessian was not positive definite):
    /// the next solve then starts with the Gauss–Newton model instead of a failed
    /// factorisation, and tries the exact one again in its second iteration.
    exact_rejected: bool,
    /// The model a chord iteration may reuse: the held factorisation with its low-rank parts as
    /// they were; cleared before any other factorisation replaces it.
    chord_model: Option<super::low_rank::Woodbury>,
}

impl Workspace {
    /// Buffers for a pattern's DOFs and Hessian entries.
    pub fn new(pattern: &crate::assembly::Pattern) -> Self {
        let n = pattern.n;
        let nnz = pattern.nnz();
        Workspace {
            grad: vec![0.0; n],
            values: vec![0.0; nnz],
            shifted: vec![0.0; nnz],
            step: vec![0.0; n],
            trial: State {
                x: vec![Vec3::zeros(); pattern.num_vertices],
                dofs: vec![0.0; pattern.num_scalar_dofs],
                terms: Default::default(),
            },
            indefinite: false,
            exact_rejected: false,
            chord_model: None,
        }
    }

    /// What the last solves learnt about the Hessian, which the next solve's first model
    /// follows: whether the last exact model needed LDLᵀ, and whether it was rejected. A frame
    /// records them so that a restart repeats the uninterrupted run exactly.
    pub fn model_hints(&self) -> [bool; 2] {
        [self.indefinite, self.exact_rejected]
    }

    /// Records that the Hessian was found not positive definite outside a solve (a stability
    /// test): the next solve starts with the Gauss–Newton model.
    pub fn note_not_positive_definite(&mut self) {
        self.exact_rejected = true;
    }

    /// Restores [`Self::model_hints`].
    pub fn set_model_hints(&mut self, hints: [bool; 2]) {
        [self.indefinite, self.exact_rejected] = hints;
    }

    /// `step = −∇Φ`, the right-hand side of every model's solve.
    fn step_from_gradient(&mut self) {
        for (s, g) in self.step.iter_mut().zip(&self.grad) {
            *s = -g;
        }
    }

    /// The gradient of the last evaluation.
    pub fn gradient(&self) -> &[Real] {
        &self.grad
    }
}

/// Factorises `values + τ·scale·I`, growing τ until it succeeds. Returns τ, or None if even a
/// huge shift fails (non-finite entries).
pub fn factor_with_shift(
    lin: &mut LinearSolver,
    pot: &Potential,
    values: &[Real],
    shifted: &mut [Real],
    tau0: Real,
) -> Option<Real> {
    factor_with_shift_upto(lin, pot, values, shifted, tau0, 1e6)
}

/// As [`factor_with_shift`], giving up once τ would exceed `tau_max`.
pub fn factor_with_shift_upto(
    lin: &mut LinearSolver,
    pot: &Potential,
    values: &[Real],
    shifted: &mut [Real],
    tau0: Real,
    tau_max: Real,
) -> Option<Real> {
    let mut tau = tau0;
    loop {
        shift_into(pot, values, shifted, tau);
        match lin.factor(shifted) {
            Ok(()) => return Some(tau),
            Err(_) => {
                tau = if tau == 0.0 { 1e-8 } else { tau * 10.0 };
                if tau > tau_max {
                    return None;
                }
            }
        }
    }
}

/// `shifted = values + τ·D`, `D` the mean |diagonal| of `values` (1 if it is all zero).
fn shift_into(pot: &Potential, values: &[Real], shifted: &mut [Real], tau: Real) {
    shifted.copy_from_slice(values);
    if tau > 0.0 {
        let n = pot.pattern.n;
        let s: Real = (0..n).map(|i| values[pot.pattern.diag(i)].abs()).sum();
        let scale = if s > 0.0 { s / n as Real } else { 1.0 };
        for i in 0..n {
            shifted[pot.pattern.diag(i)] += tau * scale;
        }
    }
}

/// The exact model Hessian of the adaptive mode: the sparse part `values` factorised by
/// Cholesky with at most the shift `tau_max` (relative, for free rigid-body modes), or, when
/// that fails and there are low-rank parts `lr`, by LDLᵀ without a shift; accepted when the
/// whole (sparse + low-rank) is positive definite (the inertia, [`super::low_rank`]). Returns the
/// shift used and the prepared low-rank solve, or `None` if the exact Hessian is not positive
/// definite.
pub fn exact_model(
    lin: &mut LinearSolver,
    pot: &Potential,
    values: &[Real],
    shifted: &mut [Real],
    lr: &[crate::energy::term::LowRank],
    tau_max: Real,
) -> Option<(Real, super::low_rank::Woodbury)> {
    exact_model_from(lin, pot, values, shifted, lr, tau_max, false, None)
}

/// [`exact_model`], trying LDLᵀ first when `indefinite_first` (the previous iteration's sparse
/// part was indefinite: one factorisation instead of a failed Cholesky and an LDLᵀ), and
/// solving `A r = r` (the sparse part) in the same pass over the factor as the low-rank vectors
/// when a model is accepted (`r` is then ready for [`super::low_rank::Woodbury::correct`];
/// otherwise it is left changed).
#[allow(clippy::too_many_arguments)]
fn exact_model_from(
    lin: &mut LinearSolver,
    pot: &Potential,
    values: &[Real],
    shifted: &mut [Real],
    lr: &[crate::energy::term::LowRank],
    tau_max: Real,
    indefinite_first: bool,
    mut r: Option<&mut [Real]>,
) -> Option<(Real, super::low_rank::Woodbury)> {
    use super::low_rank::Woodbury;
    // LDLᵀ of the unshifted sparse part, accepted when the whole is positive definite.
    let by_ldlt = |lin: &mut LinearSolver, r: Option<&mut [Real]>| {
        let negative = lin.factor_indefinite(values).ok()?;
        let wb = Woodbury::new_with(lin, lr, r);
        (wb.negative_eigenvalues(negative) == Some(0)).then_some((0.0, wb))
    };
    if indefinite_first && !lr.is_empty() {
        if let Some(m) = by_ldlt(lin, r.as_deref_mut()) {
            return Some(m);
        }
    }
    if let Some(t) = factor_with_shift_upto(lin, pot, values, shifted, tau_max, tau_max) {
        let wb = Woodbury::new_with(lin, lr, r);
        if wb.keeps_positive_definite() {
            return Some((t, wb));
        }
        return None;
    }
    if lr.is_empty() {
        return None;
    }
    by_ldlt(lin, r)
}

/// Whether the whole Hessian (sparse `values` + low-rank `lr`) shifted by `δ·mean|diag|`
/// is positive definite: Cholesky of the shifted sparse part, or with low-rank parts its LDLᵀ
/// and the inertia ([`super::low_rank`]). The stability test of an equilibrium.
pub fn is_positive_definite(
    lin: &mut LinearSolver,
    pot: &Potential,
    values: &[Real],
    lr: &[crate::energy::term::LowRank],
    delta: Real,
) -> bool {
    let mut shifted = vec![0.0; values.len()];
    shift_into(pot, values, &mut shifted, delta);
    if lin.factor(&shifted).is_ok() {
        return super::low_rank::Woodbury::new(lin, lr).keeps_positive_definite();
    }
    if lr.is_empty() {
        return false;
    }
    match lin.factor_indefinite(&shifted) {
        Ok(negative) => {
            super::low_rank::Woodbury::new(lin, lr).negative_eigenvalues(negative) == Some(0)
        }
        Err(_) => false,
    }
}

/// Backtracking (Armijo) line search along `ws.step` from `state` (energy `e`, slope `slope`):
/// the trial state in `ws.trial`, the step length, and whether it decreased Φ enough. Near
/// convergence Φ changes at round-off level; a round-off slack keeps a tiny, correct step from
/// being rejected.
fn line_search(
    pot: &Potential,
    ws: &mut Workspace,
    state: &State,
    e: Real,
    slope: Real,
    bound: Real,
    rep: &mut NewtonReport,
) -> (Real, bool) {
    let mut alpha = bound;
    if alpha.is_nan() || alpha <= 0.0 {
        // A term allows no motion along this step (a contact pair at its minimum distance).
        return (0.0, false);
    }
    for _ in 0..40 {
        if sufficient_decrease(pot, ws, state, e, slope, alpha) {
            return (alpha, true);
        }
        alpha *= 0.5;
        rep.line_search_cuts += 1;
    }
    (alpha, false)
}

/// Whether the step of length `alpha` along `ws.step` (set into `ws.trial`) decreases Φ from `e`
/// enough (Armijo, 1e-4 of the slope), within a round-off slack of 1e-13 |Φ|.
fn sufficient_decrease(
    pot: &Potential,
    ws: &mut Workspace,
    state: &State,
    e: Real,
    slope: Real,
    alpha: Real,
) -> bool {
    let slack = 1e-13 * e.abs().max(Real::MIN_POSITIVE);
    ws.trial.set_step(state, &ws.step, alpha);
    let et = pot.eval(&ws.trial.x, &ws.trial.dofs, Want::Energy, &mut [], &mut []);
    et.is_finite()
        && et <= e + 1e-4 * alpha * slope + slack
        && pot.admits(&ws.trial.x, &ws.trial.dofs)
}

/// Minimises `pot` from `state` (updated in place).
pub fn newton(
    pot: &Potential,
    lin: &mut LinearSolver,
    ws: &mut Workspace,
    state: &mut State,
    opts: NewtonOptions,
) -> NewtonReport {
    let mut rep = NewtonReport::default();
    let mut tau_prev: Real = 0.0;
    let mode = opts.projection;
    // Adaptive mode: whether this iteration tries the exact Hessian first. Not the first
    // iteration when the last one tried, in an earlier solve, was rejected; the second does.
    let mut try_exact = !ws.exact_rejected;
    let mut hinted = ws.exact_rejected;
    // Chord iterations: whether the next iteration may reuse the held factorisation, and the
    // residual the last chord iteration started from.
    let mut chord_next = opts.chord;
    let mut chord_from: Option<Real> = None;
    // The residuals before and after the last full Newton step, while they decrease: the next
    // one is predicted as r₁²/r₀, the rate of the last step applied once more, which Newton's
    // superlinear convergence beats (by 2–100× in the walker's contact solves). When that is
    // below twice the tolerance the iteration evaluates the gradient alone first (about 40% of
    // the cost of assembling the Hessian too), and assembles the Hessian only if it is not
    // converged after all: the converged evaluation that ends a solve needs no Hessian.
    let mut last_full: Option<(Real, Real)> = None;
    // The residual at the start of the last iteration, when it took a full exact step.
    let mut full_from: Option<Real> = None;
    // Each solve starts with a factorisation of its own: a step's result then depends on that
    // step alone, and a run restarted from a frame repeats the uninterrupted one exactly.
    ws.chord_model = None;
    loop {
        let mut projected = false;
        let first = match mode {
            HessianProjection::Adaptive if !try_exact => HessianProjection::GaussNewton,
            HessianProjection::Adaptive => HessianProjection::None,
            m => m,
        };
        // A chord iteration is expected when the last one (or a full Newton step) went well and
        // a model is held: it needs no Hessian.
        let expect_chord = chord_next && ws.chord_model.is_some();
        let expect_converged = last_full.is_some_and(|(r0, r1)| r1 * r1 <= 2.0 * opts.tol * r0);
        let gradient_only = expect_chord || expect_converged;
        rep.gradient_only_checks += usize::from(expect_converged && !expect_chord);
        let clock = Instant::now();
        let mut e = pot.eval_projected(
            &state.x,
            &state.dofs,
            if gradient_only {
                Want::Gradient
            } else {
                Want::Hessian
            },
            first,
            &mut ws.grad,
            &mut ws.values,
        );
        rep.timing.assembly += clock.elapsed().as_secs_f64();
        rep.energy = e;
        rep.residual = pot.residual(&ws.grad);
        if !e.is_finite() || !rep.residual.is_finite() {
            rep.failure = Some(SolveError::NonFinite);
            return rep;
        }
        if rep.residual <= opts.tol {
            rep.converged = true;
            if VERBOSE.load(std::sync::atomic::Ordering::Relaxed) {
                eprintln!(
                    "newton {:>3}: energy {e:+.9e} J  residual {}  converged{}",
                    rep.iterations,
                    crate::math::human(rep.residual),
                    if gradient_only { "  (no Hessian)" } else { "" }
                );
            }
            return rep;
        }
        // The limit counts iterations that factorised: a chord iteration halves the residual at
        // least, or is followed by one that factorises. Chord iterations have their own bound,
        // the same limit or 50, whichever is larger.
        let newton_iterations = rep.iterations - rep.chord_iterations;
        if newton_iterations >= opts.max_iter || rep.chord_iterations >= opts.max_iter.max(50) {
            rep.failure = Some(SolveError::NotConverged {
                iterations: rep.iterations,
                residual: rep.residual,
            });
            return rep;
        }
        if !gradient_only && ws.values.iter().any(|v| !v.is_finite()) {
            rep.failure = Some(SolveError::NonFiniteHessian);
            return rep;
        }
        // A chord iteration reuses the held factorisation while the last one contracted the
        // residual enough.
        if let Some(r0) = chord_from.take() {
            chord_next &= rep.residual <= CHORD_CONTRACTION * r0;
        }
        if expect_chord && chord_next {
            let clock = Instant::now();
            ws.step_from_gradient();
            let solved = ws
                .chord_model
                .as_ref()
                .is_some_and(|wb| wb.solve_in_place(lin, &mut ws.step));
            rep.timing.solve += clock.elapsed().as_secs_f64();
            let slope: Real = ws.step.iter().zip(&ws.grad).map(|(d, g)| d * g).sum();
            if solved && slope < 0.0 {
                // Only the full step: a chord step that needs a line search is a sign that the
                // old model no longer fits, and a fresh factorisation is cheaper than the cuts.
                let clock = Instant::now();
                let alpha = pot
                    .step_bound(&state.x, &state.dofs, &ws.step)
                    .fraction
                    .min(1.0);
                let accepted = alpha == 1.0 && sufficient_decrease(pot, ws, state, e, slope, alpha);
                rep.timing.line_search += clock.elapsed().as_secs_f64();
                if VERBOSE.load(std::sync::atomic::Ordering::Relaxed) {
                    eprintln!(
                        "newton {:>3}: energy {:+.9e} J  residual {}  chord  step {:.4}",
                        rep.iterations,
                        e,
                        crate::math::human(rep.residual),
                        alpha,
                    );
                }
                if accepted {
                    (last_full, full_from) = (None, None);
                    rep.iterations += 1;
                    rep.chord_iterations += 1;
                    state.copy_from(&ws.trial);
                    chord_from = Some(rep.residual);
                    chord_next = true;
                    continue;
                }
            }
            // Not a descent direction with the old model, or no decrease along it: this
            // iteration factorises afresh.
        }
        ws.chord_model = None;
        if gradient_only {
            // The Hessian was not assembled for the expected chord iteration or convergence.
            let clock = Instant::now();
            e = pot.eval_projected(
                &state.x,
                &state.dofs,
                Want::Hessian,
                first,
                &mut ws.grad,
                &mut ws.values,
            );
            rep.timing.assembly += clock.elapsed().as_secs_f64();
            if ws.values.iter().any(|v| !v.is_finite()) {
                rep.failure = Some(SolveError::NonFiniteHessian);
                return rep;
            }
        }
        let mut tau0 = if tau_prev > 1e-8 {
            tau_prev * 0.1
        } else {
            tau_prev
        };
        // Dense low-rank Hessian parts (an enclosed gas's stiffness): solved by the Woodbury
        // identity on the sparse factor, never densified.
        let clock = Instant::now();
        let lr = pot.low_rank(&state.x, &state.dofs);
        rep.timing.assembly += clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        let mut model: Option<super::low_rank::Woodbury> = None;
        let mut factored = false;
        if mode == HessianProjection::Adaptive {
            // Exact Hessian, at most with the tiny shift that free rigid-body modes need; with a
            // low-rank part, an indefinite sparse part is accepted when the whole is positive
            // definite (LDLᵀ and the inertia). If it is genuinely indefinite, use the
            // Gauss–Newton Hessian instead.
            let exact = if try_exact {
                ws.step_from_gradient();
                exact_model_from(
                    lin,
                    pot,
                    &ws.values,
                    &mut ws.shifted,
                    &lr,
                    tau0.min(1e-8),
                    ws.indefinite,
                    Some(&mut ws.step),
                )
            } else {
                None
            };
            match exact {
                Some((t, wb)) => {
                    factored = true;
                    tau0 = t;
                    model = Some(wb);
                    ws.exact_rejected = false;
                    ws.indefinite = lin.is_indefinite();
                    if ws.indefinite {
                        rep.indefinite_iterations += 1;
                    }
                }
                None => {
                    if try_exact {
                        // The assembled exact Hessian is indefinite; `first` was already
                        // Gauss–Newton otherwise. With a low-rank part, its sparse part's LDLᵀ
                        // is the last factorisation when that was indefinite too: the next
                        // exact attempt starts there.
                        ws.exact_rejected = true;
                        ws.indefinite = !lr.is_empty() && lin.is_indefinite();
                        let c = Instant::now();
                        pot.eval_projected(
                            &state.x,
                            &state.dofs,
                            Want::Hessian,
                            HessianProjection::GaussNewton,
                            &mut ws.grad,
                            &mut ws.values,
                        );
                        // Assembly, not factorisation.
                        let a = c.elapsed().as_secs_f64();
                        rep.timing.assembly += a;
                        rep.timing.factorisation -= a;
                    }
                    rep.gauss_newton_iterations += 1;
                    projected = true;
                    tau0 = 0.0;
                }
            }
        }
        let tau = if factored {
            tau0
        } else {
            match factor_with_shift(lin, pot, &ws.values, &mut ws.shifted, tau0) {
                Some(t) => t,
                None => {
                    rep.failure = Some(SolveError::Factor);
                    return rep;
                }
            }
        };
        rep.timing.factorisation += clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        tau_prev = tau;
        if tau > 0.0 {
            rep.shifted_iterations += 1;
            rep.max_shift = rep.max_shift.max(tau);
        }
        // The step: `A⁻¹(−g)` was solved with the low-rank vectors (by the accepted exact
        // model, or here), and the low-rank correction finishes it.
        let wb = match model {
            Some(wb) => wb,
            None => {
                ws.step_from_gradient();
                super::low_rank::Woodbury::new_with(lin, &lr, Some(&mut ws.step))
            }
        };
        if opts.chord {
            ws.chord_model = Some(wb.clone());
        }
        if !wb.correct(&mut ws.step) {
            rep.failure = Some(SolveError::LowRankSingular);
            return rep;
        }
        rep.timing.solve += clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        rep.iterations += 1;
        let slope: Real = ws.step.iter().zip(&ws.grad).map(|(d, g)| d * g).sum();
        if slope.is_nan() || slope >= 0.0 {
            rep.failure = Some(SolveError::NotDescent);
            return rep;
        }
        let bound = pot.step_bound(&state.x, &state.dofs, &ws.step);
        if bound.regather {
            rep.timing.line_search += clock.elapsed().as_secs_f64();
            rep.failure = Some(SolveError::Regather);
            return rep;
        }
        let (alpha, accepted) = line_search(pot, ws, state, e, slope, bound.fraction, &mut rep);
        rep.timing.line_search += clock.elapsed().as_secs_f64();
        if VERBOSE.load(std::sync::atomic::Ordering::Relaxed) {
            eprintln!(
                "newton {:>3}: energy {:+.9e} J  residual {}  shift {}  step {:.4}{}{}{}",
                rep.iterations,
                e,
                crate::math::human(rep.residual),
                crate::math::human(tau),
                alpha,
                if bound.fraction < 1.0 {
                    format!("  (bounded to {:.4})", bound.fraction)
                } else {
                    String::new()
                },
                if projected { "  gauss-newton" } else { "" },
                if accepted {
                    ""
                } else {
                    "  (line search stalled)"
                }
            );
        }
        if !accepted {
            rep.failure = Some(SolveError::LineSearchStalled {
                residual: rep.residual,
                slope,
            });
            return rep;
        }
        state.copy_from(&ws.trial);
        if mode == HessianProjection::Adaptive {
            try_exact = !projected || alpha == 1.0 || hinted;
            hinted = false;
        }
        // The first chord iteration after a fresh factorisation needs a full Newton step.
        chord_next = opts.chord && alpha == 1.0;
        let full_exact = alpha == 1.0 && !projected;
        last_full = match full_from {
            Some(r0) if full_exact && rep.residual < r0 => Some((r0, rep.residual)),
            _ => None,
        };
        full_from = full_exact.then_some(rep.residual);
    }
}
