//! The explicit driver: MorphoShell's damped Newtonian dynamics (seed 001 §2, §8, §17).
//!
//! Each vertex i of lumped mass `m_i` (ρ h A / 3, reference areas) moves under the elastic and
//! external force `F_i = −∂Φ/∂x_i` and a linear viscous drag `−c m_i v_i`, integrated by
//! semi-implicit (symplectic) Euler:
//!
//! `v ← v + Δt (F/m − c v)`,   `x ← x + Δt v`.
//!
//! Only the gradient is assembled; no Hessian is built and nothing is factorised.
//!
//! ## Time step (dispersion relations)
//! With μ the smallest shear modulus, t the smallest thickness, ρ the density, ν Poisson's ratio,
//! `D = μ t³ / (6(1 − ν))` the flexural rigidity (`E t³/(12(1−ν²))` with `E = 2μ(1+ν)`) and
//! `a_min` the smallest altitude of the reference triangles:
//!
//! * in-plane waves travel at `c_s ~ √(μ/ρ)`; the shortest wave a mesh carries has a length of
//!   order `a_min`, so its angular frequency is `ω_s ~ c_s / a_min` up to a mesh- and
//!   convention-dependent factor;
//! * bending waves obey `ρ t ω² = D k⁴`, so `ω_b = √(D/(ρt)) k²` with `k ~ 2π / a_min`.
//!
//! Symplectic Euler is stable while `ω_max Δt < 2`. shellsim takes MorphoShell's rule
//!
//! `Δt = p · min(0.185 √(ρ/μ) a_min, √(ρt/D) a_min² / 2π)`,
//!
//! whose 0.185 MorphoShell calibrated so that p need not change when the stretching rather than
//! the bending bound is the smaller. The prefactor p (`explicit.time_step_prefactor`) absorbs
//! the factors of order one; its true limit depends on the mesh. The driver measures it at the
//! start: the largest eigenvalue `ω_max²` of `M⁻¹H` by power iteration on finite differences of
//! the gradient (no Hessian), giving the limit `p* = 2 / (ω_max Δt(p = 1))`, reported in
//! `summary.json` (`explicit.stable_prefactor`) and warned about when p exceeds it.
//!
//! ## Damping and time scales
//! The longest bending mode has `k = 2π / L`, with L the reference perimeter of the largest
//! sheet (MorphoShell's sample length, which adds up every sheet's boundary; for a closed
//! surface, π × its bounding-box diagonal; `src/scales.rs`): `ω_L = √(D/(ρt)) k²`.
//! Critical damping of that mode is `c = 2 ω_L`; the drag rate is `c = p_d · 2 ω_L` with the
//! prefactor `p_d` of the phase (`damping_prefactor_dial` while the forms are dialled,
//! `damping_prefactor_wait` while waiting for equilibrium). The long time is the period of the
//! slowest mode, `T = max(2π/ω_L, L √(ρ/μ))`; the dial, the frame interval, the equilibrium
//! window and the run's time limit are multiples of it.
//!
//! ## Gradient-descent start
//! `explicit.gradient_descent_steps` steps of the overdamped limit `c m v = F` first
//! (`x ← x + Δt_gd F/(c m)`, velocities discarded), with `Δt_gd = c Δt² / 2`: forward Euler on
//! the overdamped dynamics is stable for `Δt_gd < 2c/ω_max²`, which `c Δt²/2` satisfies whenever
//! `Δt < 2/ω_max`.
//!
//! ## Dial, holds and the equilibrium test
//! The dial goes from 0 to 1 linearly over `dial_long_times` long times; at each of
//! `dial.holds` it stops until the sheet is at equilibrium. After dial 1 the run waits for
//! equilibrium and stops there. The default test (`"window"`) checks, once per window of
//! `window_long_times` long times: the force residual `‖∇Φ‖∞ / F` (shellsim's force scale, the
//! same as Newton's) below `force_tolerance`; the largest vertex displacement over the window
//! below `shape_tolerance` × the sheet's size; the change of Φ over the window below
//! `energy_tolerance` × |Φ|; and the kinetic energy below `energy_tolerance` × |Φ|. A shape
//! that still creeps fails the displacement test, so the test cannot fire while the shape moves.
//! `"morphoshell"` reproduces MorphoShell's test: the largest node force (drag included) below
//! `morphoshell_force_threshold` × μ t a_min and the largest speed below
//! `morphoshell_speed_threshold` × √(μ/ρ). Both include the force a term leaves unbalanced on
//! a degree of freedom it moves itself (a pressed slide, [`ExplicitHooks::explicit_unbalanced`]), so a
//! load the sheet does not carry is never reported as an equilibrium. Each frame's `residual`
//! (`log.csv`) is the window test's force measure at the frame's state.
//!
//! ## Bounds
//! Before anything is written ([`check`]): a vertex must be free; the drag must satisfy
//! `c Δt < 2`; and `gradient_descent_steps + max_long_times · T/Δt` at most
//! [`crate::settings::MAX_STEPS`]. The time limit is checked every step.
//!
//! [`ExplicitHooks::explicit_unbalanced`]: crate::energy::term::ExplicitHooks::explicit_unbalanced
//!
//! ## Contact
//! With `[self_contact]` or a mesh obstacle, the contact pairs are gathered at the start, at
//! every frame and whenever a vertex would soon leave the radius it may move from where they
//! were gathered; a vertex that leaves it is pulled back (the `contact` module). A term whose elements
//! change and that bounds no displacement is refused.
//!
//! ## Tracked states
//! Every step is an accepted state: terms that track a state across steps (a boundary
//! moment's angles, [`crate::energy::term::Tracked`]) move it on after each.
//!
//! ## Failure
//! A state that is not finite, or a kinetic energy above 100 × μ t A (strains of order ten
//! everywhere), stops the run: `summary.json` gives the reason and the last good frame, and the
//! unstable state is never written.

use super::{Progress, RunError, Solver};
use crate::energy::Potential;
use crate::integrate::report::ExplicitReport;
use crate::integrate::Sink;
use crate::math::{human, Real, Vec3};
use crate::settings::EquilibriumTest;
use crate::solve::State;

mod bounds;
mod contact;
mod equilibrium;
mod step;

pub use crate::scales::Scales;
pub use bounds::{check, max_frequency_squared};
pub use step::{advance, gradient, Step};

use equilibrium::{residual_at, unbalanced, Sample, Test, Window};

/// Where the dial is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    /// Dialling towards the next hold (or 1).
    Dial,
    /// Waiting for equilibrium at a hold (or at 1).
    Wait,
}

/// Why the loop ended.
enum Stop {
    /// The equilibrium test fired at dial 1.
    Converged,
    /// The state blew up: it is not written.
    Unstable(String),
    /// Interrupted, or a load that cannot balance: the state reached is written.
    Other(String),
    /// The time limit `explicit.max_long_times` was reached: the state reached is written.
    TimeLimit,
}

/// Where an explicit run is: its time, dial and phase, the holds, the next frame, the step
/// counts, the window test's energy scale and last window. A frame saves it
/// ([`Clock::saved`]) and a restart resumes it ([`Clock::restore`]).
struct Clock {
    /// Time (s).
    t: Real,
    /// The dial factor.
    dial: Real,
    /// Dialling or waiting.
    phase: Phase,
    /// The index of the next hold, if any.
    next_hold: Option<usize>,
    /// Holds reached so far.
    holds_reached: usize,
    /// The time of the next frame (s).
    next_frame: Real,
    /// Steps since the run's start (they align the windows).
    steps: usize,
    /// Gradient-descent steps left.
    gd_left: usize,
    /// The window test's smallest energy scale (J).
    energy_floor: Real,
    /// The last window's positions and energy.
    window: Window,
}

impl Clock {
    /// The state a frame records for an exact restart (see `DriverState`).
    fn saved(&self) -> super::DriverState {
        let mut e = std::collections::BTreeMap::new();
        e.insert(
            "phase".into(),
            if self.phase == Phase::Dial { 0.0 } else { 1.0 },
        );
        e.insert("next_frame".into(), self.next_frame);
        e.insert("steps".into(), self.steps as Real);
        e.insert("gradient_descent_left".into(), self.gd_left as Real);
        e.insert("energy_floor".into(), self.energy_floor);
        if self.window.energy.is_finite() {
            e.insert("window_energy".into(), self.window.energy);
        }
        super::DriverState {
            time: self.t,
            dial: self.dial,
            next_hold: self.next_hold,
            holds_reached: self.holds_reached,
            explicit: e,
            window_positions: Some(self.window.x.iter().flat_map(|p| [p.x, p.y, p.z]).collect()),
            ..Default::default()
        }
    }

    /// Resumes the exact time, phase, windows and frames a frame saved, with `holds` the
    /// settings' holds and `n` the vertex count. Errors name the missing or invalid entry.
    fn restore(
        &mut self,
        d: &super::DriverState,
        holds: &[Real],
        n: usize,
    ) -> Result<(), RunError> {
        let get = |k: &str| d.explicit.get(k).copied();
        let bad = |what: &str| {
            RunError::Restart(format!("the frame's explicit state has no valid '{what}'"))
        };
        self.t = d.time;
        self.dial = d.dial.clamp(0.0, 1.0);
        self.next_hold = d.next_hold.filter(|&k| k < holds.len());
        self.holds_reached = d.holds_reached;
        self.phase = match get("phase") {
            Some(0.0) => Phase::Dial,
            Some(1.0) => Phase::Wait,
            _ => return Err(bad("phase")),
        };
        let count = |k: &str| match get(k) {
            Some(c) if c >= 0.0 && c.fract() == 0.0 && c < 1e15 => Ok(c as usize),
            _ => Err(bad(k)),
        };
        self.steps = count("steps")?;
        self.gd_left = count("gradient_descent_left")?;
        self.next_frame = get("next_frame")
            .filter(|f| f.is_finite())
            .ok_or_else(|| bad("next_frame"))?;
        self.energy_floor = get("energy_floor")
            .filter(|f| f.is_finite())
            .ok_or_else(|| bad("energy_floor"))?;
        self.window.energy = get("window_energy").unwrap_or(Real::NAN);
        match &d.window_positions {
            Some(w) if w.len() == 3 * n && w.iter().all(|c| c.is_finite()) => {
                for (i, p) in self.window.x.iter_mut().enumerate() {
                    *p = Vec3::new(w[3 * i], w[3 * i + 1], w[3 * i + 2]);
                }
            }
            _ => return Err(bad("window_positions")),
        }
        Ok(())
    }

    /// Advances the dial by one step `dt` (s) while dialling, over `dial_time` (s; 0 jumps to
    /// 1), stopping to wait at the next of `holds` and at 1.
    fn advance_dial(&mut self, dt: Real, dial_time: Real, holds: &[Real]) {
        if self.phase == Phase::Dial && self.dial < 1.0 {
            self.dial = if dial_time > 0.0 {
                (self.dial + dt / dial_time).min(1.0)
            } else {
                1.0
            };
            if let Some(k) = self.next_hold {
                if self.dial >= holds[k] {
                    self.dial = holds[k];
                    self.next_hold = (k + 1 < holds.len()).then_some(k + 1);
                    self.phase = Phase::Wait;
                }
            }
            if self.dial >= 1.0 {
                self.phase = Phase::Wait;
            }
        }
    }
}

/// The message of a run that blew up at time `t` (s) with `what` went wrong, naming the time
/// step prefactor and, when `limit` is given, the mesh's measured limit.
fn unstable(what: &str, t: Real, prefactor: Real, limit: Option<Option<Real>>) -> String {
    format!(
        "the explicit dynamics went unstable at t = {t_h} s ({what}): lower \
         explicit.time_step_prefactor (now {prefactor}{limit_h})",
        t_h = human(t),
        limit_h = match limit {
            Some(Some(p)) => format!(", this mesh's measured limit {p:.3}"),
            Some(None) => ", this mesh's measured limit unknown".into(),
            None => String::new(),
        }
    )
}

pub(super) fn run_explicit(
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
    let n = state.x.len();
    // Contact follows the sheet through per-vertex displacement bounds (`contact`).
    let mut bounds = contact::Bounds::of(s, n);
    if s.changing && bounds.is_none() {
        return Err(RunError::Unsupported(
            "a term's elements change during the run (a term declares ChangingElements) \
             without bounding the vertices' motion, which the explicit driver needs to follow \
             them: use solver.mode = \"dynamic\""
                .into(),
        ));
    }
    let tracking = sc.terms.iter().any(|t| t.tracked().is_some());
    // The vertices on prescribed paths, which contact cannot pull back.
    let paths: Vec<usize> = {
        let mut p: Vec<usize> = sc.body.prescribed.iter().map(|&(v, _, _)| v).collect();
        p.dedup();
        p
    };
    // The explicit driver assembles gradients only, on the pattern's elements (the contact
    // pairs' change when they are gathered again).
    let mut pat = s.pattern();
    let cf = sc.settings.explicit.clone();
    let holds = sc.settings.dial.holds.clone();
    let sca = Scales::of(&sc.body);
    let dt = cf.time_step_prefactor * sca.dt_unit;
    let rate_dial = cf.damping_prefactor_dial * 2.0 * sca.omega_long;
    let rate_wait = cf.damping_prefactor_wait * 2.0 * sca.omega_long;
    let dial_time = cf.dial_long_times * sca.long_time;
    let area: Real = (0..sc.body.num_faces())
        .map(|f| {
            let [a, b, c] = sc.body.mesh.face_positions(f);
            0.5 * (b - a).cross(&(c - a)).norm()
        })
        .sum();
    let blow_up = 100.0 * sca.mu * sca.t * area;
    let mass = &sc.body.mass;
    let inv_m: Vec<Real> = (0..n)
        .map(|v| {
            if !sc.node_fixed[v] && mass[v] > 0.0 {
                1.0 / mass[v]
            } else {
                0.0
            }
        })
        .collect();

    // The mesh's stability limit, measured at the start (gradient only).
    let omega2 = {
        let pot = s.potential_at(&pat, 0.0, &state);
        max_frequency_squared(&pot, &state.x, 60)
    };
    let stable_prefactor = (omega2 > 0.0).then(|| 2.0 / (omega2.sqrt() * sca.dt_unit));
    if let Some(p) = stable_prefactor {
        if cf.time_step_prefactor > p {
            s.summary.warnings.push(format!(
                "explicit.time_step_prefactor = {} is above this mesh's stability limit {p:.3} \
                 (measured at the start); the run will likely blow up",
                cf.time_step_prefactor
            ));
        }
    }
    let mut report = ExplicitReport {
        time_step: dt,
        stable_prefactor,
        long_time: sca.long_time,
        damping_rate_dial: rate_dial,
        damping_rate_wait: rate_wait,
        sample_length: sca.length,
        min_altitude: sca.a_min,
        equilibrium_test: match cf.equilibrium {
            EquilibriumTest::Window => "window",
            EquilibriumTest::Morphoshell => "morphoshell",
        }
        .into(),
        microseconds_per_face_step: 0.0,
        holds_reached: 0,
        contact_gathers: None,
        contact_clipped: None,
    };
    let test = Test {
        cf: &cf,
        sca: &sca,
        size: sc.body.mesh.bbox_diagonal(),
        force_scale: sc.body.force_scale.max(Real::MIN_POSITIVE),
        inv_m: &inv_m,
        mass,
    };

    // Dial from the start time (a restart resumes the linear dial; holds already passed stay
    // passed).
    let mut dial = match dial0 {
        Some(d) => d,
        None if dial_time > 0.0 => (t0 / dial_time).min(1.0),
        None => 1.0,
    };
    let next_hold = holds.iter().position(|&h| h > dial);
    let mut phase = if dial >= 1.0 {
        Phase::Wait
    } else {
        Phase::Dial
    };
    if dial_time == 0.0 && next_hold.is_some() {
        // Holds with an instant dial: jump to the first one and wait.
        dial = holds[next_hold.unwrap_or(0)];
        phase = Phase::Wait;
    }
    let mut v = v0.unwrap_or_else(|| vec![Vec3::zeros(); n]);
    let mut g = vec![0.0; pat.n];
    // The frames' residuals are taken here: `g` carries a test step's forces to its update.
    let mut scratch = vec![0.0; pat.n];
    let frame_interval = sca.long_time / cf.frames_per_long_time;
    let window_steps = ((cf.window_long_times * sca.long_time / dt).round() as usize).max(1);
    let t_max = cf.max_long_times * sca.long_time;
    let mut k = Clock {
        t: t0,
        dial,
        phase,
        next_hold,
        holds_reached: 0,
        next_frame: t0 + frame_interval,
        steps: 0,
        gd_left: cf.gradient_descent_steps,
        // The energy scale of the window test: the energy itself, but at least 1e-6 of the
        // target's energy in the starting shape (a compatible target relaxes to Φ ≈ 0, where a
        // test relative to Φ alone would ask for round-off).
        energy_floor: {
            let pot = s.potential_at(&pat, 1.0, &state);
            1e-6 * gradient(&pot, &state.x, &mut g).abs()
        },
        window: Window {
            x: state.x.clone(),
            energy: Real::NAN,
        },
    };
    // A restart with the driver's state resumes its exact time, phase, windows and frames.
    if let Some(d) = &driver {
        k.restore(d, &holds, n)?;
    }
    s.summary.holds_reached = k.holds_reached;
    report.holds_reached = k.holds_reached;
    if let Some(b) = bounds.as_mut() {
        b.gather(s, &state, k.dial)?;
        pat = s.pattern();
    }
    {
        let pot = s.potential_at(&pat, k.dial, &state);
        s.summary.residual = residual_at(&pot, &state.x, &mut scratch);
        s.driver = k.saved();
        s.frame(writer, &pot, &state, &v, k.t)?;
    }
    let clock = std::time::Instant::now();
    // The densities at a dial that stays put (holds, waiting), computed once.
    let mut frozen: Option<(Real, Vec<crate::energy::material::KoiterDensity>)> = None;
    // The steps' gradients run on a team of spinning threads: a step is too short for rayon's
    // sleeping workers to be woken twice per step (`crate::team`).
    let team = crate::team::Team::new(rayon::current_num_threads());
    let mut step = Step::new(&s.potential_at(&pat, k.dial, &state), true);
    // The last step's dial: what moves with it was within its room there.
    let mut last_dial = k.dial;
    let stop = team.activate(|| -> Result<Stop, RunError> {
        Ok(loop {
            if let Some(f) = super::interruption("t", k.t) {
                break Stop::Other(f.to_string());
            }
            let dial = k.dial;
            if let Some(b) = bounds.as_mut() {
                if let Some(why) = b.dialled(s, &state, dial, last_dial, k.t)? {
                    // The state written is the last admissible one.
                    k.dial = last_dial;
                    break Stop::Other(why);
                }
                pat = s.pattern();
            }
            last_dial = dial;
            if let Some(b) = bounds.as_mut().filter(|b| b.stale) {
                b.gather(s, &state, dial)?;
                pat = s.pattern();
            }
            if k.phase == Phase::Wait && frozen.as_ref().is_none_or(|(d, _)| *d != dial) {
                let pot = s.potential(&pat, dial);
                frozen = Some((
                    dial,
                    (0..sc.body.num_faces()).map(|f| pot.density(f)).collect(),
                ));
            }
            let before: Vec<Vec3> = match &bounds {
                Some(_) => paths.iter().map(|&v| state.x[v]).collect(),
                None => Vec::new(),
            };
            sc.body.prescribe(&mut state.x, dial);
            if let Some(b) = bounds.as_mut() {
                if let Some(v) = b.prescribed(&paths, &state.x) {
                    // A path left its vertex's room: check its move, then gather there.
                    let mut from = state.x.clone();
                    for (&u, p) in paths.iter().zip(&before) {
                        from[u] = *p;
                    }
                    let pot = s.potential_at(&pat, dial, &state);
                    if pot.jump_fraction(&from, &state.x, &state.dofs, dial) < 1.0 {
                        state.x = from;
                        let p = state.x[v];
                        break Stop::Other(format!(
                            "the prescribed path of vertex {v} at ({}, {}, {}) m drives the \
                             sheet within self_contact.min_separation of itself or an obstacle at \
                             t = {} s, dial {}",
                            human(p.x),
                            human(p.y),
                            human(p.z),
                            human(k.t),
                            human(dial)
                        ));
                    }
                    b.gather(s, &state, dial)?;
                    pat = s.pattern();
                }
            }
            // Terms whose own state follows the sheet (a moving slide) catch up with it first.
            for t in sc.terms.iter() {
                if let Some(hooks) = t.explicit() {
                    let own = state.terms.get_mut(t.name());
                    hooks.explicit_begin(&sc.body, dial, &state.x, dt, own);
                }
            }
            let pot = Potential {
                frozen: frozen
                    .as_ref()
                    .filter(|(d, _)| *d == dial)
                    .map(|(_, v)| &v[..]),
                states: &state.terms,
                dial_rate: if k.phase == Phase::Dial && dial < 1.0 && dial_time > 0.0 {
                    1.0 / dial_time
                } else {
                    0.0
                },
                ..s.potential(&pat, dial)
            };
            let c = if k.phase == Phase::Dial {
                rate_dial
            } else {
                rate_wait
            };
            let testing = k.steps.is_multiple_of(window_steps) && k.steps > 0;
            // Most steps are one fused gradient-and-update; the equilibrium test needs the force
            // and the state it belongs to, the gradient-descent start its own update.
            let fused = step.fused() && k.gd_left == 0 && !testing;
            let clock = std::time::Instant::now();
            let energy = if fused {
                step.take(&pot, &mut state.x, &mut v, &mut g, &inv_m, c, dt)
            } else {
                gradient(&pot, &state.x, &mut g)
            };
            s.summary.timing.newton.assembly += clock.elapsed().as_secs_f64();
            // Terms that act on the step itself (slide friction), before the equilibrium test sees
            // the forces (a fused step has none).
            if !fused {
                for hooks in sc.terms.iter().filter_map(|t| t.explicit()) {
                    hooks.explicit_step(&pot, &state.x, &mut v, &mut g, dt);
                }
            }
            // The equilibrium test, once per window (before the step, at the state the force
            // belongs to).
            if testing {
                let healthy = energy.is_finite()
                    && state.x.iter().all(|p| p.iter().all(|c| c.is_finite()))
                    && v.iter().all(|p| p.iter().all(|c| c.is_finite()));
                let kinetic: Real = v
                    .iter()
                    .zip(mass)
                    .map(|(v, m)| 0.5 * m * v.norm_squared())
                    .sum();
                if !healthy || kinetic > blow_up {
                    let what = format!("energy {} J, kinetic {} J", human(energy), human(kinetic));
                    let why = unstable(&what, k.t, cf.time_step_prefactor, Some(stable_prefactor));
                    break Stop::Unstable(why);
                }
                // A load the sheet can never balance (a pressed slide past the sheet) stops the
                // run; one not balanced yet keeps it going.
                let unbalanced = match unbalanced(&pot, &state.x) {
                    Ok(f) => f,
                    Err(why) => break Stop::Other(why),
                };
                let sample = Sample {
                    x: &state.x,
                    v: &v,
                    g: &g,
                    energy,
                    kinetic,
                    unbalanced,
                    drag: c,
                };
                let at_rest = k.phase == Phase::Wait
                    && test.at_rest(&pot, &sample, &k.window, k.energy_floor);
                k.window.x.copy_from_slice(&state.x);
                k.window.energy = energy;
                if at_rest {
                    if k.dial >= 1.0 {
                        break Stop::Converged;
                    }
                    k.holds_reached += 1;
                    report.holds_reached = k.holds_reached;
                    s.summary.holds_reached = k.holds_reached;
                    k.phase = Phase::Dial;
                    let pot = s.potential_at(&pat, k.dial, &state);
                    s.summary.residual = residual_at(&pot, &state.x, &mut scratch);
                    k.next_frame = k.t + frame_interval;
                    s.driver = k.saved();
                    s.frame(writer, &pot, &state, &v, k.t)?;
                    // A restart from this frame gathers the pairs here: so does the run.
                    if let Some(b) = bounds.as_mut() {
                        b.stale = true;
                    }
                }
            }
            // The step.
            if k.gd_left > 0 {
                let cg = c.max(Real::MIN_POSITIVE);
                let h = cg * dt * dt / 2.0;
                for i in 0..n {
                    let f = Vec3::new(g[3 * i], g[3 * i + 1], g[3 * i + 2]);
                    v[i] = -f * (inv_m[i] / cg);
                    state.x[i] += v[i] * h;
                }
                if let Some(b) = bounds.as_mut() {
                    b.clip(&mut state.x, None, &inv_m, dt);
                }
                k.gd_left -= 1;
                if k.gd_left == 0 {
                    v.iter_mut().for_each(|v| *v = Vec3::zeros());
                }
            } else {
                if !fused {
                    advance(&mut state.x, &mut v, &g, &inv_m, c, dt);
                }
                if let Some(b) = bounds.as_mut() {
                    b.clip(&mut state.x, Some(&mut v), &inv_m, dt);
                }
            }
            // Every step is accepted: terms that track a state across steps (a moment's
            // angles, which follow the boundary through full turns) move it on.
            if tracking {
                super::hooks::accept(sc, &mut state);
            }
            k.t += dt;
            k.steps += 1;
            s.summary.steps += 1;
            // The time limit, every step (a comparison): a window longer than the time left
            // does not carry the run past it.
            if k.t >= t_max {
                break Stop::TimeLimit;
            }
            k.advance_dial(dt, dial_time, &holds);
            if k.t >= k.next_frame {
                let pot = s.potential_at(&pat, k.dial, &state);
                let healthy = state.x.iter().all(|p| p.iter().all(|c| c.is_finite()));
                if !healthy {
                    let why = unstable(
                        "a position is not finite",
                        k.t,
                        cf.time_step_prefactor,
                        None,
                    );
                    break Stop::Unstable(why);
                }
                s.summary.residual = residual_at(&pot, &state.x, &mut scratch);
                k.next_frame += frame_interval;
                s.driver = k.saved();
                s.frame(writer, &pot, &state, &v, k.t)?;
                // A restart from this frame gathers the pairs here: so does the run.
                if let Some(b) = bounds.as_mut() {
                    b.stale = true;
                }
                let dialling = k.phase == Phase::Dial;
                progress.update(
                    if dialling {
                        0.5 * k.dial
                    } else {
                        0.5 + 0.5 * (k.t / t_max).min(1.0)
                    },
                    &format!(
                        "explicit {}  t {} s  dt {} s  dial {}  E {} J",
                        if dialling { "dialling" } else { "waiting" },
                        human(k.t),
                        human(dt),
                        human(k.dial),
                        human(energy)
                    ),
                );
            }
        })
    })?;
    drop(team);
    let wall = clock.elapsed().as_secs_f64();
    report.microseconds_per_face_step =
        1e6 * wall / (k.steps.max(1) as Real * sc.body.num_faces() as Real);
    if let Some(b) = &bounds {
        report.contact_gathers = Some(b.gathers);
        report.contact_clipped = Some(b.clipped);
    }
    finish(
        s,
        writer,
        &pat,
        stop,
        &k,
        &state,
        &v,
        report,
        cf.max_long_times,
        &mut scratch,
    )
}

/// Writes what the run reached, after the loop: the summary (residual, time, dial, the explicit
/// report, why it stopped) and the last frame, unless the state blew up.
#[allow(clippy::too_many_arguments)]
fn finish(
    s: &mut Solver,
    writer: &mut dyn Sink,
    pat: &crate::assembly::Pattern,
    stop: Stop,
    k: &Clock,
    state: &State,
    v: &[Vec3],
    report: ExplicitReport,
    max_long_times: Real,
    scratch: &mut [Real],
) -> Result<(), RunError> {
    let pot = s.potential_at(pat, k.dial, state);
    s.summary.residual = residual_at(&pot, &state.x, scratch);
    s.summary.time = Some(k.t);
    s.summary.dial = k.dial;
    s.summary.explicit = Some(report);
    s.driver = k.saved();
    match stop {
        Stop::Converged => {
            s.summary.converged = true;
            s.summary.energy = crate::integrate::report::energies(&pot, state, v);
            s.frame(writer, &pot, state, v, k.t)?;
        }
        Stop::Unstable(reason) => {
            s.summary.converged = false;
            s.summary.residual = Real::NAN;
            s.summary.reason = format!(
                "{reason}; the run stopped, last good frame {}",
                writer.last_frame()
            );
        }
        Stop::Other(_) | Stop::TimeLimit => {
            s.summary.converged = false;
            s.summary.reason = match stop {
                Stop::Other(reason) => reason,
                _ => format!(
                    "no equilibrium after explicit.max_long_times = {max_long_times} long times \
                     ({t_h} s); residual {}",
                    human(s.summary.residual),
                    t_h = human(k.t)
                ),
            };
            s.summary.energy = crate::integrate::report::energies(&pot, state, v);
            s.frame(writer, &pot, state, v, k.t)?;
        }
    }
    Ok(())
}
