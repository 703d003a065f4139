//! The arc-length driver: statics with the dial (the load factor) as an unknown beside the
//! positions, Crisfield's spherical arc-length method, so that the equilibrium path is followed
//! through limit points of the load (snap-through, snap-back, a balloon's pressure maximum).
//!
//! **Unknowns and constraint.** The free DOFs `u` and the dial `λ`: every load, prescribed
//! path, gas pressure or amount and rest form follows `λ` exactly as under load control.
//! Equilibrium is `g(u, λ) = ∂Φ/∂u = 0`; each step adds the constraint
//!
//! `‖W Δu‖² / ψ² + Δλ² = Δs²`
//!
//! on the increment from the last converged point. `W` weighs each DOF into metres (1 on a
//! position, the mean edge length on an edge rotation, a global DOF's declared length on it),
//! and `ψ = ‖W t₀‖` is the first tangent's displacement per unit dial, `t₀ = −H⁻¹ ∂g/∂λ` at the
//! start. So the path coordinate `s` is in dial units: a linear response advances the dial by
//! `Δs/√2` per step.
//!
//! **Predictor.** The first step follows the tangent `t₀` (increasing the dial); every later
//! one the previous converged increment (the secant), scaled to the step length. The secant
//! keeps the direction of travel through a limit point, and through a bifurcation point
//! (where the tangent `−H⁻¹ ∂g/∂λ` is unbounded, in the direction of the buckling mode) it
//! stays on the path it came along.
//!
//! **Corrector** (M. A. Crisfield, "A fast incremental/iterative solution procedure that
//! handles snap-through", Computers & Structures 13 (1981) 55–62). Each iteration solves
//! `H a = −g` and `H b = −∂g/∂λ` with one factorisation and takes `δu = a + δλ b`, `δλ` the
//! root of the constraint's quadratic whose increment makes the smaller angle with the current
//! one (when the quadratic has no real root, its vertex). `H` is the exact Hessian: Cholesky
//! while it is positive definite, LDLᵀ beyond (whose inertia counts the negative eigenvalues),
//! with dense low-rank parts through the Woodbury identity. `∂g/∂λ` is a central difference in
//! `λ` (step 1e-6; exact for the loads, which are linear in `λ`). Converged when
//! `‖∇Φ‖∞ ≤ tolerance × F`, as every static solve.
//!
//! **Step.** After a converged step `Δs ← Δs √(5 / iterations)`, within `[Δs/2, 2Δs]` and at
//! most `solver.max_arc_length_step`; after a failed one it is halved, and the run stops below
//! `solver.min_continuation_step`.
//!
//! **Landing.** A step that crosses a hold of `dial.holds`, dial 1, or (going down) dial 0 is
//! replaced by the equilibrium at that dial, solved by the same Newton with `λ` fixed from the
//! linear interpolation of the step. The run ends at dial 1, back at dial 0, or after
//! `solver.max_arc_length_steps` steps.
//!
//! **Critical points.** A sign change of `dλ/ds` (the tangent's dial component, oriented along
//! the path) is a limit point: its dial and arc length are the extremum of the cubic Hermite
//! interpolant of `λ(s)` from the values and slopes at the two converged points around it. A change in
//! the number of negative eigenvalues without one is a bifurcation point (reported between the
//! two steps that bracket it). Both go to `log.csv` (`critical_point`) and `summary.json`.

use super::report::{ArcLengthReport, CriticalPoint};
use super::{interruption, DriverState, Progress, RunError, RunFailure, Sink, Solver};
use crate::assembly::Want;
use crate::math::{human, Real, Vec3};
use crate::model::Scene;
use crate::solve::low_rank::Woodbury;
use crate::solve::{NewtonReport, SolveError, State};
use std::time::Instant;

/// Crisfield's desired number of corrector iterations per step.
const DESIRED_ITERATIONS: Real = 5.0;

/// The dial step of the central difference `∂g/∂λ`.
const DIAL_EPS: Real = 1e-6;

/// What a step's corrector keeps at its converged point: the tangent `−H⁻¹ ∂g/∂λ` there (the
/// next predictor) and the number of negative eigenvalues of `H`.
struct AtPoint {
    tangent: Vec<Real>,
    negative: usize,
}

/// The constraint of a corrector.
#[derive(Clone, Copy)]
enum Constraint {
    /// `‖W Δu‖²/ψ² + Δλ² = Δs²` from the base point.
    Sphere { ds: Real, psi: Real },
    /// `λ` fixed (a landing).
    Dial,
}

/// The DOF weights `W` (module doc), zero on the held vertices and pinned DOFs.
fn weights(s: &Solver) -> Vec<Real> {
    let pat = s.pattern();
    let body = &s.scene.body;
    let nx = 3 * pat.num_vertices;
    let ne = nx + body.num_edge_dofs();
    let mut w = vec![1.0; pat.n];
    w[nx..ne].fill(body.mean_edge);
    for (k, g) in s.scene.globals.iter().enumerate() {
        w[ne + k] = g.length;
    }
    s.potential(&pat, 0.0).mask_fixed(&mut w);
    // A skew vertex keeps its weights: the vectors weighed are already projected onto its free
    // directions, and the projection of the weights themselves is no mask.
    for sk in &body.skew {
        w[3 * sk.vertex..3 * sk.vertex + 3].fill(1.0);
    }
    w
}

/// `Σ wᵢ² aᵢ bᵢ`.
fn wdot(w: &[Real], a: &[Real], b: &[Real]) -> Real {
    w.iter()
        .zip(a.iter().zip(b))
        .map(|(w, (a, b))| w * w * a * b)
        .sum()
}

/// `a − b` as a DOF vector (vertex xyz, then the scalar DOFs).
fn difference(a: &State, b: &State, out: &mut [Real]) {
    for (v, (p, q)) in a.x.iter().zip(&b.x).enumerate() {
        for k in 0..3 {
            out[3 * v + k] = p[k] - q[k];
        }
    }
    let off = 3 * a.x.len();
    for (k, (p, q)) in a.dofs.iter().zip(&b.dofs).enumerate() {
        out[off + k] = p - q;
    }
}

/// `state += α d` (`d` in DOF order), term states unchanged.
fn add(state: &mut State, d: &[Real], alpha: Real) {
    for (v, p) in state.x.iter_mut().enumerate() {
        *p += Vec3::new(d[3 * v], d[3 * v + 1], d[3 * v + 2]) * alpha;
    }
    let off = 3 * state.x.len();
    for (k, p) in state.dofs.iter_mut().enumerate() {
        *p += d[off + k] * alpha;
    }
}

/// `∂g/∂λ` at `(state, λ)` by a central difference, the prescribed paths moved with the dial;
/// zero on the DOFs the solver does not move.
fn dial_derivative(s: &Solver, lambda: Real, state: &State, out: &mut [Real]) {
    let pat = s.pattern();
    let mut x = state.x.clone();
    let mut lo = vec![0.0; out.len()];
    let (a, b) = (lambda - DIAL_EPS, lambda + DIAL_EPS);
    s.scene.body.prescribe(&mut x, b);
    s.potential_at(&pat, b, state)
        .eval(&x, &state.dofs, Want::Gradient, out, &mut []);
    s.scene.body.prescribe(&mut x, a);
    let pot = s.potential_at(&pat, a, state);
    pot.eval(&x, &state.dofs, Want::Gradient, &mut lo, &mut []);
    for (o, l) in out.iter_mut().zip(&lo) {
        *o = (*o - l) / (b - a);
    }
    pot.mask_fixed(out);
}

/// Factorises the exact Hessian `values` at `(state, λ)` with its low-rank parts: Cholesky when
/// it is positive definite, LDLᵀ otherwise. `None` when it is singular (or LDLᵀ without
/// pivoting breaks down).
fn factor(
    s: &mut Solver,
    lambda: Real,
    state: &State,
    values: &[Real],
) -> Option<(Woodbury, usize)> {
    let pat = s.pattern();
    let lr = s
        .potential_at(&pat, lambda, state)
        .low_rank(&state.x, &state.dofs);
    let negative = match s.lin.factor(values) {
        Ok(()) => 0,
        Err(_) => s.lin.factor_indefinite(values).ok()?,
    };
    let wb = Woodbury::new(&mut s.lin, &lr);
    let negative = wb.negative_eigenvalues(negative)?;
    Some((wb, negative))
}

/// Newton on the bordered system from `(trial, λ)` with `constraint` on the increment from
/// `(base, base_λ)`; on success `trial` and `λ` hold the converged point.
#[allow(clippy::too_many_arguments)]
fn correct(
    s: &mut Solver,
    w: &[Real],
    base: &State,
    base_lambda: Real,
    trial: &mut State,
    lambda: &mut Real,
    constraint: Constraint,
) -> Result<(NewtonReport, Option<AtPoint>), RunError> {
    let n = s.pattern.n;
    let opts = s.config.newton;
    let mut rep = NewtonReport::default();
    let mut g = vec![0.0; n];
    let mut values = vec![0.0; s.pattern.nnz()];
    let mut a = vec![0.0; n];
    let mut b = vec![0.0; n];
    let mut d = vec![0.0; n];
    let result = loop {
        let clock = Instant::now();
        let pat = s.pattern();
        if values.len() != pat.nnz() {
            values = vec![0.0; pat.nnz()];
        }
        let pot = s.potential_at(&pat, *lambda, trial);
        rep.energy = pot.eval(&trial.x, &trial.dofs, Want::Hessian, &mut g, &mut values);
        rep.residual = pot.residual(&g);
        dial_derivative(s, *lambda, trial, &mut b);
        rep.timing.assembly += clock.elapsed().as_secs_f64();
        if !rep.energy.is_finite()
            || !rep.residual.is_finite()
            || values.iter().chain(&b).any(|v| !v.is_finite())
        {
            break Err(SolveError::NonFinite);
        }
        let clock = Instant::now();
        let Some((wb, negative)) = factor(s, *lambda, trial, &values) else {
            break Err(SolveError::Factor);
        };
        rep.timing.factorisation += clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        for v in b.iter_mut() {
            *v = -*v;
        }
        if !wb.solve_in_place(&mut s.lin, &mut b) {
            break Err(SolveError::LowRankSingular);
        }
        if rep.residual <= opts.tol {
            rep.timing.solve += clock.elapsed().as_secs_f64();
            break Ok(AtPoint {
                tangent: b.clone(),
                negative,
            });
        }
        if rep.iterations >= opts.max_iter {
            break Err(SolveError::NotConverged {
                iterations: opts.max_iter,
                residual: rep.residual,
            });
        }
        for (a, g) in a.iter_mut().zip(&g) {
            *a = -g;
        }
        if !wb.solve_in_place(&mut s.lin, &mut a) {
            break Err(SolveError::LowRankSingular);
        }
        rep.timing.solve += clock.elapsed().as_secs_f64();
        let dl = match constraint {
            Constraint::Dial => 0.0,
            Constraint::Sphere { ds, psi } => {
                difference(trial, base, &mut d);
                let dlam = *lambda - base_lambda;
                let p2 = psi * psi;
                let dp: Vec<Real> = d.iter().zip(&a).map(|(d, a)| d + a).collect();
                let qa = wdot(w, &b, &b) / p2 + 1.0;
                let qb = 2.0 * (wdot(w, &dp, &b) / p2 + dlam);
                let qc = wdot(w, &dp, &dp) / p2 + dlam * dlam - ds * ds;
                let disc = qb * qb - 4.0 * qa * qc;
                if disc < 0.0 {
                    -qb / (2.0 * qa)
                } else {
                    // The two roots without cancellation; the one whose increment turns
                    // least from the current one.
                    let q = -0.5 * (qb + qb.signum() * disc.sqrt());
                    let r1 = q / qa;
                    let r2 = if q != 0.0 { qc / q } else { r1 };
                    let (ddb, dd) = (wdot(w, &d, &b), wdot(w, &d, &dp));
                    let cos = |r: Real| (dd + r * ddb) / p2 + dlam * (dlam + r);
                    if cos(r1) >= cos(r2) {
                        r1
                    } else {
                        r2
                    }
                }
            }
        };
        add(trial, &a, 1.0);
        add(trial, &b, dl);
        *lambda += dl;
        s.scene.body.prescribe(&mut trial.x, *lambda);
        rep.iterations += 1;
        s.refresh(trial, *lambda)?;
    };
    s.record(&rep);
    Ok(match result {
        Ok(at) => {
            rep.converged = true;
            (rep, Some(at))
        }
        Err(e) => {
            rep.failure = Some(e);
            (rep, None)
        }
    })
}

/// The extremum `(s*, λ*)` of the cubic Hermite interpolant of `λ(s)` between two points
/// `(s, λ, dλ/ds)` whose slopes differ in sign (a limit point between them); `None` when they
/// do not.
fn hermite_extremum(p0: (Real, Real, Real), p1: (Real, Real, Real)) -> Option<(Real, Real)> {
    let ((s0, y0, m0), (s1, y1, m1)) = (p0, p1);
    let h = s1 - s0;
    if h.is_nan() || h <= 0.0 || m0 * m1 > 0.0 {
        return None;
    }
    // dy/dτ = A τ² + B τ + C on τ ∈ [0, 1].
    let qa = 6.0 * (y0 - y1) + 3.0 * h * (m0 + m1);
    let qb = 6.0 * (y1 - y0) - h * (4.0 * m0 + 2.0 * m1);
    let qc = h * m0;
    let roots = if qa.abs() <= 1e-14 * (qb.abs() + qc.abs()) {
        vec![-qc / qb]
    } else {
        let disc = (qb * qb - 4.0 * qa * qc).max(0.0).sqrt();
        vec![(-qb - disc) / (2.0 * qa), (-qb + disc) / (2.0 * qa)]
    };
    let t = roots
        .into_iter()
        .filter(|t| t.is_finite() && (0.0..=1.0).contains(t))
        .min_by(|a, b| (a - 0.5).abs().total_cmp(&(b - 0.5).abs()))?;
    let (t2, t3) = (t * t, t * t * t);
    let y = (2.0 * t3 - 3.0 * t2 + 1.0) * y0
        + (t3 - 2.0 * t2 + t) * h * m0
        + (-2.0 * t3 + 3.0 * t2) * y1
        + (t3 - t2) * h * m1;
    Some((s0 + t * h, y))
}

/// Refuses an arc-length scene that it cannot control (exit 2, naming `solver.continuation` in
/// the settings file `settings_name`): a prescribed gas volume (a multiplier, already a path
/// control of its own), or a scene where nothing depends on the dial.
pub fn check(scene: &Scene, settings_name: &str) -> Result<(), crate::settings::SettingsError> {
    if scene.settings.solver.continuation != crate::settings::Continuation::ArcLength {
        return Ok(());
    }
    let invalid = |reason: &str| crate::settings::SettingsError::Invalid {
        path: settings_name.to_string(),
        key: "solver.continuation".into(),
        reason: reason.to_string(),
    };
    if scene.terms.iter().any(|t| t.updates().is_some()) {
        return Err(invalid(
            "\"arc_length\" controls the load factor; a prescribed gas volume (gas.control = \
             \"volume\") is a path control of its own and already passes the pressure's \
             limit points. Use gas.control = \"pressure\" or \"amount\" with arc length, or \
             load control with the volume",
        ));
    }
    if scene.terms.iter().any(|t| t.step_limit().is_some()) {
        let key = match scene
            .settings
            .obstacles
            .iter()
            .position(|o| o.shape == Some(crate::config::obstacle::ShapeKind::Mesh))
        {
            Some(i) if !scene.settings.self_contact.enabled => format!("obstacles[{i}].shape"),
            _ => "self_contact.enabled".into(),
        };
        return Err(crate::settings::SettingsError::Invalid {
            path: settings_name.to_string(),
            key,
            reason: "self-contact and mesh obstacles bound every Newton step by continuous \
                     collision detection; \"arc_length\" corrects along the path with steps \
                     that are not bounded, and the dial is an unknown of its solve. Use \
                     solver.continuation = \"load\" or an analytic shape"
                .into(),
        });
    }
    // ∂g/∂λ at the reference state, at mid-dial: zero when nothing follows the dial.
    let pattern = crate::assembly::Pattern::for_scene(scene);
    let n = pattern.n;
    let state = State::reference(scene);
    let grad = |dial: Real| {
        let (x, pot) = super::statics::reference_potential(scene, &pattern, &state, dial);
        let mut g = vec![0.0; n];
        pot.eval(&x, &state.dofs, Want::Gradient, &mut g, &mut []);
        pot.mask_fixed(&mut g);
        g
    };
    if grad(0.25) == grad(0.75) {
        return Err(invalid(
            "\"arc_length\" controls the dial, and nothing in this scene depends on it: no \
             load, prescribed displacement, gas pressure or amount, moving obstacle or \
             changing rest form. Add what the path should follow",
        ));
    }
    Ok(())
}

/// Runs the arc-length continuation (module doc) from `state` (the perturbed start), or from a
/// restart at dial `restart` with its driver's state `driver`.
pub(super) fn run_arc_length(
    s: &mut Solver,
    writer: &mut dyn Sink,
    progress: &mut dyn Progress,
    mut state: State,
    restart: Option<Real>,
    driver: Option<DriverState>,
) -> Result<(), RunError> {
    let st = s.scene.settings.solver.clone();
    let holds = s.scene.settings.dial.holds.clone();
    let zeros = vec![Vec3::zeros(); state.x.len()];
    let mut lambda = restart.unwrap_or(0.0);
    let resumed = driver.map(|d| d.arc_length).unwrap_or_default();
    let resume = |k: &str| resumed.get(k).copied().filter(|v| v.is_finite());
    let mut arc = resume("arc_length").unwrap_or(0.0);
    let mut report = ArcLengthReport {
        length: arc,
        ..Default::default()
    };
    let w = weights(s);
    let n = s.pattern.n;
    // The start: its tangent, ψ and inertia (from the last converged point of a restart).
    s.scene.body.prescribe(&mut state.x, lambda);
    let at = {
        let pat = s.pattern();
        let pot = s.potential_at(&pat, lambda, &state);
        let mut g = vec![0.0; n];
        let mut values = vec![0.0; pat.nnz()];
        pot.eval(&state.x, &state.dofs, Want::Hessian, &mut g, &mut values);
        let mut t = vec![0.0; n];
        dial_derivative(s, lambda, &state, &mut t);
        let f = factor(s, lambda, &state, &values);
        f.and_then(|(wb, negative)| {
            for v in t.iter_mut() {
                *v = -*v;
            }
            (wb.solve_in_place(&mut s.lin, &mut t) && t.iter().all(|v| v.is_finite())).then_some(
                AtPoint {
                    tangent: t,
                    negative,
                },
            )
        })
    };
    {
        let pat = s.pattern();
        let pot = s.potential(&pat, lambda);
        s.driver = driver_state(lambda, arc, Real::NAN, 0.0, 0.0, 0);
        s.path_columns = path_columns(arc, at.as_ref().map_or(0, |a| a.negative), 0.0);
        s.frame(writer, &pot, &state, &zeros, arc)?;
    }
    let Some(mut at) = at else {
        return finish(
            s,
            &state,
            lambda,
            report,
            Some(RunFailure::ArcLengthStart(
                "the Hessian at the start is singular: a support leaves the sheet free to move \
                 as a rigid body, or to swing about a line of held vertices. Hold enough \
                 components that no rigid motion is left (see [[constraints.support]])"
                    .into(),
            )),
        );
    };
    let psi = resume("psi").unwrap_or_else(|| wdot(&w, &at.tangent, &at.tangent).sqrt());
    if !(psi.is_finite() && psi > 0.0) {
        return finish(
            s,
            &state,
            lambda,
            report,
            Some(RunFailure::ArcLengthStart(
                "the dial moves no free DOF at the start (the tangent ∂u/∂λ is zero): the \
                 loads act only on held vertices"
                    .into(),
            )),
        );
    }
    report.psi = psi;
    let min_step = st.min_continuation_step;
    let mut ds = resume("step")
        .unwrap_or(st.arc_length_step)
        .min(st.max_arc_length_step);
    // The previous converged increment (displacement, Δλ); a restart keeps only the sign of
    // dλ/ds where it stopped.
    let mut previous: Option<(Vec<Real>, Real)> = None;
    let restart_direction = resume("direction").unwrap_or(1.0);
    // The sign of dλ/ds at the last converged point.
    let mut rising = restart_direction.signum();
    // The last converged point's (s, λ, dλ/ds), dλ/ds = ±1/√(‖W t‖²/ψ² + 1).
    let slope = |t: &[Real], sign: Real| sign / (wdot(&w, t, t) / (psi * psi) + 1.0).sqrt();
    let mut last = (arc, lambda, slope(&at.tangent, rising));
    let mut steps = 0usize;
    let mut trial = state.clone();
    let mut inc = vec![0.0; n];
    let mut failure = None;
    // A restart at dial 1: the end itself, solved again with these settings.
    if lambda >= 1.0 {
        let mut l1 = 1.0;
        trial.copy_from(&state);
        s.scene.body.prescribe(&mut trial.x, l1);
        let (rep, got) = correct(s, &w, &state, lambda, &mut trial, &mut l1, Constraint::Dial)?;
        match got {
            Some(next) => {
                state.copy_from(&trial);
                at = next;
                let pat = s.pattern();
                let pot = s.potential(&pat, 1.0);
                s.driver = driver_state(1.0, arc, psi, ds, rising, at.negative);
                s.path_columns = path_columns(arc, at.negative, 0.0);
                s.frame(writer, &pot, &state, &zeros, arc)?;
                report.end = "dial 1".into();
            }
            None => {
                report.end = "failed".into();
                failure = Some(RunFailure::ArcLengthStep {
                    min: min_step,
                    dial: lambda,
                    arc_length: arc,
                    cause: rep.failure_or_unknown(),
                    tolerance: s.config.newton.tol,
                    force_scale: s.force_scale,
                });
            }
        }
        report.length = arc;
        report.negative_eigenvalues = at.negative;
        return finish(s, &state, 1.0, report, failure);
    }
    let end = loop {
        if let Some(f) = interruption("dial", lambda) {
            failure = Some(f);
            break None;
        }
        if steps >= st.max_arc_length_steps {
            break Some("steps");
        }
        // Predictor: along the previous increment (the secant), or at the start along the
        // tangent; scaled to the step length.
        let (dir, dl_dir) = match &previous {
            Some((du, dl)) => (du, *dl),
            None => {
                let sign = restart_direction.signum();
                for v in at.tangent.iter_mut() {
                    *v *= sign;
                }
                (&at.tangent, sign)
            }
        };
        let len = (wdot(&w, dir, dir) / (psi * psi) + dl_dir * dl_dir).sqrt();
        let alpha = ds / len;
        let dl = alpha * dl_dir;
        trial.copy_from(&state);
        add(&mut trial, dir, alpha);
        let mut lt = lambda + dl;
        s.scene.body.prescribe(&mut trial.x, lt);
        s.refresh(&trial, lt)?;
        let (rep, got) = correct(
            s,
            &w,
            &state,
            lambda,
            &mut trial,
            &mut lt,
            Constraint::Sphere { ds, psi },
        )?;
        let mut iterations = rep.iterations;
        let mut got = got.filter(|_| super::hooks::admissible(s.scene, &trial));
        let mut cause = rep.failure_or_unknown();
        // Landing on a hold, dial 1, or dial 0 on the way down.
        if got.is_some() {
            let up = lt > lambda;
            let crossed = holds
                .iter()
                .copied()
                .chain([1.0])
                .chain((!up).then_some(0.0))
                .filter(|&h| {
                    if up {
                        h > lambda && h <= lt
                    } else {
                        h < lambda && h >= lt
                    }
                })
                .min_by(|a, b| (a - lambda).abs().total_cmp(&(b - lambda).abs()));
            if let Some(h) = crossed.filter(|&h| h != lt) {
                let frac = (h - lambda) / (lt - lambda);
                difference(&trial, &state, &mut inc);
                trial.copy_from(&state);
                add(&mut trial, &inc, frac);
                let mut lh = h;
                s.scene.body.prescribe(&mut trial.x, lh);
                s.refresh(&trial, lh)?;
                let (rep, landed) =
                    correct(s, &w, &state, lambda, &mut trial, &mut lh, Constraint::Dial)?;
                iterations += rep.iterations;
                cause = rep.failure_or_unknown();
                got = landed.filter(|_| super::hooks::admissible(s.scene, &trial));
                lt = h;
            }
        }
        let Some(next) = got else {
            s.summary.rejected_steps += 1;
            ds *= 0.5;
            if ds < min_step {
                failure = Some(RunFailure::ArcLengthStep {
                    min: min_step,
                    dial: lambda,
                    arc_length: arc,
                    cause,
                    tolerance: s.config.newton.tol,
                    force_scale: s.force_scale,
                });
                break None;
            }
            continue;
        };
        // Accepted.
        difference(&trial, &state, &mut inc);
        let dlam = lt - lambda;
        let taken = (wdot(&w, &inc, &inc) / (psi * psi) + dlam * dlam).sqrt();
        arc += taken;
        state.copy_from(&trial);
        super::hooks::accept(s.scene, &mut state);
        steps += 1;
        s.summary.steps += 1;
        let frame = writer.num_frames();
        let mut code = 0.0;
        // The sign of dλ/ds at the new point: the path's tangent (t, 1), oriented along the
        // step just taken. A limit point lies where it changes; the inertia changes there too,
        // and where it changes without one, an eigenvalue crossed zero on a path that goes on
        // rising or falling: a bifurcation point.
        let rising_next = if wdot(&w, &next.tangent, &inc) / (psi * psi) + dlam >= 0.0 {
            1.0
        } else {
            -1.0
        };
        let limit = rising_next != rising;
        if limit {
            let here = (arc, lt, slope(&next.tangent, rising_next));
            let (sx, lx) = hermite_extremum(last, here).unwrap_or(if rising > 0.0 {
                if last.1 >= lt {
                    (last.0, last.1)
                } else {
                    (arc, lt)
                }
            } else if last.1 <= lt {
                (last.0, last.1)
            } else {
                (arc, lt)
            });
            let maximum = rising > 0.0;
            code = if maximum { 1.0 } else { -1.0 };
            report.critical_points.push(CriticalPoint {
                kind: if maximum {
                    "load_maximum"
                } else {
                    "load_minimum"
                }
                .into(),
                dial: lx,
                arc_length: sx,
                frame,
                negative_eigenvalues: next.negative,
            });
        }
        if next.negative.abs_diff(at.negative) > usize::from(limit) {
            code = 2.0;
            report.critical_points.push(CriticalPoint {
                kind: "bifurcation".into(),
                dial: 0.5 * (lambda + lt),
                arc_length: arc - 0.5 * taken,
                frame,
                negative_eigenvalues: next.negative,
            });
        }
        rising = rising_next;
        last = (arc, lt, slope(&next.tangent, rising_next));
        previous = Some((inc.clone(), dlam));
        lambda = lt;
        at = next;
        ds = (ds * (DESIRED_ITERATIONS / iterations.max(1) as Real).sqrt())
            .clamp(0.5 * ds, 2.0 * ds)
            .min(st.max_arc_length_step);
        progress.update(
            lambda.clamp(0.0, 1.0),
            &format!(
                "arc length {}  dial {}  step {}  negative eigenvalues {}",
                human(arc),
                human(lambda),
                human(taken),
                at.negative
            ),
        );
        let pat = s.pattern();
        let pot = s.potential(&pat, lambda);
        s.driver = driver_state(lambda, arc, psi, ds, rising, at.negative);
        s.path_columns = path_columns(arc, at.negative, code);
        s.frame(writer, &pot, &state, &zeros, arc)?;
        if lambda == 1.0 {
            break Some("dial 1");
        }
        if lambda == 0.0 && dlam < 0.0 {
            break Some("unloaded");
        }
    };
    report.steps = steps;
    report.length = arc;
    report.negative_eigenvalues = at.negative;
    report.end = end.unwrap_or("failed").into();
    finish(s, &state, lambda, report, failure)
}

/// The summary of an arc-length run (its frames are written: every accepted step's).
fn finish(
    s: &mut Solver,
    state: &State,
    lambda: Real,
    report: ArcLengthReport,
    failure: Option<RunFailure>,
) -> Result<(), RunError> {
    s.summary.dial = lambda;
    s.summary.converged = failure.is_none();
    s.summary.reason = failure.map(|f| f.to_string()).unwrap_or_default();
    let pat = s.pattern();
    let pot = s.potential(&pat, lambda);
    let zeros = vec![Vec3::zeros(); state.x.len()];
    s.summary.energy = super::report::energies(&pot, state, &zeros);
    s.summary.arc_length = Some(report);
    Ok(())
}

/// The driver state an arc-length frame records (`arc_length`: its path coordinate, ψ, the
/// next step and the sign of dλ/ds there).
fn driver_state(
    lambda: Real,
    arc: Real,
    psi: Real,
    step: Real,
    rising: Real,
    negative: usize,
) -> DriverState {
    let mut m = std::collections::BTreeMap::new();
    m.insert("arc_length".to_string(), arc);
    if psi.is_finite() {
        m.insert("psi".into(), psi);
        m.insert("step".into(), step);
        m.insert("direction".into(), rising);
        m.insert("negative_eigenvalues".into(), negative as Real);
    }
    DriverState {
        time: arc,
        dial: lambda,
        arc_length: m,
        ..Default::default()
    }
}

/// `log.csv`'s columns of an arc-length frame.
fn path_columns(arc: Real, negative: usize, code: Real) -> Vec<(String, Real)> {
    vec![
        ("arc_length".into(), arc),
        ("negative_eigenvalues".into(), negative as Real),
        ("critical_point".into(), code),
    ]
}

#[cfg(test)]
mod tests {
    use super::hermite_extremum;

    #[test]
    fn the_hermite_extremum_is_exact_for_a_cubic() {
        // λ(s) = 1 − (s − 0.3)² + 0.5 (s − 0.3)³: maximum at s = 0.3 on [0, 1].
        let f = |s: f64| 1.0 - (s - 0.3).powi(2) + 0.5 * (s - 0.3).powi(3);
        let df = |s: f64| -2.0 * (s - 0.3) + 1.5 * (s - 0.3).powi(2);
        let (s, l) = hermite_extremum((0.0, f(0.0), df(0.0)), (1.0, f(1.0), df(1.0))).unwrap();
        assert!(
            (s - 0.3).abs() < 1e-12 && (l - 1.0).abs() < 1e-12,
            "{s} {l}"
        );
        // A minimum, and slopes of one sign (no extremum between).
        let (s, _) = hermite_extremum((0.0, 1.0, -1.0), (2.0, 1.0, 1.0)).unwrap();
        assert!((s - 1.0).abs() < 1e-12, "{s}");
        assert!(hermite_extremum((0.0, 0.0, 1.0), (1.0, 1.0, 0.5)).is_none());
    }
}
