//! The solver state the drivers share ([`Solver`]): the scene, its pattern and factorisation,
//! Newton's workspace, the summary and counters, and the frames it writes.

use super::report::{LogRow, Summary};
use super::Sink;
use super::{config, DriverState, RunError};
use crate::assembly::{Pattern, Want};
use crate::energy::Potential;
use crate::math::{Real, Vec3};
use crate::model::Scene;
use crate::settings::Mode;
use crate::solve::newton::Workspace;
use crate::solve::{newton, LinearSolver, NewtonOptions, NewtonReport, SolveError, State};
use std::time::Instant;

/// `r ← H⁻¹ r` with the last factorisation of `lin` and the low-rank parts of `pot` at `state`
/// (Woodbury); `false` when there is no factor or the low-rank solve is singular.
pub(super) fn apply_inverse(
    lin: &mut LinearSolver,
    pot: &Potential,
    state: &State,
    r: &mut [Real],
) -> bool {
    if !lin.is_factored() {
        return false;
    }
    let lr = pot.low_rank(&state.x, &state.dofs);
    let wb = crate::solve::low_rank::Woodbury::new(lin, &lr);
    wb.solve_in_place(lin, r)
}

/// Multiplier updates allowed per solve (see [`Solver::solve`]).
pub(super) const MAX_UPDATES: usize = 50;

/// The most times one solve gathers the contact pairs again ([`SolveError::Regather`]).
const MAX_REGATHERS: usize = 100;

/// The smallest static force scale, relative to the body's `max(E h) × mean edge`: with the
/// default tolerance 1e-9, a residual of 1e-13 of the body's scale, 25× the round-off floor
/// measured on a cantilever whose load is 6e-7 of its membrane stiffness.
const ROUND_OFF_FLOOR: Real = 1e-4;

pub(super) struct Solver<'a> {
    pub(super) scene: &'a Scene,
    /// The current sparsity pattern (replaced when a term's elements change, see
    /// [`Solver::refresh`]); potentials borrow a clone of the handle ([`Solver::pattern`]).
    pub(super) pattern: std::sync::Arc<Pattern>,
    /// Whether some term's elements change during the run.
    pub(super) changing: bool,
    /// The positions at which the changing terms' elements were last gathered (empty when no
    /// term's elements change): a contact term tells there which pairs it gathered.
    pub(super) taken_at: Vec<Vec3>,
    /// The scalar DOFs there.
    pub(super) taken_dofs: Vec<Real>,
    /// The run's controls, from the validated settings.
    pub(super) config: config::RunConfig,
    pub(super) lin: LinearSolver,
    /// Factorisations of the linear solvers of earlier patterns.
    pub(super) retired: crate::linalg::FactorCounts,
    pub(super) ws: Workspace,
    pub(super) summary: Summary,
    pub(super) start: Instant,
    /// The summary's counters when the previous frame was written; log rows report the
    /// differences.
    pub(super) at_last_frame: Counters,
    /// The driver's state as of the next frame (the drivers keep it current).
    pub(super) driver: DriverState,
    /// The residual's force scale (N): the body's, or in statics the applied loads' when
    /// smaller ([`Potential::load_scale`]).
    pub(super) force_scale: Real,
    /// The unperturbed start of a perturbed planar one: the first frame shows it, not the
    /// perturbation (which the summary reports as `symmetry_breaking`).
    pub(super) reference: Option<State>,
    /// The driver's own `log.csv` columns for the next frame (the arc-length path's).
    pub(super) path_columns: Vec<(String, Real)>,
}

/// Counters that log rows report per frame.
#[derive(Clone, Copy, Default)]
pub(super) struct Counters {
    pub(super) newton: usize,
    pub(super) steps: usize,
    pub(super) shifted: usize,
    pub(super) gauss_newton: usize,
    pub(super) rejected: usize,
}

impl Counters {
    pub(super) fn of(s: &Summary) -> Self {
        Counters {
            newton: s.newton_iterations,
            steps: s.steps,
            shifted: s.shifted_iterations,
            gauss_newton: s.gauss_newton_iterations,
            rejected: s.rejected_steps,
        }
    }
}

impl<'a> Solver<'a> {
    /// The solver of `scene` on `threads` threads. The run's clock starts when the user
    /// started the command (the scene's build counts), so that `wall_seconds` also holds the
    /// Hessian's sparsity pattern and its analysis made here.
    pub(super) fn new(scene: &'a Scene, threads: usize) -> Result<Self, RunError> {
        let start = Instant::now()
            .checked_sub(std::time::Duration::from_secs_f64(
                scene.build_seconds.clamp(0.0, 1e9),
            ))
            .unwrap_or_else(Instant::now);
        // The implicit drivers factorise: the sparsity pattern and its symbolic analysis
        // (ordering, elimination tree) are timed together as `analysis`. The explicit driver
        // never factorises and skips the analysis; its pattern's time counts as `other`.
        let clock = Instant::now();
        let pattern = Pattern::for_scene(scene);
        let mut lin = LinearSolver::new(&pattern)?;
        let ws = Workspace::new(&pattern);
        let analysis = if scene.settings.solver.mode != Mode::Explicit {
            lin.analyse()?;
            clock.elapsed().as_secs_f64()
        } else {
            0.0
        };
        let changing = scene.terms.iter().any(|t| t.changing().is_some());
        let config = config::RunConfig::new(scene);
        let summary = Summary {
            mode: match config.mode {
                Mode::Static => "static",
                Mode::Dynamic => "dynamic",
                Mode::Explicit => "explicit",
            }
            .into(),
            vertices: scene.body.num_vertices(),
            faces: scene.body.num_faces(),
            threads,
            warnings: scene.body.warnings.clone(),
            ..Default::default()
        };
        let mut s = Solver {
            scene,
            pattern: std::sync::Arc::new(pattern),
            taken_at: if changing {
                scene.body.mesh.positions.clone()
            } else {
                Vec::new()
            },
            taken_dofs: if changing {
                vec![0.0; scene.num_scalar_dofs()]
            } else {
                Vec::new()
            },
            changing,
            config,
            lin,
            retired: Default::default(),
            ws,
            summary,
            start,
            at_last_frame: Counters::default(),
            driver: DriverState::default(),
            reference: None,
            path_columns: Vec::new(),
            force_scale: scene.body.force_scale,
        };
        // Statics: a load small against the sheet's stiffness sets the residual's scale, so
        // that every load step is solved relative to the load itself; but not below
        // ROUND_OFF_FLOOR × the body's scale, where the gradient's round-off (about 4e-15 of
        // it, measured on a stiff cantilever) would keep the tolerance out of reach.
        if s.config.mode == Mode::Static {
            let pat = s.pattern();
            let phi = vec![0.0; scene.num_scalar_dofs()];
            let load = s
                .potential(&pat, 1.0)
                .load_scale(&scene.body.mesh.positions, &phi);
            if load > 0.0 {
                s.force_scale = s
                    .force_scale
                    .min(load.max(ROUND_OFF_FLOOR * scene.body.force_scale));
            }
        }
        s.summary.force_scale = s.force_scale;
        s.summary.timing.analysis = analysis;
        Ok(s)
    }

    /// The `linear_system` entry of the summary: the current pattern's system and the
    /// factorisations of the whole run (`None` when nothing was factorised).
    pub(super) fn linear_system_report(&self) -> Option<super::report::LinearSystemReport> {
        let c = self.lin.counts();
        let factorisations = c.factorisations + self.retired.factorisations;
        let ordering = self.lin.ordering()?;
        let steps = self.summary.steps.max(1) as Real;
        Some(super::report::LinearSystemReport {
            unknowns: self.lin.unknowns(),
            ordering: ordering.name().into(),
            factor_nonzeros: self.lin.factor_nnz(),
            factor_flops: self.lin.factor_flops(),
            factorisations,
            failed_factorisations: c.failed + self.retired.failed,
            factorisations_per_step: factorisations as Real / steps,
            iterations_per_step: self.summary.newton_iterations as Real / steps,
        })
    }

    /// The current pattern, for potentials to borrow.
    pub(super) fn pattern(&self) -> std::sync::Arc<Pattern> {
        self.pattern.clone()
    }

    /// Follows the terms whose elements change to the state `state` at dial `dial`: a new
    /// pattern when their elements there differ, a new symbolic factorisation only when the
    /// union of the stencils changed. Returns whether the pattern was replaced (take a new
    /// [`Solver::pattern`]).
    pub(super) fn refresh(&mut self, state: &State, dial: Real) -> Result<bool, RunError> {
        if !self.changing {
            return Ok(false);
        }
        // The elements are taken at this state: the motion bound starts here.
        self.taken_at.clone_from(&state.x);
        self.taken_dofs.clone_from(&state.dofs);
        let Some(p) = self
            .pattern
            .refreshed(self.scene, &state.x, &state.dofs, dial)
        else {
            return Ok(false);
        };
        self.summary.element_changes += 1;
        // The explicit driver assembles gradients only: nothing to factorise.
        if self.config.mode != Mode::Explicit && !p.same_union(&self.pattern) {
            let c = self.lin.counts();
            self.retired.factorisations += c.factorisations;
            self.retired.failed += c.failed;
            let clock = Instant::now();
            self.lin = LinearSolver::new(&p)?;
            self.lin.analyse()?;
            self.summary.timing.analysis += clock.elapsed().as_secs_f64();
            self.ws = Workspace::new(&p);
            self.summary.pattern_rebuilds += 1;
        }
        self.pattern = std::sync::Arc::new(p);
        Ok(true)
    }

    pub(super) fn potential<'p>(&self, pattern: &'p Pattern, dial: Real) -> Potential<'p>
    where
        'a: 'p,
    {
        self.potential_scaled(pattern, dial, 1.0)
    }

    /// The potential at `dial` with `state`'s term states.
    pub(super) fn potential_at<'p>(
        &self,
        pattern: &'p Pattern,
        dial: Real,
        state: &'p State,
    ) -> Potential<'p>
    where
        'a: 'p,
    {
        Potential {
            states: &state.terms,
            ..self.potential(pattern, dial)
        }
    }

    pub(super) fn potential_scaled<'p>(
        &self,
        pattern: &'p Pattern,
        dial: Real,
        stretch_scale: Real,
    ) -> Potential<'p>
    where
        'a: 'p,
    {
        // Statics ramps every applied load with the dial, gravity too: a continuation step
        // then adds a fraction of the weight, not all of it at once from the reference shape.
        let gravity = match self.config.mode {
            Mode::Static => self.config.gravity * dial,
            _ => self.config.gravity,
        };
        Potential {
            dial,
            gravity,
            stretch_scale,
            force_scale: self.force_scale,
            ..Potential::new(self.scene, pattern)
        }
    }

    pub(super) fn record(&mut self, rep: &NewtonReport) {
        self.summary.newton_iterations += rep.iterations;
        self.summary.shifted_iterations += rep.shifted_iterations;
        self.summary.gauss_newton_iterations += rep.gauss_newton_iterations;
        self.summary.chord_iterations += rep.chord_iterations;
        self.summary.gradient_only_checks += rep.gradient_only_checks;
        self.summary.indefinite_iterations += rep.indefinite_iterations;
        self.summary.residual = rep.residual;
        self.summary.timing.newton.add(&rep.timing);
    }

    /// Newton on `pot` from `state`, then the terms' multiplier updates (a prescribed volume's
    /// pressure, [`crate::energy::term::Multiplier`]), re-solving until no term asks for
    /// another solve. Each solve is evaluated with the term states `state` holds when it
    /// starts (`pot.terms` is replaced). The report sums the iterations of every solve; more
    /// than [`MAX_UPDATES`] updates is a failure.
    pub(super) fn solve(
        &mut self,
        pot: &Potential,
        state: &mut State,
        opts: NewtonOptions,
    ) -> NewtonReport {
        let mut total = NewtonReport::default();
        let mut regathers = 0;
        let mut updates = 0;
        while updates < MAX_UPDATES {
            // The solver's current pattern: a term that gathered its elements again within
            // this solve replaced the one the caller's potential was made on.
            let pat = self.pattern();
            let terms = state.terms.clone();
            let taken = self.taken_at.clone();
            let taken_dofs = self.taken_dofs.clone();
            let pot = &Potential {
                states: &terms,
                pattern: &pat,
                taken_at: &taken,
                taken_dofs: &taken_dofs,
                ..*pot
            };
            let rep = newton(pot, &mut self.lin, &mut self.ws, state, opts);
            self.record(&rep);
            total.absorb(&rep);
            if matches!(rep.failure, Some(SolveError::Regather)) && regathers < MAX_REGATHERS {
                // A vertex would leave the reach of the contact pairs: gather them at this
                // iterate and go on from it.
                regathers += 1;
                total.failure = None;
                if self.refresh(state, pot.dial).is_err() {
                    total.failure = Some(SolveError::Factor);
                    return total;
                }
                continue;
            }
            if !rep.converged {
                return total;
            }
            updates += 1;
            if !self.scene.terms.iter().any(|t| t.updates().is_some()) {
                return total;
            }
            let lin = &mut self.lin;
            let at = state.clone();
            let mut sensitivity = |u: &[Real]| -> Option<Real> {
                let mut y = u.to_vec();
                apply_inverse(lin, pot, &at, &mut y)
                    .then(|| u.iter().zip(&y).map(|(a, b)| a * b).sum::<Real>())
            };
            if !super::hooks::update(pot, state, &mut sensitivity) {
                return total;
            }
        }
        total.converged = false;
        total.failure = Some(SolveError::MultiplierNotConverged {
            updates: MAX_UPDATES,
        });
        total
    }

    pub(super) fn frame(
        &mut self,
        writer: &mut dyn Sink,
        pot: &Potential,
        state: &State,
        v: &[Vec3],
        time: Real,
    ) -> Result<(), RunError> {
        let reference = self.reference.take();
        let state = reference.as_ref().unwrap_or(state);
        let (now, last) = (Counters::of(&self.summary), self.at_last_frame);
        let (reaction_field, reactions) = super::report::reactions(pot, state);
        self.summary.reactions.clone_from(&reactions);
        let row = LogRow {
            frame: 0,
            time,
            dial: pot.dial,
            energy: Default::default(),
            observables: Vec::new(),
            path: std::mem::take(&mut self.path_columns),
            reactions,
            reaction_field,
            residual: self.summary.residual,
            newton_iterations: now.newton - last.newton,
            steps: now.steps - last.steps,
            shifted_iterations: now.shifted - last.shifted,
            gauss_newton_iterations: now.gauss_newton - last.gauss_newton,
            rejected_steps: now.rejected - last.rejected,
            wall_seconds: self.start.elapsed().as_secs_f64(),
        };
        self.at_last_frame = now;
        let clock = Instant::now();
        let mut driver = self.driver.clone();
        driver.mode = self.summary.mode.clone();
        driver.perturb_pending = reference.is_some();
        driver.model_hints = self.ws.model_hints();
        driver.globals = state.dofs[self.scene.body.num_edge_dofs()..].to_vec();
        for (name, own) in state.terms.iter() {
            if !own.is_empty() {
                driver.terms.insert(name.to_string(), own.to_vec());
            }
        }
        // The sink evaluates the frame with `state`'s own term states.
        let r = writer.frame(pot, state, v, row, Some(&driver));
        self.summary.timing.output += clock.elapsed().as_secs_f64();
        r?;
        Ok(())
    }

    /// Lets the terms predict the equilibrium at dial `pot.dial` from the one at `from`
    /// (see [`crate::energy::term::Predictor`]) with the last factorisation.
    pub(super) fn predict(&mut self, pot: &Potential, from: Real, state: &mut State) {
        if !self.scene.terms.iter().any(|t| t.predictor().is_some()) {
            return;
        }
        if !self.lin.is_factored() {
            // The first step: the Hessian at the start (dial `from`).
            let at = Potential {
                dial: from,
                states: &state.terms,
                ..*pot
            };
            let mut values = vec![0.0; pot.pattern.nnz()];
            let mut g = vec![0.0; pot.pattern.n];
            at.eval(&state.x, &state.dofs, Want::Hessian, &mut g, &mut values);
            let lr = at.low_rank(&state.x, &state.dofs);
            let mut shifted = vec![0.0; values.len()];
            if crate::solve::newton::exact_model(
                &mut self.lin,
                &at,
                &values,
                &mut shifted,
                &lr,
                1e-8,
            )
            .is_none()
            {
                return;
            }
        }
        let lin = &mut self.lin;
        let mut predicted = state.clone();
        let at = &*state;
        let pot_at = Potential {
            states: &at.terms,
            ..*pot
        };
        let mut solve = |r: &mut [Real]| apply_inverse(lin, &pot_at, at, r);
        for t in self.scene.terms.iter() {
            if let Some(p) = t.predictor() {
                let own = predicted.terms.get_mut(t.name());
                p.predict(
                    &pot_at,
                    from,
                    &mut predicted.x,
                    &predicted.dofs,
                    own,
                    &mut solve,
                );
            }
        }
        // Safeguard: a linear prediction from a nearly singular Hessian (an unstressed membrane
        // has soft modes) can land far off; keep it (positions and term states) only when it
        // lowers the potential.
        let e = |s: &State| {
            Potential {
                states: &s.terms,
                ..*pot
            }
            .eval(&s.x, &s.dofs, Want::Energy, &mut [], &mut [])
        };
        let ep = e(&predicted);
        if !(ep.is_finite() && ep < e(state)) {
            return;
        }
        // A term that bounds the steps (contact) must allow the whole prediction: it is a step
        // like Newton's, and may not carry the sheet through itself.
        if self.allows(pot, state, &predicted.x, &predicted.dofs) {
            state.copy_from(&predicted);
        }
    }

    /// Whether the terms that bound the steps ([`crate::energy::term::StepLimit`], contact)
    /// allow the whole jump from the positions `from` at dial `from_dial` to `to` at
    /// `pot.dial`, the scalar DOFs `phi` held, a new step's start (prescribed paths and mesh obstacles moved with the dial):
    /// `None` when they do, else a reason for the step's failure.
    pub(super) fn jump_refused(
        &self,
        pot: &Potential,
        from: &[Vec3],
        to: &[Vec3],
        phi: &[Real],
        from_dial: Real,
    ) -> Option<crate::solve::SolveError> {
        if !self.scene.terms.iter().any(|t| t.step_limit().is_some()) {
            return None;
        }
        (pot.jump_fraction(from, to, phi, from_dial) < 1.0).then_some(
            crate::solve::SolveError::Refused(
                "the step would carry a mesh obstacle or a prescribed vertex within the \
                 minimum separation of the sheet (checked by continuous collision detection \
                 over the jump)",
            ),
        )
    }

    /// Whether the terms that bound the steps ([`crate::energy::term::StepLimit`], contact)
    /// allow the whole straight step from `from` to `(to, to_dofs)` under `pot` (always, when
    /// no term bounds the steps): a predicted start is such a step, and may not carry the sheet
    /// through itself.
    pub(super) fn allows(
        &self,
        pot: &Potential,
        from: &State,
        to: &[Vec3],
        to_dofs: &[Real],
    ) -> bool {
        if !self.scene.terms.iter().any(|t| t.step_limit().is_some()) {
            return true;
        }
        let nx = 3 * from.x.len();
        let mut step = vec![0.0; nx + from.dofs.len()];
        for (v, (a, b)) in from.x.iter().zip(to).enumerate() {
            for k in 0..3 {
                step[3 * v + k] = b[k] - a[k];
            }
        }
        for (i, (a, b)) in from.dofs.iter().zip(to_dofs).enumerate() {
            step[nx + i] = b - a;
        }
        let bound = Potential {
            states: &from.terms,
            taken_at: &self.taken_at,
            taken_dofs: &self.taken_dofs,
            ..*pot
        }
        .step_bound(&from.x, &from.dofs, &step);
        !bound.regather && bound.fraction >= 1.0
    }

    /// Tests `H + δI ≻ 0` at `state` (see module doc).
    pub(super) fn is_stable(&mut self, dial: Real, state: &State) -> bool {
        let (x, phi) = (&state.x, &state.dofs);
        let pattern = self.pattern();
        let pot = self.potential_at(&pattern, dial, state);
        let mut values = vec![0.0; pattern.nnz()];
        let mut g = vec![0.0; pattern.n];
        // Timed with the Newton solves' assembly and factorisation.
        let clock = Instant::now();
        pot.eval(x, phi, Want::Hessian, &mut g, &mut values);
        let lr = pot.low_rank(x, phi);
        self.summary.timing.newton.assembly += clock.elapsed().as_secs_f64();
        // One factorisation of H + 1e-9·mean|diag|·I, with the dense low-rank part through
        // the inertia (an indefinite sparse part is fine when the whole is positive definite).
        let clock = Instant::now();
        let stable =
            crate::solve::newton::is_positive_definite(&mut self.lin, &pot, &values, &lr, 1e-9);
        self.summary.timing.newton.factorisation += clock.elapsed().as_secs_f64();
        if !stable {
            // The solve that follows (from a perturbed state) starts without an exact model
            // known to fail.
            self.ws.note_not_positive_definite();
        }
        stable
    }
}

#[cfg(test)]
mod tests {
    use super::Solver;
    use crate::mesh::generate::{rectangle, Spacing};
    use crate::{Scene, Settings};
    use std::time::{Duration, Instant};

    /// The run's clock covers what the solver's construction does (the Hessian's pattern and
    /// its analysis) and the scene's build before it: `wall_seconds` is what the user waited.
    #[test]
    fn the_run_clock_starts_before_the_pattern_and_the_analysis() {
        let mesh = rectangle(-0.5, -0.5, 1.0, 1.0, 0.25, Spacing::default());
        let settings = Settings::from_str_with(
            "[rest]\ntarget = \"uniform\"\nbbar = [1.0, 0.0, 0.0]\n",
            "clock",
            &[],
        )
        .unwrap();
        let mut scene = Scene::build(mesh, settings).unwrap();
        scene.build_seconds = 0.25;
        let before = Instant::now();
        let s = Solver::new(&scene, 1).unwrap();
        let took = before.elapsed();
        assert!(s.summary.timing.analysis > 0.0);
        // The clock started a build's length before the construction began: what is missing
        // from the 0.25 s is the moment before the clock was read, not the construction (a
        // clock read at its end would miss all of `took`).
        let lead = before.saturating_duration_since(s.start);
        let missing = Duration::from_secs_f64(0.25).saturating_sub(lead);
        assert!(
            missing < took / 4,
            "missing {missing:?} of a {took:?} construction"
        );
        assert!(lead <= Duration::from_secs_f64(0.25), "{lead:?}");
    }
}
