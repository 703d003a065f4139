//! The static driver: adaptive continuation of the dial (rest forms and loads), then of the
//! stretching weight (membrane continuation), with the stability check and saddle escapes.

use super::Sink;
use super::{perturb, Progress, RunError, RunFailure, Solver, StepControl};
use crate::math::{Real, Vec3};
use crate::solve::{NewtonOptions, NewtonReport, State};

pub(super) fn run_static(
    s: &mut Solver,
    writer: &mut dyn Sink,
    progress: &mut dyn Progress,
    mut state: State,
    restart: Option<Real>,
) -> Result<(), RunError> {
    let cf = s.config.statics.clone();
    let opts = s.config.newton;
    let tol = opts.tol;
    // Intermediate continuation steps need not be solved to full accuracy, unless they are
    // written: every frame (and its row of the load–displacement curve) is converged to the
    // tolerance.
    let loose = (tol * 1e3).min(1e-5).max(tol);
    let (min_step, sb, seed) = (cf.min_step, s.config.symmetry_breaking, s.config.seed);
    let (check, max_escapes) = (cf.check_stability, cf.max_saddle_escapes);
    let cont_frames = cf.continuation_frames;
    // Hold points: the continuation lands on each, solves it to full accuracy and writes a frame.
    let holds = s.scene.settings.dial.holds.clone();
    let zeros = vec![Vec3::zeros(); state.x.len()];
    let dial_start = restart.unwrap_or(0.0).clamp(0.0, 1.0);
    {
        // The first frame's contact pairs, where it is.
        s.refresh(&state, dial_start)?;
        let pat = s.pattern();
        let pot = s.potential(&pat, dial_start);
        s.driver = super::DriverState {
            time: dial_start,
            dial: dial_start,
            ..Default::default()
        };
        s.frame(writer, &pot, &state, &zeros, dial_start)?;
    }
    let mut dial = dial_start;
    // A restart solves at least once, even from a frame at dial 1 (the settings may differ).
    let mut need_solve = restart.is_some();
    // Halved on failure, doubled after an easy solve (≤ 5 Newton iterations).
    let mut steps = StepControl::new(
        cf.first_step.min(cf.max_step),
        min_step,
        cf.max_step,
        2.0,
        5,
        1,
    );
    // Membrane continuation: the stretching weight starts at 1/softening and grows ×ratio per
    // solve once the dial is at 1 (see the module doc).
    let mut scale = 1.0 / cf.softening;
    let mut ratio: Real = 10.0;
    let mut trial = state.clone();
    let mut failure: Option<RunFailure> = None;
    while dial < 1.0 || scale < 1.0 || need_solve {
        if let Some(f) = super::interruption("dial", dial) {
            failure = Some(f);
            break;
        }
        let (target, target_scale) = if dial < 1.0 {
            // A step that ends within round-off of dial 1 or of a hold ends on it (ten steps
            // of 0.1 sum to 0.9999999999999999), so that no extra step of 1e-16 follows.
            let mut next = (dial + steps.step).min(1.0);
            if 1.0 - next < DIAL_ROUND_OFF {
                next = 1.0;
            }
            let hold = holds
                .iter()
                .copied()
                .find(|&h| h > dial && h < next + DIAL_ROUND_OFF && h < 1.0);
            (hold.unwrap_or(next), scale)
        } else {
            (1.0, (scale * ratio).min(1.0))
        };
        let at_hold = holds.contains(&target) && target > dial;
        let t = if (target < 1.0 || target_scale < 1.0) && !cont_frames && !at_hold {
            loose
        } else {
            tol
        };
        trial.copy_from(&state);
        s.scene.body.prescribe(&mut trial.x, target);
        s.refresh(&trial, target)?;
        let pat = s.pattern();
        let pot = s.potential_scaled(&pat, target, target_scale);
        // The jump to the new dial (prescribed paths, mesh obstacles) may not carry anything
        // through the sheet: a step whose jump contact refuses is cut like a failed solve.
        let refused = if target != dial {
            s.jump_refused(&pot, &state.x, &trial.x, &state.dofs, dial)
        } else {
            None
        };
        if target != dial && refused.is_none() {
            s.predict(&pot, dial, &mut trial);
        }
        let rep = match refused {
            Some(f) => NewtonReport {
                converged: false,
                failure: Some(f),
                ..Default::default()
            },
            None => s.solve(&pot, &mut trial, NewtonOptions { tol: t, ..opts }),
        };
        // A term tracking a state across steps (a moment's angle) may refuse a step too large
        // for it; the step is then cut like a failed solve.
        let admissible = rep.converged && super::hooks::admissible(s.scene, &trial);
        let rep = if rep.converged && !admissible {
            NewtonReport {
                converged: false,
                failure: Some(crate::solve::SolveError::Refused(
                    "a boundary turned by more than π/2 in one step (a moment load tracks its \
                     angle step by step)",
                )),
                ..rep
            }
        } else {
            rep
        };
        if rep.converged {
            let taken = target - dial;
            state.copy_from(&trial);
            super::hooks::accept(s.scene, &mut state);
            let grow = rep.iterations <= 5;
            if dial < 1.0 {
                dial = target;
                steps.accepted(rep.iterations, true);
            } else {
                scale = target_scale;
                if rep.iterations == 0 {
                    // The raised weight changed nothing the tolerance sees: the membrane is at
                    // its rest metric, and the rest of the way is one step (halved like any
                    // other if it fails).
                    ratio = ratio.max(1.0 / scale);
                } else if grow {
                    ratio = (ratio * ratio).min(1e3);
                }
            }
            need_solve = false;
            s.summary.steps += 1;
            progress.update(
                dial,
                &format!(
                    "continuation  dial {}  step {}  E {} J  r {}",
                    crate::math::human(dial),
                    crate::math::human(taken),
                    crate::math::human(rep.energy),
                    crate::math::human(rep.residual)
                ),
            );
            if at_hold {
                s.summary.holds_reached += 1;
            }
            if (cont_frames || at_hold) && dial < 1.0 {
                let pat = s.pattern();
                let pot = s.potential(&pat, dial);
                s.driver = super::DriverState::at_dial(dial, &steps);
                s.frame(writer, &pot, &state, &zeros, dial)?;
            }
        } else if dial < 1.0 {
            s.summary.rejected_steps += 1;
            if !steps.rejected(steps.step) {
                failure = Some(match cf.pressure_control {
                    Some(p) => RunFailure::PressureLimit {
                        pressure: p * dial,
                        dial,
                        volume: crate::mesh::closed::enclosed_volume(
                            &state.x,
                            &s.scene.body.mesh.faces,
                        ),
                        cause: rep.failure_or_unknown(),
                        limit_stretch: crate::energy::membrane::thin_sphere_limit_stretch(
                            &s.scene.settings.material.membrane(),
                        ),
                    },
                    None => RunFailure::ContinuationStep {
                        min: min_step,
                        dial,
                        cause: rep.failure_or_unknown(),
                        tolerance: tol,
                        loose,
                        force_scale: s.force_scale,
                        from_loads: s.force_scale < s.scene.body.force_scale,
                    },
                });
                break;
            }
        } else {
            s.summary.rejected_steps += 1;
            ratio = ratio.sqrt();
            if ratio < 1.01 {
                failure = Some(RunFailure::MembraneContinuation {
                    scale,
                    cause: rep.failure_or_unknown(),
                });
                break;
            }
        }
    }
    if failure.is_none() && check {
        let mut escapes = 0;
        while !s.is_stable(1.0, &state) {
            if let Some(f) = super::interruption("dial", dial) {
                failure = Some(f);
                break;
            }
            if escapes >= max_escapes {
                failure = Some(RunFailure::Saddle { escapes });
                break;
            }
            escapes += 1;
            let amp = sb.max(1e-3) * s.scene.body.mean_edge * 10f64.powi(escapes as i32);
            perturb(
                s.scene,
                &mut state.x,
                amp,
                seed.wrapping_add(escapes as u64),
            );
            s.refresh(&state, 1.0)?;
            let pat = s.pattern();
            let pot = s.potential(&pat, 1.0);
            let rep = s.solve(
                &pot,
                &mut state,
                NewtonOptions {
                    max_iter: opts.max_iter * 5,
                    ..opts
                },
            );
            if !rep.converged {
                failure = Some(RunFailure::AfterSaddle(rep.failure_or_unknown()));
                break;
            }
        }
        s.summary.saddle_escapes = escapes;
    }
    s.summary.dial = dial;
    s.summary.converged = failure.is_none();
    s.summary.reason = failure.map(|f| f.to_string()).unwrap_or_default();
    let pat = s.pattern();
    let pot = s.potential(&pat, dial);
    s.summary.energy = super::report::energies(&pot, &state, &zeros);
    s.driver = super::DriverState::at_dial(dial, &steps);
    // The series' time of a static frame is its dial (a failed run's last frame included).
    s.frame(writer, &pot, &state, &zeros, dial)?;
    Ok(())
}

/// The static potential at `dial` before a run (for the checks that need one): the reference
/// state's positions with the prescribed paths at `dial`, and the potential with every load,
/// gravity included, ramped to `dial` as the static driver ramps them, with `state`'s term
/// states.
pub(super) fn reference_potential<'p>(
    scene: &'p crate::model::Scene,
    pattern: &'p crate::assembly::Pattern,
    state: &'p State,
    dial: Real,
) -> (Vec<Vec3>, crate::energy::Potential<'p>) {
    let mut x = state.x.clone();
    scene.body.prescribe(&mut x, dial);
    let pot = crate::energy::Potential {
        dial,
        gravity: Vec3::from(scene.settings.loads.gravity) * dial,
        states: &state.terms,
        ..crate::energy::Potential::new(scene, pattern)
    };
    (x, pot)
}

/// Rejects a dynamic scene whose dial starts above 0 (`rest.dial_time = 0`: at 1, or at the
/// first hold) when the jump there from the reference (mesh obstacles moved by their
/// displacement, vertices on prescribed paths) would carry something within the contact's
/// minimum separation of the sheet: the run would start from a state the contact never checked.
pub fn check_start(
    scene: &crate::model::Scene,
    settings_name: &str,
) -> Result<(), crate::settings::SettingsError> {
    let settings = &scene.settings;
    if settings.solver.mode != crate::settings::Mode::Dynamic
        || settings.rest.dial_time > 0.0
        || !scene.terms.iter().any(|t| t.step_limit().is_some())
    {
        return Ok(());
    }
    let dial = settings.dial.holds.first().copied().unwrap_or(1.0);
    let pattern = crate::assembly::Pattern::for_scene(scene);
    let state = State::reference(scene);
    let (x, pot) = reference_potential(scene, &pattern, &state, dial);
    if pot.jump_fraction(&state.x, &x, &state.dofs, 0.0) < 1.0 {
        return Err(crate::settings::SettingsError::Invalid {
            path: settings_name.to_string(),
            key: "rest.dial_time".into(),
            reason: format!(
                "is 0, so the run starts at dial {}, where a mesh obstacle moved by its \
                 displacement (or a vertex on a prescribed path) is within the contact's \
                 minimum separation of the sheet or through it: set rest.dial_time > 0 to \
                 move it in over time",
                crate::math::human(dial)
            ),
        });
    }
    Ok(())
}

/// How close a continuation step's end may come to dial 1 or a hold and be taken as it.
const DIAL_ROUND_OFF: Real = 1e-12;

/// Rejects a static scene whose supports leave it free to translate along a direction in which
/// the loads at dial 1 have a net force: it has no equilibrium, and the automatic pins that
/// remove the free motions ([`crate::body::hold::rigid_pins`]) would carry that force as a
/// reaction. The net force `Σ fᵥ` along each free translation `t` must be below 1e-6 of
/// `Σ |fᵥ|` (balanced loads cancel to round-off).
pub fn check_supports(
    scene: &crate::model::Scene,
    settings_name: &str,
) -> Result<(), crate::settings::SettingsError> {
    let settings = &scene.settings;
    let modes: Vec<Vec3> = scene
        .body
        .rigid
        .modes
        .iter()
        .filter(|m| m.w == Vec3::zeros())
        .map(|m| m.t)
        .collect();
    if settings.solver.mode != crate::settings::Mode::Static
        || !settings.obstacles.is_empty()
        || settings.contact.enabled
        || modes.is_empty()
    {
        return Ok(());
    }
    let pattern = crate::assembly::Pattern::for_scene(scene);
    let state = State::reference(scene);
    let (x, pot) = reference_potential(scene, &pattern, &state, 1.0);
    let f = pot.applied_forces(&x, &state.dofs);
    let nv = scene.body.num_vertices();
    let force = |v: usize| Vec3::new(f[3 * v], f[3 * v + 1], f[3 * v + 2]);
    let total: Vec3 = (0..nv).map(force).sum();
    let size: Real = (0..nv).map(|v| force(v).norm()).sum();
    for t in modes {
        let along = total.dot(&t);
        if along.abs() > 1e-6 * size {
            let h = crate::math::human;
            return Err(crate::settings::SettingsError::Invalid {
                path: settings_name.to_string(),
                key: "constraints".into(),
                reason: format!(
                    "the supports leave the sheet free to translate along ({}, {}, {}), and \
                     the loads at dial 1 push it that way with a net force of {} N (of {} N \
                     in all): a static scene has no equilibrium then, and the system is \
                     singular. Hold vertices or components that carry it (constraint_indicators, \
                     fix_tags, fix_boxes, [[constraints.support]]), balance the loads, or use \
                     solver.mode = \"dynamic\"",
                    h(t.x),
                    h(t.y),
                    h(t.z),
                    h(along),
                    h(size)
                ),
            });
        }
    }
    Ok(())
}
