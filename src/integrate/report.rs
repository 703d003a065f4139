//! What a run reports: its energies, one row of `log.csv` per frame ([`LogRow`]), the summary
//! ([`Summary`], `summary.json`), and the errors of the output it writes to ([`OutputError`]).
//! The drivers fill these records and hand them to their [`crate::integrate::Sink`]; the
//! output module writes them.

use crate::energy::Potential;
use crate::math::{Real, Vec3};
use crate::solve::State;
use serde::Serialize;

/// Errors while writing output.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    /// A file or folder could not be written.
    #[error("{path}: {reason}")]
    Io {
        /// The path.
        path: String,
        /// Why.
        reason: String,
    },
    /// The folder holds the output of an earlier run.
    #[error(
        "{path} holds the output of an earlier run ({what}); pass --overwrite to replace it, or \
         choose another --out"
    )]
    Used {
        /// The folder.
        path: String,
        /// What is there.
        what: String,
    },
    /// Another run writes into the folder.
    #[error(
        "{path}: another shellsim run (process {pid}) is writing into this folder; wait for it \
         or choose another --out (remove {path}/.shellsim.lock if that process is not shellsim)"
    )]
    Locked {
        /// The folder.
        path: String,
        /// The process holding the lock.
        pid: u32,
    },
    /// A frame contained NaN or infinity; it was not written.
    #[error(
        "frame {index} at t = {} would hold a non-finite value in '{field}; not written",
        crate::math::human(*.time)
    )]
    NonFinite {
        /// Frame index.
        index: usize,
        /// Time.
        time: Real,
        /// The field.
        field: String,
    },
}

/// Energies of a state by term (J): `total`, then each reported term under its own name (in
/// the scene's term order), then `kinetic` (½ Σ m |v|²).
#[derive(Clone, Debug, Default)]
pub struct Energies {
    /// Sum of the terms and the kinetic energy.
    pub total: Real,
    /// The terms' energies by name.
    pub terms: Vec<(&'static str, Real)>,
    /// Kinetic energy ½ Σ m |v|².
    pub kinetic: Real,
}

impl Energies {
    /// The energy reported under `name` (`"total"`, a term's name, `"kinetic"`).
    pub fn get(&self, name: &str) -> Option<Real> {
        match name {
            "total" => Some(self.total),
            "kinetic" => Some(self.kinetic),
            _ => self.terms.iter().find(|t| t.0 == name).map(|t| t.1),
        }
    }

    /// `(name, value)` pairs in column order.
    pub fn columns(&self) -> Vec<(&str, Real)> {
        let mut c = vec![("total", self.total)];
        c.extend(self.terms.iter().copied());
        c.push(("kinetic", self.kinetic));
        c
    }
}

impl Serialize for Energies {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        // A run stopped by a non-finite state may hold non-finite energies: they are left
        // out, never written as `null`.
        let cols: Vec<_> = self
            .columns()
            .into_iter()
            .filter(|(_, v)| v.is_finite())
            .collect();
        let mut m = s.serialize_map(Some(cols.len()))?;
        for (k, v) in cols {
            m.serialize_entry(k, &v)?;
        }
        m.end()
    }
}

/// One row of the per-frame log.
#[derive(Clone, Debug, Default, Serialize)]
pub struct LogRow {
    /// Frame index.
    pub frame: usize,
    /// Simulated time (s); in static mode the dial factor, and `log.csv` has no time column.
    pub time: Real,
    /// Dial factor of the rest forms.
    pub dial: Real,
    /// Energies.
    #[serde(flatten)]
    pub energy: Energies,
    /// Quantities the terms log (load–displacement measures), by column name.
    #[serde(skip)]
    pub observables: Vec<(String, Real)>,
    /// The driver's own columns (the arc-length path: `arc_length`, `negative_eigenvalues`,
    /// `critical_point`), before the reactions.
    #[serde(skip)]
    pub path: Vec<(String, Real)>,
    /// Each support's total reaction ([`reactions`]).
    #[serde(skip)]
    pub reactions: Vec<Reaction>,
    /// The reaction at every vertex (N; zero where nothing is held).
    #[serde(skip)]
    pub reaction_field: Vec<Vec3>,
    /// Relative residual ‖∇Φ‖∞/F of the last solve.
    pub residual: Real,
    /// Newton iterations since the previous frame.
    pub newton_iterations: usize,
    /// Steps (time steps or continuation steps) since the previous frame.
    pub steps: usize,
    /// Newton iterations since the previous frame that needed a diagonal shift.
    pub shifted_iterations: usize,
    /// Newton iterations since the previous frame that fell back to the Gauss–Newton Hessian.
    pub gauss_newton_iterations: usize,
    /// Steps rejected (and cut) since the previous frame.
    pub rejected_steps: usize,
    /// Wall time since the start (s).
    pub wall_seconds: Real,
}

fn not_finite(v: &Real) -> bool {
    !v.is_finite()
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// The run summary written to `summary.json`.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Summary {
    /// Whether the run reached its goal (static: a stable equilibrium at dial 1; dynamic: the end
    /// time, or equilibrium when asked to stop there).
    pub converged: bool,
    /// Why it stopped, when not converged.
    pub reason: String,
    /// `"static"` or `"dynamic"`.
    pub mode: String,
    /// Last frame, relative to the output folder.
    pub final_frame: String,
    /// Frames written.
    pub frames: usize,
    /// Wall time (s).
    pub wall_seconds: Real,
    /// Accepted steps (time steps or continuation steps).
    pub steps: usize,
    /// Rejected steps (cut after a failed Newton solve).
    pub rejected_steps: usize,
    /// Total Newton iterations.
    pub newton_iterations: usize,
    /// Newton iterations that needed a diagonal shift.
    pub shifted_iterations: usize,
    /// Newton iterations that fell back to the Gauss–Newton Hessian.
    pub gauss_newton_iterations: usize,
    /// Newton iterations that solved with an earlier iteration's factorisation (chord
    /// iterations of the implicit dynamics).
    pub chord_iterations: usize,
    /// Checks of convergence made with the gradient alone, the residual predicted below the
    /// tolerance (a converged one ends its solve without assembling the Hessian).
    pub gradient_only_checks: usize,
    /// Newton iterations whose sparse Hessian part was indefinite and made positive definite
    /// by a dense low-rank part (an enclosed gas past a pressure limit point).
    pub indefinite_iterations: usize,
    /// Saddle points detected and escaped by perturbation.
    pub saddle_escapes: usize,
    /// Steps before which a term's elements changed (a new sparsity pattern); left out when 0.
    #[serde(skip_serializing_if = "is_zero")]
    pub element_changes: usize,
    /// Of those, the ones that changed the union of the stencils (a new symbolic
    /// factorisation); left out when 0.
    #[serde(skip_serializing_if = "is_zero")]
    pub pattern_rebuilds: usize,
    /// Vertices.
    pub vertices: usize,
    /// Faces.
    pub faces: usize,
    /// Worker threads.
    pub threads: usize,
    /// Final simulated time (s); absent in static runs, whose progress is the dial.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time: Option<Real>,
    /// Final dial factor.
    pub dial: Real,
    /// Hold points of `dial.holds` at which the run reached equilibrium.
    pub holds_reached: usize,
    /// Final relative residual (left out when it is not finite).
    #[serde(skip_serializing_if = "not_finite")]
    pub residual: Real,
    /// Final energies.
    pub energy: Energies,
    /// Wall time spent in the moisture diffusion and the rest forms it sets (s; 0 without
    /// `[moisture]`): the coupled step's cost over the mechanics alone is
    /// `wall / (wall − moisture_seconds)`.
    pub moisture_seconds: Real,
    /// Accepted and rejected error-controlled diffusion sub-steps, and the numeric
    /// factorisations they needed (0 without `[moisture]`).
    pub diffusion_substeps: usize,
    /// See `diffusion_substeps`.
    pub diffusion_rejected: usize,
    /// See `diffusion_substeps`.
    pub diffusion_factorisations: usize,
    /// Conjugate-gradient iterations of the diffusion solves, and the solves done by the
    /// sparse Cholesky instead (strong lateral coupling).
    pub diffusion_cg_iterations: usize,
    /// See `diffusion_cg_iterations`.
    pub diffusion_direct_solves: usize,
    /// Warnings raised while loading.
    pub warnings: Vec<String>,
    /// Where the wall time went (s).
    pub timing: Timing,
    /// The mechanics' sparse linear system: its size, ordering, factor and factorisations
    /// (left out in explicit runs, which factorise nothing).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub linear_system: Option<LinearSystemReport>,
    /// Explicit mode: its time step, time scales and cost.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub explicit: Option<ExplicitReport>,
    /// The residual's force scale F (N): `max(E h) × mean edge`, or in statics the largest
    /// applied nodal load when smaller.
    pub force_scale: Real,
    /// The amplitude of the symmetry-breaking perturbation of a planar start (m): every free
    /// vertex moved along its normal by up to this much after the first frame.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub symmetry_breaking: Option<Real>,
    /// Each support's total reaction at the last frame (none without supports).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub reactions: Vec<Reaction>,
    /// Arc-length continuation: the path traced and its critical points.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arc_length: Option<ArcLengthReport>,
}

/// The mechanics' sparse linear system (`summary.json`'s `linear_system`).
#[derive(Clone, Debug, Default, Serialize)]
pub struct LinearSystemReport {
    /// Unknowns of the last pattern.
    pub unknowns: usize,
    /// Its fill-reducing ordering: `"amd"` or `"nested_dissection"`, the one with fewer flops.
    pub ordering: String,
    /// Non-zeros of the Cholesky factor L.
    pub factor_nonzeros: usize,
    /// Flops of one numeric factorisation (Σ over L's columns of the squared count).
    pub factor_flops: Real,
    /// Numeric factorisations over the run (all patterns), and of those the failed ones (a
    /// non-positive pivot: an indefinite Hessian tried before its fallback).
    pub factorisations: usize,
    /// See `factorisations`.
    pub failed_factorisations: usize,
    /// Factorisations per accepted step.
    pub factorisations_per_step: Real,
    /// Newton iterations per accepted step.
    pub iterations_per_step: Real,
}

/// What an arc-length run traced (`summary.json`'s `arc_length`).
#[derive(Clone, Debug, Default, Serialize)]
pub struct ArcLengthReport {
    /// Accepted steps.
    pub steps: usize,
    /// The path coordinate at the end (dial units, see `solver.arc_length_step`).
    pub length: Real,
    /// ψ: the displacement per unit dial of the first tangent (m), which scales the
    /// displacement part of the arc length.
    pub psi: Real,
    /// How the path ended: `"dial 1"`, `"unloaded"` (back at dial 0), `"steps"`
    /// (`solver.max_arc_length_steps`) or `"failed"` (see `reason`).
    pub end: String,
    /// Negative eigenvalues of the Hessian at the last point (0: a stable equilibrium).
    pub negative_eigenvalues: usize,
    /// Limit and bifurcation points passed, in path order.
    pub critical_points: Vec<CriticalPoint>,
}

/// A critical point of an arc-length path.
#[derive(Clone, Debug, Serialize)]
pub struct CriticalPoint {
    /// `"load_maximum"`, `"load_minimum"` (limit points: the dial's extremum along the path)
    /// or `"bifurcation"` (a Hessian eigenvalue crossed zero with the dial still rising or
    /// falling).
    pub kind: String,
    /// Its dial: a limit point's from the cubic Hermite interpolant of the dial along the path
    /// between the two frames around it (values and slopes), a bifurcation's midway between
    /// them.
    pub dial: Real,
    /// Its path coordinate, likewise.
    pub arc_length: Real,
    /// The first frame past it.
    pub frame: usize,
    /// Negative eigenvalues of the Hessian at that frame.
    pub negative_eigenvalues: usize,
}

impl Summary {
    /// Refuses a summary that would hold a non-finite number (serialised as `null`): the run
    /// is marked unconverged (exit 1) with an internal error naming the values, which
    /// [`crate::output::Writer::summary`] leaves out. Returns whether it did.
    pub fn refuse_non_finite(&mut self) -> bool {
        let (_, paths) = summary_json(self);
        if paths.is_empty() {
            return false;
        }
        self.converged = false;
        let was = std::mem::take(&mut self.reason);
        self.reason = format!(
            "internal error: summary.json would hold a non-finite number at {} (left out){}",
            paths.join(", "),
            if was.is_empty() {
                String::new()
            } else {
                format!("; the run stopped: {was}")
            }
        );
        true
    }
}

/// Where a run's wall time went (s): Newton's parts (explicit mode: the force evaluations under
/// `assembly`), the moisture diffusion, writing frames, and the rest (setup, predictors,
/// bookkeeping).
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Timing {
    /// Reading the settings and the mesh, building the scene and checking it, before the run
    /// ([`crate::model::Scene::build_seconds`]).
    pub build: Real,
    /// The sparse Hessian's sparsity pattern and its symbolic analysis (the fill-reducing
    /// ordering, the elimination tree and supernodes), once per pattern (implicit modes).
    pub analysis: Real,
    /// Assembly, factorisation, solve and line search, summed over the Newton solves.
    #[serde(flatten)]
    pub newton: crate::solve::newton::NewtonTiming,
    /// Moisture diffusion and the rest forms it sets.
    pub diffusion: Real,
    /// Building and writing frames, the series and the log.
    pub output: Real,
    /// The wall time not in the above.
    pub other: Real,
}

/// What an explicit run reports in `summary.json` ([`crate::integrate`]'s explicit driver).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct ExplicitReport {
    /// The time step Δt (s).
    pub time_step: Real,
    /// The mesh's measured stability limit of `explicit.time_step_prefactor` (left out when
    /// the stiffness at the start has no positive eigenvalue).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stable_prefactor: Option<Real>,
    /// The long time T (s).
    pub long_time: Real,
    /// The drag rate c while dialling (1/s).
    pub damping_rate_dial: Real,
    /// The drag rate c while waiting (1/s).
    pub damping_rate_wait: Real,
    /// The sample length L (the largest sheet's reference perimeter, m).
    pub sample_length: Real,
    /// The smallest reference altitude a_min (m).
    pub min_altitude: Real,
    /// `"window"` or `"morphoshell"`.
    pub equilibrium_test: String,
    /// Wall time per face and step (µs), the whole loop included.
    pub microseconds_per_face_step: Real,
    /// Hold points at which equilibrium was reached.
    pub holds_reached: usize,
    /// With contact: how many times the pairs and the vertices' displacement bounds were
    /// gathered.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact_gathers: Option<usize>,
    /// With contact: vertex steps pulled back inside their displacement bound.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact_clipped: Option<usize>,
}

/// Energies of a state by term.
pub fn energies(pot: &Potential, state: &State, v: &[Vec3]) -> Energies {
    let pot = &Potential {
        states: &state.terms,
        ..*pot
    };
    energies_of(pot, pot.energies(&state.x, &state.dofs), v)
}

/// The energies record of the terms' energies and the kinetic energy at velocities `v`.
pub fn energies_of(pot: &Potential, terms: Vec<(&'static str, Real)>, v: &[Vec3]) -> Energies {
    let kinetic: Real = v
        .iter()
        .zip(pot.mass)
        .map(|(v, m)| 0.5 * m * v.norm_squared())
        .sum();
    let total = terms.iter().map(|t| t.1).sum::<Real>() + kinetic;
    Energies {
        total,
        terms,
        kinetic,
    }
}

/// The total reaction of one support (`[constraints]` key or list entry): the sum of the forces
/// it exerts on the sheet and their moment about the origin, `Σ x × R`.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Reaction {
    /// The support, as in the settings (`fix_boxes[0]`, `support[1]`, `rigid_pins`, ...).
    pub support: String,
    /// Total force (N).
    pub force: [Real; 3],
    /// Total moment about the origin (N·m).
    pub moment: [Real; 3],
}

impl Reaction {
    /// The support's name in column names: `fix_boxes[0]` → `fix_boxes_0`.
    pub fn column_name(&self) -> String {
        self.support.replace('[', "_").replace(']', "")
    }

    /// `log.csv`'s columns: `reaction_force_NAME_x|y|z` (N) and `reaction_moment_NAME_x|y|z`
    /// (N·m).
    pub fn columns(&self) -> Vec<(String, Real)> {
        let n = self.column_name();
        let mut out = Vec::with_capacity(6);
        for (what, v) in [("force", self.force), ("moment", self.moment)] {
            for (c, x) in ["x", "y", "z"].iter().zip(v) {
                out.push((format!("reaction_{what}_{n}_{c}"), x));
            }
        }
        out
    }
}

/// The reactions of `pot`'s supports at `state`: per vertex ([`Potential::reactions`]) and
/// per support ([`crate::body::Body::supports`]), in the settings' order.
pub fn reactions(pot: &Potential, state: &State) -> (Vec<Vec3>, Vec<Reaction>) {
    let body = pot.body;
    if body.supports.is_empty() {
        return (Vec::new(), Vec::new());
    }
    let pot = &Potential {
        states: &state.terms,
        ..*pot
    };
    let r = pot.reactions(&state.x, &state.dofs);
    // At a skew vertex, the reaction split among the supports' directions that hold it.
    let mut split: std::collections::BTreeMap<usize, Vec<(usize, Vec3)>> = Default::default();
    for (gi, g) in body.supports.iter().enumerate() {
        for &(v, d) in &g.directions {
            split.entry(v).or_default().push((gi, d));
        }
    }
    let mut by_group: Vec<Vec<(usize, Vec3)>> = vec![Vec::new(); body.supports.len()];
    for (&v, dirs) in &split {
        let d: Vec<Vec3> = dirs.iter().map(|&(_, d)| d).collect();
        for (&(gi, _), part) in dirs.iter().zip(crate::body::hold::split_reaction(r[v], &d)) {
            by_group[gi].push((v, part));
        }
    }
    let totals = body
        .supports
        .iter()
        .zip(&by_group)
        .map(|(g, parts)| {
            let (mut f, mut m) = (Vec3::zeros(), Vec3::zeros());
            for &d in &g.dofs {
                let (v, k) = (d / 3, d % 3);
                let mut rv = Vec3::zeros();
                rv[k] = r[v][k];
                f += rv;
                m += state.x[v].cross(&rv);
            }
            for &(v, rv) in parts {
                f += rv;
                m += state.x[v].cross(&rv);
            }
            Reaction {
                support: g.name.clone(),
                force: f.into(),
                moment: m.into(),
            }
        })
        .chain((!body.edge_normal.is_empty()).then(|| Reaction {
            support: "boundary_rotations".into(),
            force: [0.0; 3],
            moment: pot.rotation_couple(&state.x, &state.dofs).into(),
        }))
        .collect();
    (r, totals)
}

/// `summary` as JSON with every `null` (a non-finite number) left out, and the dotted paths
/// of the values left out.
pub fn summary_json(summary: &Summary) -> (String, Vec<String>) {
    fn prune(v: &mut serde_json::Value, at: &str, out: &mut Vec<String>) {
        let key = |k: &str| {
            if at.is_empty() {
                k.to_string()
            } else {
                format!("{at}.{k}")
            }
        };
        match v {
            serde_json::Value::Object(m) => {
                m.retain(|k, x| {
                    let null = x.is_null();
                    if null {
                        out.push(key(k));
                    }
                    !null
                });
                for (k, x) in m.iter_mut() {
                    prune(x, &key(k), out);
                }
            }
            serde_json::Value::Array(a) => {
                a.retain(|x| {
                    let null = x.is_null();
                    if null {
                        out.push(format!("{at}[]"));
                    }
                    !null
                });
                for (i, x) in a.iter_mut().enumerate() {
                    prune(x, &format!("{at}[{i}]"), out);
                }
            }
            _ => {}
        }
    }
    let mut paths = Vec::new();
    let text = match serde_json::to_value(summary) {
        Ok(mut v) => {
            prune(&mut v, "", &mut paths);
            match paths.is_empty() {
                // The fields in their declared order.
                true => serde_json::to_string_pretty(summary),
                false => serde_json::to_string_pretty(&v),
            }
            .unwrap_or_default()
        }
        // Serialising plain data cannot fail; were it to, the file says so instead of a value.
        Err(e) => {
            paths.push(format!("(the whole summary: {e})"));
            String::from("{}")
        }
    };
    (text, paths)
}

/// Where a run's frames and summary go: the drivers hand their states and records to a sink
/// and never see files ([`crate::output::Writer`] is the one that writes them).
pub trait Sink {
    /// Writes a frame of `state` (positions, DOFs, term states) with velocities `v`, evaluated
    /// with `pot`, its `log.csv` row and the driver's state for a restart.
    fn frame(
        &mut self,
        pot: &Potential,
        state: &State,
        v: &[Vec3],
        row: LogRow,
        driver: Option<&super::DriverState>,
    ) -> Result<(), OutputError>;
    /// Sets a per-face field that the next frames carry (the moisture's), one value per face.
    fn set_face_field(&mut self, name: &str, data: Vec<Real>);
    /// Number of faces of the frames.
    fn num_faces(&self) -> usize;
    /// Number of frames written.
    fn num_frames(&self) -> usize;
    /// The last frame's file name (empty before the first).
    fn last_frame(&self) -> String;
    /// Frees the room kept for the summary after a full disk.
    fn release_reserve(&mut self);
    /// Writes the summary.
    fn summary(&self, summary: &Summary) -> Result<(), OutputError>;
}
