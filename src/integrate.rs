//! Drivers: static equilibrium by adaptive continuation of the dial factor, and implicit-Euler
//! dynamics with adaptive time steps.
//!
//! Membrane continuation (statics): the dial continuation runs with the stretching weight
//! divided by c (`solver.membrane_continuation`, by default c = (L/10h)² with L the mesh's
//! bounding-box diagonal), which makes the sheet effectively √c times thicker relative to its
//! bending, as stiff as a plate of thickness L/10; then the weight is raised back to 1 by
//! warm-started solves at dial 1 (×10, then ×100 after an easy solve; a failed solve takes the
//! square root of the ratio). Newton's quadratic model is poor for thin sheets making large rotations (stiff
//! stretching, soft bending): measured on the 13.5k-face Gauss–Codazzi–Mainardi cone, 269 Newton
//! iterations without it, 17 with it, the same equilibrium to 1e-7. Both call Newton on a [`Potential`] and write frames
//! through an [`output::Writer`](crate::output::Writer).
//!
//! Symmetry breaking: a perfectly flat start is a saddle for many programmed shapes (a metric
//! that asks for a cone, for one). When the initial sheet is exactly planar, every free vertex is
//! moved along the vertex normal by `symmetry_breaking × mean edge × u`, `u` uniform in [−1, 1)
//! from a SplitMix64 stream seeded by `solver.seed`: deterministic and reproducible. After a
//! static solve, the equilibrium is tested for stability (Cholesky of `H + δ·mean|diag|·I`,
//! δ = 1e-9, which fails iff H has an eigenvalue below −δ·mean|diag|); a saddle is perturbed again
//! (amplitude ×10 each time) and re-solved. A saddle is never reported as an equilibrium.

use crate::assembly::{Pattern, Want};
use crate::math::{Real, Sym2, Vec3};
use crate::mesh::generate::Rng;
use crate::output::{LogRow, OutputError, Summary, Writer};
use crate::scene::Scene;
use crate::settings::Mode;
use crate::solve::linear::LinearError;
use crate::solve::newton::{factor_with_shift_upto, Workspace};
use crate::solve::potential::{Damping, Friction, Inertia};
use crate::solve::{newton, LinearSolver, NewtonOptions, NewtonReport, Potential};
use std::time::Instant;

/// Friction lag: a step is re-solved with the updated normal forces until they change by at
/// most this fraction of the largest one ...
const FRICTION_LAG_TOL: Real = 1e-3;
/// ... or this many solves were made (the last one is accepted).
const FRICTION_LAG_MAX: usize = 6;

/// Errors that stop a run (as opposed to non-convergence, which is reported in the summary).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    /// Output could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The linear solver could not be set up.
    #[error(transparent)]
    Linear(#[from] LinearError),
    /// The moisture state made the rest forms invalid.
    #[error("moisture: {0}")]
    Moisture(String),
}

/// The moisture diffusion of a dynamic run and the rest forms it drives.
struct Moisture {
    diffusion: crate::diffusion::Diffusion,
    /// Nodal moisture at the last accepted step, and the trial of the current one.
    u: Vec<Real>,
    trial: Vec<Real>,
    /// Largest nodal change of the last trial step.
    change: Real,
    /// Lumped vertex masses with the absorbed water, at `u` and at `trial` (empty when
    /// `moisture.water_density = 0`).
    mass: Vec<Real>,
    trial_mass: Vec<Real>,
    /// `[moisture.ground]`: each face's own conditions (top, bottom), the ground's
    /// `(k, value, distance)`, and which sides currently touch it.
    base: Vec<[crate::diffusion::SurfaceBc; 2]>,
    taped: Vec<[bool; 2]>,
    /// Sides covered by tape (top, bottom): the growth law sees moisture 0 there.
    tape: Vec<[bool; 2]>,
    ground: Option<(Real, Real, Real)>,
    touching: Vec<[bool; 2]>,
}

impl Moisture {
    /// Builds the diffusion system of a scene with `moisture.enabled` (None otherwise).
    fn new(sc: &Scene) -> Result<Option<Self>, RunError> {
        use crate::diffusion::{Diffusion, Diffusivity, Side, SurfaceBc};
        use crate::settings::{SurfaceKind, SurfaceSide};
        let mo = &sc.settings.moisture;
        if !mo.enabled {
            return Ok(None);
        }
        let dirs: Vec<Vec3> = sc.growth.direction.iter().map(|d| d.1).collect();
        let mut diffusion = Diffusion::new(
            &sc.mesh.positions,
            &sc.mesh.faces,
            &sc.thickness,
            &dirs,
            Diffusivity {
                along: mo.diffusivity_along,
                across: mo.diffusivity_across,
                through: mo.diffusivity_through,
            },
            mo.layers,
        )?;
        // Sides sealed on purpose (tape): the ground exchange leaves them sealed.
        let mut taped = vec![[false; 2]; sc.num_faces()];
        // Sides covered by tape (`tape = true`): a non-swelling layer for the growth law.
        let mut tape = vec![[false; 2]; sc.num_faces()];
        for b in &mo.boundary {
            let side = match b.side {
                SurfaceSide::Top => Side::Top,
                SurfaceSide::Bottom => Side::Bottom,
            };
            let bc = match b.kind {
                SurfaceKind::Sealed => SurfaceBc::Sealed,
                SurfaceKind::Value => SurfaceBc::Value(b.value),
                SurfaceKind::Flux => SurfaceBc::Flux(b.value),
                SurfaceKind::Robin => SurfaceBc::Robin {
                    k: b.k,
                    ambient: b.ambient,
                },
            };
            let faces = crate::scene::region_faces(&sc.mesh, b)
                .map_err(|e| RunError::Moisture(e.to_string()))?;
            for f in faces {
                diffusion
                    .set_surface(f, side, bc)
                    .map_err(RunError::Moisture)?;
                if bc == SurfaceBc::Sealed {
                    taped[f][side as usize] = true;
                }
                if b.tape {
                    tape[f][side as usize] = true;
                }
            }
        }
        let u = vec![mo.initial; diffusion.num_nodes()];
        let nf = sc.num_faces();
        let base = (0..nf)
            .map(|f| {
                [
                    diffusion.surface(f, Side::Top),
                    diffusion.surface(f, Side::Bottom),
                ]
            })
            .collect();
        let h_mean = sc.thickness.iter().sum::<Real>() / nf.max(1) as Real;
        let ground = mo
            .ground
            .as_ref()
            .map(|g| (g.k, g.value, g.distance.or(h_mean)));
        let mut m = Moisture {
            trial: u.clone(),
            u,
            diffusion,
            change: 0.0,
            mass: Vec::new(),
            trial_mass: Vec::new(),
            base,
            taped,
            tape,
            ground,
            touching: vec![[false; 2]; nf],
        };
        m.mass = m.masses_of(sc, &m.u);
        m.trial_mass = m.mass.clone();
        Ok(Some(m))
    }

    /// Switches the ground exchange of every face side on or off from the positions `x`: a side
    /// touches when it faces the ground (its outward normal within 60° of the ground's inward
    /// one) and the face's centroid is within `distance` of the ground, thickness included.
    fn update_ground(&mut self, sc: &Scene, x: &[Vec3]) -> Result<(), String> {
        use crate::diffusion::{Side, SurfaceBc};
        let (Some((k, value, distance)), Some(g)) = (self.ground, &sc.ground) else {
            return Ok(());
        };
        for (f, face) in sc.mesh.faces.iter().enumerate() {
            let [p0, p1, p2] = face.map(|v| x[v]);
            let n = (p1 - p0).cross(&(p2 - p0)).normalize();
            let c = (p0 + p1 + p2) / 3.0;
            let facing = n.dot(&g.normal);
            let gap = g.normal.dot(&(c - g.point)) - 0.5 * sc.thickness[f] * facing.abs();
            let near = gap <= distance && facing.abs() >= 0.5;
            // The top (+n) faces the ground when n points into it.
            let touch = [near && facing < 0.0, near && facing > 0.0];
            for (s, side) in [Side::Top, Side::Bottom].into_iter().enumerate() {
                if touch[s] == self.touching[f][s] {
                    continue;
                }
                let base = self.base[f][s];
                if self.taped[f][s] || matches!(base, SurfaceBc::Value(_)) {
                    continue;
                }
                let bc = if touch[s] {
                    SurfaceBc::Robin { k, ambient: value }
                } else {
                    base
                };
                self.diffusion.replace_surface(f, side, bc)?;
                self.touching[f][s] = touch[s];
            }
        }
        Ok(())
    }

    /// Lumped vertex masses with face densities ρ_shell + (m⁺ + m⁻)/2 · ρ_water (seed 000 §3,
    /// "Mass Matrix"); empty when the water density is 0 (the scene's masses apply).
    fn masses_of(&self, sc: &Scene, u: &[Real]) -> Vec<Real> {
        let rho_w = sc.settings.moisture.water_density;
        if rho_w == 0.0 {
            return Vec::new();
        }
        let mut mass = sc.mass.clone();
        for (f, face) in sc.mesh.faces.iter().enumerate() {
            let (top, bottom) = self.diffusion.surface_moisture(u, f);
            let area = sc.mesh.face_area(f);
            let dm = 0.5 * (top + bottom) * rho_w * sc.thickness[f] * area / 3.0;
            for &v in face {
                mass[v] += dm;
            }
        }
        mass
    }

    /// The masses at the accepted state (`trial = false`) or the trial one (the scene's without
    /// water density).
    fn mass<'s>(&'s self, sc: &'s Scene, trial: bool) -> &'s [Real] {
        let m = if trial { &self.trial_mass } else { &self.mass };
        if m.is_empty() {
            &sc.mass
        } else {
            m
        }
    }

    /// Rest forms of every face from the moisture `u`.
    ///
    /// A taped side (`moisture.boundary.tape`) is a layer that does not swell: the law sees
    /// moisture 0 there, so wet paper under tape curls away from it as a bilayer does.
    fn targets_of(&self, sc: &Scene, u: &[Real]) -> Result<Vec<(Sym2, Sym2)>, String> {
        (0..sc.num_faces())
            .map(|f| {
                let (mut top, mut bottom) = self.diffusion.surface_moisture(u, f);
                if self.tape[f][0] {
                    top = 0.0;
                }
                if self.tape[f][1] {
                    bottom = 0.0;
                }
                let m = (top, bottom);
                let reference = (sc.rest.abar0[f], sc.rest.bbar0[f]);
                crate::scene::growth_face(
                    &sc.settings,
                    &sc.growth,
                    f,
                    reference,
                    sc.thickness[f],
                    m,
                )
                .map_err(|e| format!("growth at face {f}: {e}"))
            })
            .collect()
    }

    /// Hands the surface moisture of the accepted state to the writer for the next frame.
    fn publish(&self, writer: &mut Writer) {
        let nf = writer.num_faces();
        let (mut top, mut bottom) = (Vec::with_capacity(nf), Vec::with_capacity(nf));
        for f in 0..nf {
            let (a, b) = self.diffusion.surface_moisture(&self.u, f);
            top.push(a);
            bottom.push(b);
        }
        writer.set_face_field("moisture_top", top);
        writer.set_face_field("moisture_bottom", bottom);
    }
}

/// The potential of the accepted state of a dynamic run: with moisture, its rest forms
/// `targets` and its wet masses.
fn accepted<'a>(
    base: Potential<'a>,
    moisture: Option<&'a Moisture>,
    targets: &'a [(Sym2, Sym2)],
) -> Potential<'a> {
    match moisture {
        Some(m) => Potential {
            rest_override: Some(targets),
            mass: m.mass(base.scene, false),
            ..base
        },
        None => base,
    }
}

/// Receives progress updates (a terminal progress bar, or nothing).
pub trait Progress {
    /// Called after every accepted step with (progress in [0, 1], label).
    fn update(&mut self, fraction: Real, message: &str);
}

/// A progress sink that ignores everything.
pub struct Quiet;
impl Progress for Quiet {
    fn update(&mut self, _: Real, _: &str) {}
}

/// Area-weighted vertex normals.
pub fn vertex_normals(scene: &Scene, x: &[Vec3]) -> Vec<Vec3> {
    let mut n = vec![Vec3::zeros(); x.len()];
    for f in &scene.mesh.faces {
        let c = (x[f[1]] - x[f[0]]).cross(&(x[f[2]] - x[f[0]]));
        for &v in f {
            n[v] += c;
        }
    }
    for v in &mut n {
        let l = v.norm();
        if l > 0.0 {
            *v /= l;
        }
    }
    n
}

/// True when all face normals are parallel (the sheet is planar).
pub fn is_planar(scene: &Scene, x: &[Vec3]) -> bool {
    let mut n0: Option<Vec3> = None;
    for f in &scene.mesh.faces {
        let c = (x[f[1]] - x[f[0]]).cross(&(x[f[2]] - x[f[0]])).normalize();
        match n0 {
            None => n0 = Some(c),
            Some(n) => {
                if n.dot(&c) < 1.0 - 1e-12 {
                    return false;
                }
            }
        }
    }
    true
}

/// Moves free vertices along their normals by `amp × u`, u uniform in [−1, 1) (seeded).
pub fn perturb(scene: &Scene, x: &mut [Vec3], amp: Real, seed: u64) {
    let normals = vertex_normals(scene, x);
    let mut rng = Rng::new(seed);
    for (v, p) in x.iter_mut().enumerate() {
        let u = rng.symmetric();
        if !scene.fixed[v] {
            *p += normals[v] * (amp * u);
        }
    }
}

struct Solver<'a> {
    scene: &'a Scene,
    pattern: &'a Pattern,
    lin: LinearSolver,
    ws: Workspace,
    gravity: Vec3,
    summary: Summary,
    start: Instant,
    /// The summary's counters when the previous frame was written; log rows report the
    /// differences.
    at_last_frame: Counters,
}

/// Counters that log rows report per frame.
#[derive(Clone, Copy, Default)]
struct Counters {
    newton: usize,
    steps: usize,
    shifted: usize,
    gauss_newton: usize,
    rejected: usize,
}

impl Counters {
    fn of(s: &Summary) -> Self {
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
    fn new(scene: &'a Scene, pattern: &'a Pattern, threads: usize) -> Result<Self, RunError> {
        let lin = LinearSolver::new(pattern)?;
        let ws = Workspace::new(pattern);
        let summary = Summary {
            mode: match scene.settings.solver.mode {
                Mode::Static => "static",
                Mode::Dynamic => "dynamic",
            }
            .into(),
            vertices: scene.num_vertices(),
            faces: scene.num_faces(),
            threads,
            warnings: scene.warnings.clone(),
            ..Default::default()
        };
        Ok(Solver {
            scene,
            pattern,
            lin,
            ws,
            gravity: Vec3::from(scene.settings.loads.gravity),
            summary,
            start: Instant::now(),
            at_last_frame: Counters::default(),
        })
    }

    fn potential(&self, dial: Real) -> Potential<'a> {
        self.potential_scaled(dial, 1.0)
    }

    fn potential_scaled(&self, dial: Real, stretch_scale: Real) -> Potential<'a> {
        Potential {
            dial,
            gravity: self.gravity,
            stretch_scale,
            ..Potential::new(self.scene, self.pattern)
        }
    }

    fn record(&mut self, rep: &NewtonReport) {
        self.summary.newton_iterations += rep.iterations;
        self.summary.shifted_iterations += rep.shifted_iterations;
        self.summary.gauss_newton_iterations += rep.gauss_newton_iterations;
        self.summary.residual = rep.residual;
    }

    fn frame(
        &mut self,
        writer: &mut Writer,
        pot: &Potential,
        x: &[Vec3],
        phi: &[Real],
        v: &[Vec3],
        time: Real,
    ) -> Result<(), RunError> {
        let (now, last) = (Counters::of(&self.summary), self.at_last_frame);
        let row = LogRow {
            frame: 0,
            time,
            dial: pot.dial,
            energy: Default::default(),
            observables: Vec::new(),
            residual: self.summary.residual,
            newton_iterations: now.newton - last.newton,
            steps: now.steps - last.steps,
            shifted_iterations: now.shifted - last.shifted,
            gauss_newton_iterations: now.gauss_newton - last.gauss_newton,
            rejected_steps: now.rejected - last.rejected,
            wall_seconds: self.start.elapsed().as_secs_f64(),
        };
        self.at_last_frame = now;
        writer.frame(pot, x, phi, v, row)?;
        Ok(())
    }

    /// Tests `H + δI ≻ 0` at `x` (see module doc).
    fn is_stable(&mut self, dial: Real, x: &[Vec3], phi: &[Real]) -> bool {
        let pot = self.potential(dial);
        let mut values = vec![0.0; self.pattern.nnz()];
        let mut g = vec![0.0; self.pattern.n];
        pot.eval(x, phi, Want::Hessian, &mut g, &mut values);
        // One factorisation of H + 1e-9·mean|diag|·I (τ may not grow beyond 1e-9).
        let mut shifted = vec![0.0; values.len()];
        if factor_with_shift_upto(&mut self.lin, &pot, &values, &mut shifted, 1e-9, 1e-9).is_none()
        {
            return false;
        }
        // A dense low-rank part keeps the whole positive definite or not (inertia test).
        let lr = pot.low_rank(x, phi);
        lr.is_empty()
            || crate::solve::low_rank::Woodbury::new(&mut self.lin, &lr).keeps_positive_definite()
    }
}

/// A state to start from instead of the reference mesh (a restart).
#[derive(Clone, Debug)]
pub struct InitialState {
    /// Positions (m).
    pub x: Vec<Vec3>,
    /// Edge DOFs (rad), empty without them.
    pub phi: Vec<Real>,
    /// Velocities (m/s), for dynamics; `None` starts at rest.
    pub v: Option<Vec<Vec3>>,
    /// Time (dynamics, s) or dial factor (statics) to resume from.
    pub time: Real,
}

/// Runs a scene to completion from the reference mesh, or from `initial` (a restart), writing
/// frames, the log and the summary.
pub fn run(
    scene: &Scene,
    writer: &mut Writer,
    progress: &mut dyn Progress,
    threads: usize,
    initial: Option<InitialState>,
) -> Result<Summary, RunError> {
    let pattern = Pattern::for_scene(scene);
    let mut s = Solver::new(scene, &pattern, threads)?;
    let (mut x, phi, v, start) = match initial {
        Some(st) => (st.x, st.phi, st.v, Some(st.time)),
        None => (
            scene.mesh.positions.clone(),
            vec![0.0; scene.num_edge_dofs()],
            None,
            None,
        ),
    };
    let sb = scene.settings.solver.symmetry_breaking;
    if sb > 0.0 && is_planar(scene, &x) {
        perturb(
            scene,
            &mut x,
            sb * scene.mean_edge,
            scene.settings.solver.seed,
        );
    }
    match scene.settings.solver.mode {
        Mode::Static => run_static(&mut s, writer, progress, x, phi, start)?,
        Mode::Dynamic => run_dynamic(&mut s, writer, progress, x, phi, v, start.unwrap_or(0.0))?,
    }
    s.summary.wall_seconds = s.start.elapsed().as_secs_f64();
    s.summary.frames = writer.num_frames();
    s.summary.final_frame = writer.last_frame();
    writer.summary(&s.summary)?;
    Ok(s.summary)
}

fn run_static(
    s: &mut Solver,
    writer: &mut Writer,
    progress: &mut dyn Progress,
    mut x: Vec<Vec3>,
    mut phi: Vec<Real>,
    restart: Option<Real>,
) -> Result<(), RunError> {
    let st = &s.scene.settings.solver;
    let (tol, max_iter) = (st.tolerance, st.max_newton_iterations);
    let (min_step, sb, seed) = (st.min_continuation_step, st.symmetry_breaking, st.seed);
    let (check, max_escapes) = (st.check_stability, st.max_saddle_escapes);
    let cont_frames = s.scene.settings.output.continuation_frames;
    let zeros = vec![Vec3::zeros(); x.len()];
    let dial_start = restart.unwrap_or(0.0).clamp(0.0, 1.0);
    {
        let pot = s.potential(dial_start);
        s.frame(writer, &pot, &x, &phi, &zeros, dial_start)?;
    }
    let mut dial = dial_start;
    // A restart solves at least once, even from a frame at dial 1 (the settings may differ).
    let mut need_solve = restart.is_some();
    let mut step = st.continuation_step;
    // Membrane continuation: the stretching weight starts at 1/softening and grows ×ratio per
    // solve once the dial is at 1 (see the module doc).
    let h_min = s
        .scene
        .thickness
        .iter()
        .copied()
        .fold(Real::INFINITY, Real::min);
    // A softened membrane under external loads or prescribed displacements would follow a
    // different (much softer) path: "auto" keeps the continuation for rest-form programming only.
    let loaded = s.scene.settings.loads.any_external() || !s.scene.prescribed.is_empty();
    let softening = match st.membrane_continuation {
        crate::settings::Softening::Auto(_) if loaded => 1.0,
        m => m.factor(s.scene.mesh.bbox_diagonal(), h_min),
    };
    let mut scale = 1.0 / softening.max(1.0);
    let mut ratio: Real = 10.0;
    let mut trial = x.clone();
    let mut trial_phi = phi.clone();
    let mut failure: Option<String> = None;
    while dial < 1.0 || scale < 1.0 || need_solve {
        let (target, target_scale) = if dial < 1.0 {
            ((dial + step).min(1.0), scale)
        } else {
            (1.0, (scale * ratio).min(1.0))
        };
        // Intermediate continuation steps need not be solved to full accuracy.
        let t = if target < 1.0 || target_scale < 1.0 {
            (tol * 1e3).min(1e-5).max(tol)
        } else {
            tol
        };
        trial.copy_from_slice(&x);
        trial_phi.copy_from_slice(&phi);
        s.scene.prescribe(&mut trial, target);
        let pot = s.potential_scaled(target, target_scale);
        let rep = newton(
            &pot,
            &mut s.lin,
            &mut s.ws,
            &mut trial,
            &mut trial_phi,
            NewtonOptions { tol: t, max_iter },
        );
        s.record(&rep);
        // A term tracking a state across steps (a moment's angle) may refuse a step too large
        // for it; the step is then cut like a failed solve.
        let admissible = rep.converged && s.scene.admissible(&trial, &trial_phi);
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
            x.copy_from_slice(&trial);
            phi.copy_from_slice(&trial_phi);
            s.scene.accept(&x, &phi);
            let grow = rep.iterations <= 5;
            if dial < 1.0 {
                dial = target;
                if grow {
                    step = (step * 2.0).min(1.0);
                }
            } else {
                scale = target_scale;
                if grow {
                    ratio = (ratio * ratio).min(1e3);
                }
            }
            need_solve = false;
            s.summary.steps += 1;
            progress.update(
                dial,
                &format!("dial {dial:.4} E {:.4e} r {:.1e}", rep.energy, rep.residual),
            );
            if cont_frames && dial < 1.0 {
                let pot = s.potential(dial);
                s.frame(writer, &pot, &x, &phi, &zeros, dial)?;
            }
        } else if dial < 1.0 {
            s.summary.rejected_steps += 1;
            step *= 0.5;
            if step < min_step {
                failure = Some(format!(
                    "continuation step fell below {min_step} at dial {dial:.6}: {}",
                    rep.failure_text()
                ));
                break;
            }
        } else {
            s.summary.rejected_steps += 1;
            ratio = ratio.sqrt();
            if ratio < 1.01 {
                failure = Some(format!(
                    "membrane continuation stalled at stretching weight {scale:.3e}: {}",
                    rep.failure_text()
                ));
                break;
            }
        }
    }
    if failure.is_none() && check {
        let mut escapes = 0;
        while !s.is_stable(1.0, &x, &phi) {
            if escapes >= max_escapes {
                failure = Some(format!(
                    "equilibrium is a saddle (Hessian indefinite) after {escapes} perturbations"
                ));
                break;
            }
            escapes += 1;
            let amp = sb.max(1e-3) * s.scene.mean_edge * 10f64.powi(escapes as i32);
            perturb(s.scene, &mut x, amp, seed.wrapping_add(escapes as u64));
            let pot = s.potential(1.0);
            let rep = newton(
                &pot,
                &mut s.lin,
                &mut s.ws,
                &mut x,
                &mut phi,
                NewtonOptions {
                    tol,
                    max_iter: max_iter * 5,
                },
            );
            s.record(&rep);
            if !rep.converged {
                failure = Some(format!("after escaping a saddle: {}", rep.failure_text()));
                break;
            }
        }
        s.summary.saddle_escapes = escapes;
    }
    s.summary.dial = dial;
    s.summary.converged = failure.is_none();
    s.summary.reason = failure.unwrap_or_default();
    let pot = s.potential(dial);
    s.summary.energy = Writer::energies(&pot, &x, &phi, &zeros);
    s.frame(writer, &pot, &x, &phi, &zeros, 1.0_f64.max(dial))?;
    Ok(())
}

fn run_dynamic(
    s: &mut Solver,
    writer: &mut Writer,
    progress: &mut dyn Progress,
    mut x: Vec<Vec3>,
    mut phi: Vec<Real>,
    v0: Option<Vec<Vec3>>,
    t0: Real,
) -> Result<(), RunError> {
    let sc = s.scene;
    let tm = sc.settings.time.clone();
    let (tol, max_iter) = (
        sc.settings.solver.tolerance,
        sc.settings.solver.max_newton_iterations,
    );
    let dial_time = sc.settings.rest.dial_time;
    let dial_at = |t: Real| {
        if dial_time > 0.0 {
            (t / dial_time).min(1.0)
        } else {
            1.0
        }
    };
    let n = x.len();
    let mut v = v0.unwrap_or_else(|| vec![Vec3::zeros(); n]);
    let mut xhat = x.clone();
    let mut trial = x.clone();
    let mut trial_phi = phi.clone();
    let damping = tm.damping > 0.0;
    let (mut a_prev, mut b_prev) = if damping {
        sc.forms(&x, &phi)
    } else {
        (Vec::new(), Vec::new())
    };
    // Moisture: the diffusion state and the rest forms it sets (None without diffusion).
    let mut moisture = Moisture::new(sc)?;
    let mut targets: Vec<(Sym2, Sym2)> = Vec::new();
    let mut trial_targets: Vec<(Sym2, Sym2)> = Vec::new();
    if let Some(m) = &moisture {
        targets = m.targets_of(sc, &m.u).map_err(RunError::Moisture)?;
        m.publish(writer);
    }
    {
        let pot = accepted(s.potential(dial_at(t0)), moisture.as_ref(), &targets);
        s.frame(writer, &pot, &x, &phi, &v, t0)?;
    }
    // Friction: the lagged normal forces, carried from step to step.
    let friction = sc.ground.as_ref().is_some_and(|g| g.friction > 0.0);
    let mut lambda = match &sc.ground {
        Some(g) if friction => g.normal_forces(&x),
        _ => Vec::new(),
    };
    let mut t = t0;
    let mut dt = tm.dt;
    // The next output time after the start (a restart resumes the output grid).
    let mut next_out = (((t0 / tm.output_interval) + 1e-9).floor() + 1.0) * tm.output_interval;
    next_out = next_out.min(tm.end);
    let mut easy = 0;
    let mut failure: Option<String> = None;
    let eps_t = 1e-12 * tm.end;
    while t < tm.end - eps_t {
        let h = dt.min(next_out - t).min(tm.end - t);
        let dial = dial_at(t + h);
        for i in 0..n {
            xhat[i] = x[i] + v[i] * h;
        }
        // Vertices on prescribed paths are fixed: their inertia is not assembled, so the
        // prediction can carry their prescribed position into every trial.
        sc.prescribe(&mut xhat, dial);
        trial.copy_from_slice(&xhat);
        trial_phi.copy_from_slice(&phi);
        let moisture_clock = Instant::now();
        if let Some(m) = &mut moisture {
            // Diffuse over the step, then set the rest forms from the new surface moisture.
            if let Err(e) = m.update_ground(sc, &x) {
                failure = Some(format!("moisture at t = {t:.6e}: {e}"));
                break;
            }
            m.trial.copy_from_slice(&m.u);
            if let Err(e) = m.diffusion.step(&mut m.trial, h) {
                failure = Some(format!("moisture diffusion at t = {t:.6e}: {e}"));
                break;
            }
            // The step control sees the diffusion too: a step that changes the computed moisture
            // (prescribed nodes excluded: their jump is imposed) by more than
            // moisture.max_change anywhere is cut before the mechanical solve.
            m.change = (0..m.u.len())
                .filter(|&i| !m.diffusion.is_prescribed(i))
                .fold(0.0, |c: Real, i| c.max((m.trial[i] - m.u[i]).abs()));
            if m.change > sc.settings.moisture.max_change && h > tm.dt_min {
                s.summary.moisture_seconds += moisture_clock.elapsed().as_secs_f64();
                s.summary.rejected_steps += 1;
                dt = (h * 0.5).max(tm.dt_min);
                easy = 0;
                continue;
            }
            match m.targets_of(sc, &m.trial) {
                Ok(tt) => trial_targets = tt,
                Err(e) => {
                    failure = Some(format!("at t = {t:.6e}: {e}"));
                    break;
                }
            }
            m.trial_mass = m.masses_of(sc, &m.trial);
            s.summary.moisture_seconds += moisture_clock.elapsed().as_secs_f64();
        }
        let trial_mass = moisture.as_ref().map_or(&sc.mass[..], |m| m.mass(sc, true));
        // Friction lags the normal force: solve with λ, update λ from the solution, and re-solve
        // until it agrees (see solve::contact).
        let mut rep;
        let mut lag = 0;
        loop {
            let pot = Potential {
                dial,
                inertia: Some(Inertia {
                    inv_dt2: 1.0 / (h * h),
                    xhat: &xhat,
                }),
                damping: damping.then_some(Damping {
                    eta_over_dt: tm.damping / h,
                    a_prev: &a_prev,
                    b_prev: &b_prev,
                }),
                gravity: s.gravity,
                rest_override: moisture.as_ref().map(|_| &trial_targets[..]),
                mass: trial_mass,
                friction: friction.then_some(Friction {
                    x_prev: &x,
                    normal_force: &lambda,
                    eps: sc.settings.contact.slip_speed * h,
                }),
                ..Potential::new(sc, s.pattern)
            };
            rep = newton(
                &pot,
                &mut s.lin,
                &mut s.ws,
                &mut trial,
                &mut trial_phi,
                NewtonOptions { tol, max_iter },
            );
            s.record(&rep);
            let Some(ground) = sc.ground.as_ref().filter(|_| friction && rep.converged) else {
                break;
            };
            let new = ground.normal_forces(&trial);
            let scale = new.iter().fold(0.0, |m: Real, v| m.max(*v));
            let diff = new
                .iter()
                .zip(&lambda)
                .fold(0.0, |m: Real, (a, b)| m.max((a - b).abs()));
            lambda.copy_from_slice(&new);
            lag += 1;
            if diff <= FRICTION_LAG_TOL * scale || lag >= FRICTION_LAG_MAX {
                break;
            }
        }
        if !rep.converged {
            s.summary.rejected_steps += 1;
            dt = h * 0.5;
            easy = 0;
            if dt < tm.dt_min {
                failure = Some(format!(
                    "time step fell below dt_min = {} at t = {t:.6e}: {}",
                    tm.dt_min,
                    rep.failure_text()
                ));
                break;
            }
            continue;
        }
        for i in 0..n {
            v[i] = (trial[i] - x[i]) / h;
        }
        x.copy_from_slice(&trial);
        sc.accept(&trial, &trial_phi);
        phi.copy_from_slice(&trial_phi);
        if let Some(m) = &mut moisture {
            m.u.copy_from_slice(&m.trial);
            std::mem::swap(&mut targets, &mut trial_targets);
            std::mem::swap(&mut m.mass, &mut m.trial_mass);
        }
        t += h;
        s.summary.steps += 1;
        if damping {
            let (a, b) = sc.forms(&x, &phi);
            a_prev = a;
            b_prev = b;
        }
        let calm = moisture
            .as_ref()
            .is_none_or(|m| m.change <= 0.5 * sc.settings.moisture.max_change);
        if rep.iterations <= 3 && calm {
            easy += 1;
            if easy >= 3 {
                dt = (dt * 1.5).min(tm.dt_max);
                easy = 0;
            }
        } else {
            easy = 0;
        }
        progress.update(
            t / tm.end,
            &format!("t {t:.4e} s  E {:.4e}  r {:.1e}", rep.energy, rep.residual),
        );
        let at_output = t >= next_out - 1e-9 * h.max(eps_t);
        let mut stop = false;
        if tm.stop_at_equilibrium {
            let pot = accepted(s.potential(dial), moisture.as_ref(), &targets);
            let mut g = vec![0.0; s.pattern.n];
            pot.eval(&x, &phi, Want::Gradient, &mut g, &mut []);
            let r = pot.residual(&g);
            let en = Writer::energies(&pot, &x, &phi, &v);
            stop = dial >= 1.0
                && r <= tol
                && en.kinetic
                    <= tm.equilibrium_kinetic
                        * (en.get("stretching").unwrap_or(0.0) + en.get("bending").unwrap_or(0.0))
                            .max(Real::MIN_POSITIVE);
        }
        if at_output || stop || t >= tm.end - eps_t {
            if let Some(m) = &moisture {
                m.publish(writer);
            }
            let pot = accepted(s.potential(dial), moisture.as_ref(), &targets);
            s.frame(writer, &pot, &x, &phi, &v, t)?;
            while next_out <= t + eps_t {
                next_out += tm.output_interval;
            }
            next_out = next_out.min(tm.end);
        }
        if stop {
            break;
        }
    }
    s.summary.time = t;
    s.summary.dial = dial_at(t);
    s.summary.converged = failure.is_none();
    s.summary.reason = failure.unwrap_or_default();
    let pot = accepted(s.potential(dial_at(t)), moisture.as_ref(), &targets);
    s.summary.energy = Writer::energies(&pot, &x, &phi, &v);
    if s.summary.reason.is_empty() {
        return Ok(());
    }
    // Record the state reached when the run stopped early.
    s.frame(writer, &pot, &x, &phi, &v, t)?;
    Ok(())
}
