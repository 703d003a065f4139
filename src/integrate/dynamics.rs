//! The dynamic driver: implicit Euler (seed 000 §3) with adaptive time steps, output timing and
//! the equilibrium stop; the moisture sub-step ([`super::moisture`]) and the friction lag
//! ([`super::friction`]) are their own modules.

use super::friction::FrictionLag;
use super::transport::{accepted, Field, Targets, Transport};
use super::Sink;
use super::{OutputClock, Progress, RunError, RunFailure, Solver, StepControl};
use crate::assembly::Want;
use crate::energy::potential::{Damping, Inertia};
use crate::energy::Potential;
use crate::math::{Real, Vec3};
use crate::solve::State;
use std::time::Instant;

pub(super) fn run_dynamic(
    s: &mut Solver,
    writer: &mut dyn Sink,
    progress: &mut dyn Progress,
    mut state: State,
    from: super::Resume,
) -> Result<(), RunError> {
    let super::Resume {
        v: v0,
        t0,
        dial: dial0,
        driver,
    } = from;
    let sc = s.scene;
    // A restart with the driver's state resumes at its exact time (series.pvd rounds it).
    if let Some(d) = &driver {
        if (d.time - t0).abs() > 1e-9 * t0.abs().max(s.config.dynamics.time.end) {
            return Err(RunError::Restart(format!(
                "the frame's state is at t = {} s, its series.pvd entry at {} s: they belong \
                 to different frames",
                crate::math::human(d.time),
                crate::math::human(t0)
            )));
        }
    }
    let t0 = driver.as_ref().map_or(t0, |d| d.time);
    let cf = s.config.dynamics.clone();
    let tm = &cf.time;
    let opts = s.config.newton;
    let tol = opts.tol;
    let dial_time = cf.dial_time;
    let dial_at = |t: Real| {
        if dial_time > 0.0 {
            (t / dial_time).min(1.0)
        } else {
            1.0
        }
    };
    // The dial advances linearly in time, except that it stops at each hold until the
    // equilibrium test passes (a restart resumes the linear dial at its time; holds already
    // passed stay passed).
    let holds = sc.settings.dial.holds.clone();
    let mut dial_now = dial0.unwrap_or_else(|| dial_at(t0));
    let mut next_hold = holds.iter().position(|&h| h > dial_now);
    let mut holding = false;
    if dial_time == 0.0 {
        if let Some(k) = next_hold {
            dial_now = holds[k];
            holding = true;
        }
    }
    let mut holds_reached = 0usize;
    if let Some(d) = &driver {
        dial_now = d.dial;
        holding = d.holding;
        next_hold = d.next_hold.filter(|&k| k < holds.len());
        holds_reached = d.holds_reached;
    }
    let n = state.x.len();
    let mut v = v0.unwrap_or_else(|| vec![Vec3::zeros(); n]);
    let mut xhat = state.x.clone();
    // The global DOFs (after the edge DOFs) have inertia too: their velocities and prediction.
    let ne = sc.body.num_edge_dofs();
    let mut w = vec![0.0; sc.globals.len()];
    if let Some(d) = driver
        .as_ref()
        .filter(|d| d.global_velocities.len() == w.len())
    {
        w.copy_from_slice(&d.global_velocities);
    }
    let mut dofs_hat = state.dofs.clone();
    // The last step's change of velocity per unit time (vertices, then global DOFs): with a
    // fixed time step, Newton starts from x + h v + h² a, the positions' quadratic
    // extrapolation, instead of the inertial prediction x + h v (equal to it before the first
    // step). Not with an adaptive step, which grows after steps that took few Newton
    // iterations: a better start would let it grow past the accuracy it keeps now.
    let mut acc = vec![0.0; 3 * n + w.len()];
    if let Some(a) = driver.as_ref().and_then(|d| d.acceleration.as_ref()) {
        if a.len() != acc.len() || a.iter().any(|c| !c.is_finite()) {
            return Err(RunError::Restart(
                "the frame's state has an acceleration of the wrong length or not finite".into(),
            ));
        }
        acc.copy_from_slice(a);
    }
    let mut trial = state.clone();
    let damping = tm.damping > 0.0;
    let (mut a_prev, mut b_prev) = if damping {
        sc.body.forms(&state.x, &state.dofs)
    } else {
        (Vec::new(), Vec::new())
    };
    // Moisture or temperature: the diffusion state and the rest forms it sets (None without
    // a coupled field).
    let mut moisture = Transport::new(sc)?;
    let mut targets = Targets::default();
    let mut trial_targets = Targets::default();
    if let (Some(m), Some(d)) = (&mut moisture, &driver) {
        m.resume(sc, d).map_err(RunError::Restart)?;
    }
    if let Some(m) = &moisture {
        targets = m.targets_of(sc, false)?;
        m.publish(writer);
    }
    // Halved on failure, ×1.5 after 3 easy steps (≤ 3 Newton iterations).
    let mut steps = StepControl::new(tm.dt, tm.dt_min, tm.dt_max, 1.5, 3, 3);
    if let Some(d) = &driver {
        steps.resume(d.step, d.easy_steps);
    }
    // What a frame's state file records at time `t` (see `DriverState`).
    macro_rules! record {
        ($t:expr) => {
            super::DriverState {
                time: $t,
                dial: dial_now,
                step: Some(steps.step),
                easy_steps: steps.easy(),
                holding,
                next_hold,
                holds_reached,
                moisture: moisture
                    .as_ref()
                    .filter(|m| m.field == Field::Moisture)
                    .map(|m| m.u.clone()),
                temperature: moisture
                    .as_ref()
                    .filter(|m| m.field == Field::Temperature)
                    .map(|m| m.u.clone()),
                temperature_max: moisture
                    .as_ref()
                    .filter(|m| m.field == Field::Temperature)
                    .map(|m| m.peak.clone()),
                diffusion_substep: moisture.as_ref().map(|m| m.diffusion.next_substep()),
                global_velocities: w.clone(),
                acceleration: Some(acc.clone()),
                ..Default::default()
            }
        };
    }
    {
        // The first frame's contact pairs, where it is.
        s.refresh(&state, dial_now)?;
        let pat = s.pattern();
        let pot = accepted(s.potential(&pat, dial_now), moisture.as_ref(), &targets);
        s.driver = record!(t0);
        s.path_columns = m_columns(moisture.as_ref(), sc);
        s.frame(writer, &pot, &state, &v, t0)?;
    }
    // Friction: the lagged normal forces, carried from step to step.
    let obstacles = !sc.settings.obstacles.is_empty();
    // With a fixed step and no obstacle, Newton starts from the extrapolation (see `acc`).
    let extrapolate = tm.dt_max <= tm.dt && !obstacles;
    let mut lag = FrictionLag::new(sc, &state.x, dial_now, cf.slip_speed);
    // With friction, the last accepted step (its start, its start's dial, its length): frames
    // report the friction forces of that step. The first frame reports none.
    let mut last_step: Option<(Vec<Vec3>, Real, Real)> =
        lag.as_ref().map(|_| (state.x.clone(), dial_now, 0.0));
    let mut t = t0;
    // The next output time after the start (a restart resumes the output grid).
    let mut clock = OutputClock::new(t0, tm.output_interval, tm.end);
    let mut failure: Option<RunFailure> = None;
    let eps_t = 1e-12 * tm.end;
    while t < tm.end - eps_t {
        if let Some(f) = super::interruption("t", t) {
            failure = Some(f);
            break;
        }
        let mut h = clock.step_from(t, steps.step).min(tm.end - t);
        // A step ends where a windowed surface condition starts or stops.
        if let Some(ts) = moisture.as_ref().and_then(|m| m.next_switch(t)) {
            h = h.min(ts - t);
        }
        let (dial, reaches_hold) = if holding {
            (dial_now, false)
        } else {
            let d = if dial_time > 0.0 {
                (dial_now + h / dial_time).min(1.0)
            } else {
                1.0
            };
            match next_hold {
                Some(k) if d >= holds[k] => (holds[k], true),
                _ => (d, false),
            }
        };
        // Terms whose elements change (contact pairs) follow the state at the step's start,
        // with what moves with the dial (a mesh obstacle) where the step takes it.
        s.refresh(&state, dial)?;
        for i in 0..n {
            xhat[i] = state.x[i] + v[i] * h;
        }
        // Vertices on prescribed paths are fixed: their inertia is not assembled, so the
        // prediction can carry their prescribed position into every trial.
        sc.body.prescribe(&mut xhat, dial);
        if obstacles {
            // Newton starts from the last state, not the prediction: the prediction of a sheet
            // falling onto an obstacle lies deep inside it, where the penalty's curvature and
            // the friction's lagged normals make the first iterations wander.
            trial.x.copy_from_slice(&state.x);
            sc.body.prescribe(&mut trial.x, dial);
        } else if extrapolate {
            let h2 = h * h;
            for (i, t) in trial.x.iter_mut().enumerate() {
                let a = Vec3::new(acc[3 * i], acc[3 * i + 1], acc[3 * i + 2]);
                *t = xhat[i] + a * h2;
            }
            sc.body.prescribe(&mut trial.x, dial);
        } else {
            trial.x.copy_from_slice(&xhat);
        }
        dofs_hat.copy_from_slice(&state.dofs);
        for (k, wk) in w.iter().enumerate() {
            dofs_hat[ne + k] += wk * h;
        }
        trial.dofs.copy_from_slice(&dofs_hat);
        if extrapolate {
            for (k, a) in acc[3 * n..].iter().enumerate() {
                trial.dofs[ne + k] += a * h * h;
            }
        }
        // With self-contact a predicted start is a step like Newton's: Newton starts from the
        // step's start when the contact does not allow all of it.
        if !obstacles {
            let pat = s.pattern();
            let pot = s.potential(&pat, dial);
            if !s.allows(&pot, &state, &trial.x, &trial.dofs) {
                trial.x.copy_from_slice(&state.x);
                sc.body.prescribe(&mut trial.x, dial);
            }
        }
        let moisture_clock = Instant::now();
        if moisture.is_some() {
            progress.update(
                t / tm.end,
                &format!(
                    "diffusion  t {} s  dt {} s",
                    crate::math::human(t),
                    crate::math::human(h)
                ),
            );
        }
        if let Some(m) = &mut moisture {
            // Diffuse over the step, then set the rest forms from the new surface moisture.
            if let Err(e) = m
                .update_ground(sc, &state.x)
                .and_then(|_| m.update_windows(t))
            {
                failure = Some(RunFailure::MoistureSurface { t, source: e });
                break;
            }
            m.update_sources(sc, t, h);
            m.trial.copy_from_slice(&m.u);
            let tol = m.tolerance(sc);
            match m.diffusion.advance(&mut m.trial, h, tol) {
                Ok(a) => {
                    s.summary.diffusion_substeps += a.substeps;
                    s.summary.diffusion_rejected += a.rejected;
                    s.summary.diffusion_factorisations += a.factorisations;
                    s.summary.diffusion_cg_iterations += a.cg_iterations;
                    s.summary.diffusion_direct_solves += a.direct_solves;
                }
                Err(e) => {
                    failure = Some(RunFailure::Diffusion { t, source: e });
                    break;
                }
            }
            // The step control sees the diffusion too: a step that changes the computed moisture
            // (prescribed nodes excluded: their jump is imposed) by more than
            // moisture.max_change anywhere is cut before the mechanical solve.
            m.change = (0..m.u.len())
                .filter(|&i| !m.diffusion.is_prescribed(i))
                .fold(0.0, |c: Real, i| c.max((m.trial[i] - m.u[i]).abs()));
            if m.change > m.max_change && h > tm.dt_min {
                s.summary.moisture_seconds += moisture_clock.elapsed().as_secs_f64();
                s.summary.rejected_steps += 1;
                steps.rejected(h);
                steps.step = steps.step.max(tm.dt_min);
                continue;
            }
            m.raise_peak();
            match m.targets_of(sc, true) {
                Ok(tt) => trial_targets = tt,
                Err(e) => {
                    failure = Some(RunFailure::Growth { t, source: e });
                    break;
                }
            }
            m.trial_mass = m.masses_of(&sc.body, &m.trial);
            if let Some((vertex, &mass)) = m
                .trial_mass
                .iter()
                .enumerate()
                .find(|(_, &w)| !(w.is_finite() && w > 0.0))
            {
                failure = Some(RunFailure::Mass { t, vertex, mass });
                break;
            }
            s.summary.moisture_seconds += moisture_clock.elapsed().as_secs_f64();
        }
        let trial_mass = moisture
            .as_ref()
            .map_or(&sc.body.mass[..], |m| m.mass(&sc.body, true));
        // Friction lags the normal force: solve with λ, update λ from the solution, and re-solve
        // until it agrees.
        if let Some(l) = &mut lag {
            l.start_step();
        }
        let pat = s.pattern();
        // The jump to the step's dial (prescribed paths, mesh obstacles) may not carry anything
        // through the sheet: a step whose jump contact refuses is cut like a failed solve.
        let refused = (dial != dial_now)
            .then(|| {
                s.jump_refused(
                    &s.potential(&pat, dial),
                    &state.x,
                    &trial.x,
                    &state.dofs,
                    dial_now,
                )
            })
            .flatten();
        let rep = if let Some(f) = refused {
            crate::solve::NewtonReport {
                converged: false,
                failure: Some(f),
                ..Default::default()
            }
        } else {
            loop {
                let pot = Potential {
                    dial,
                    inertia: Some(Inertia {
                        inv_dt2: 1.0 / (h * h),
                        xhat: &xhat,
                        dofs_hat: &dofs_hat,
                    }),
                    damping: damping.then_some(Damping {
                        eta_over_dt: tm.damping / h,
                        a_prev: &a_prev,
                        b_prev: &b_prev,
                    }),
                    gravity: s.config.gravity,
                    mass: trial_mass,
                    friction: lag.as_ref().map(|l| l.friction(&state.x, dial_now, h)),
                    ..Potential::new(sc, &pat)
                };
                // The trial's rest forms, thickness and moduli from the coupled field.
                let pot = match &moisture {
                    Some(_) => trial_targets.apply(pot),
                    None => pot,
                };
                let rep = s.solve(&pot, &mut trial, opts);
                let again =
                    rep.converged && lag.as_mut().is_some_and(|l| l.resolve(sc, &trial.x, dial));
                if !again {
                    break rep;
                }
            }
        };
        if !rep.converged {
            s.summary.rejected_steps += 1;
            if !steps.rejected(h) {
                failure = Some(RunFailure::TimeStep {
                    dt_min: tm.dt_min,
                    t,
                    cause: rep.failure_or_unknown(),
                });
                break;
            }
            continue;
        }
        // Projections after the implicit step (seed 002's volume preservation), before the
        // velocities are taken from the positions (its Algorithm 1, lines 10–12).
        let projected = {
            let pat = s.pattern();
            let pot = accepted(s.potential(&pat, dial), moisture.as_ref(), &trial_targets);
            super::hooks::project(&pot, &mut trial)
        };
        if let Err(e) = projected {
            s.summary.rejected_steps += 1;
            if !steps.rejected(h) {
                failure = Some(RunFailure::TimeStep {
                    dt_min: tm.dt_min,
                    t,
                    cause: crate::solve::SolveError::Projection(e.to_string()),
                });
                break;
            }
            continue;
        }
        for (i, ((vi, t), x)) in v.iter_mut().zip(&trial.x).zip(&state.x).enumerate() {
            let vn = (t - x) / h;
            let a = (vn - *vi) / h;
            acc[3 * i..3 * i + 3].copy_from_slice(&[a.x, a.y, a.z]);
            *vi = vn;
        }
        for (k, wk) in w.iter_mut().enumerate() {
            let wn = (trial.dofs[ne + k] - state.dofs[ne + k]) / h;
            acc[3 * n + k] = (wn - *wk) / h;
            *wk = wn;
        }
        if let Some(last) = &mut last_step {
            // The step the frames' friction forces are taken over.
            last.0.copy_from_slice(&state.x);
            (last.1, last.2) = (dial_now, h);
        }
        state.copy_from(&trial);
        super::hooks::accept(sc, &mut state);
        if let Some(m) = &mut moisture {
            m.accept();
            std::mem::swap(&mut targets, &mut trial_targets);
        }
        t += h;
        s.summary.steps += 1;
        dial_now = dial;
        if reaches_hold {
            holding = true;
        }
        if damping {
            let (a, b) = sc.body.forms(&state.x, &state.dofs);
            a_prev = a;
            b_prev = b;
        }
        let calm = moisture
            .as_ref()
            .is_none_or(|m| m.change <= 0.5 * m.max_change);
        steps.accepted(rep.iterations, calm);
        progress.update(
            t / tm.end,
            &format!(
                "step  t {} s  dt {} s  E {} J  r {}",
                crate::math::human(t),
                crate::math::human(h),
                crate::math::human(rep.energy),
                crate::math::human(rep.residual)
            ),
        );
        let at_output = clock.due(t, h, eps_t);
        let mut stop = false;
        let mut released = false;
        if tm.stop_at_equilibrium || holding {
            let pat = s.pattern();
            let pot = Potential {
                states: &state.terms,
                ..accepted(s.potential(&pat, dial), moisture.as_ref(), &targets)
            };
            let mut g = vec![0.0; pat.n];
            pot.eval(&state.x, &state.dofs, Want::Gradient, &mut g, &mut []);
            let r = pot.residual(&g);
            let en = super::report::energies(&pot, &state, &v);
            let calm = r <= tol
                && en.kinetic
                    <= tm.equilibrium_kinetic
                        * (en.get("stretching").unwrap_or(0.0) + en.get("bending").unwrap_or(0.0))
                            .max(Real::MIN_POSITIVE);
            if holding && calm {
                // At equilibrium on a hold: write it and dial on.
                holding = false;
                released = true;
                holds_reached += 1;
                next_hold = next_hold.and_then(|k| (k + 1 < holds.len()).then_some(k + 1));
            }
            stop = tm.stop_at_equilibrium && dial >= 1.0 && calm;
        }
        if at_output || stop || released || t >= tm.end - eps_t {
            if let Some(m) = &moisture {
                m.publish(writer);
            }
            let pat = s.pattern();
            let pot = Potential {
                friction: match (&lag, &last_step) {
                    (Some(l), Some((x0, d0, h0))) if *h0 > 0.0 => Some(l.solved(x0, *d0, *h0)),
                    _ => None,
                },
                ..accepted(s.potential(&pat, dial), moisture.as_ref(), &targets)
            };
            s.driver = record!(t);
            s.path_columns = m_columns(moisture.as_ref(), sc);
            s.frame(writer, &pot, &state, &v, t)?;
            clock.passed(t, h, eps_t);
        }
        if stop {
            break;
        }
    }
    s.summary.time = Some(t);
    s.summary.dial = dial_now;
    s.summary.holds_reached = holds_reached;
    s.driver = record!(t);
    s.summary.converged = failure.is_none();
    s.summary.reason = failure.map(|f| f.to_string()).unwrap_or_default();
    let pat = s.pattern();
    let pot = accepted(s.potential(&pat, dial_now), moisture.as_ref(), &targets);
    s.summary.energy = super::report::energies(&pot, &state, &v);
    if s.summary.reason.is_empty() {
        return Ok(());
    }
    // Record the state reached when the run stopped early.
    s.path_columns = m_columns(moisture.as_ref(), sc);
    s.frame(writer, &pot, &state, &v, t)?;
    Ok(())
}

/// The log's `mass` column (kg) of a run whose absorbed water changes its mass: the sheet's
/// total mass at the accepted state, dry mass plus water, which falls as a leaf dries.
fn m_columns(field: Option<&Transport>, sc: &crate::model::Scene) -> Vec<(String, Real)> {
    match field {
        Some(m) if m.wet() => vec![("mass".into(), m.mass(&sc.body, false).iter().sum())],
        _ => Vec::new(),
    }
}
