//! Output: one VTK frame per output time, a ParaView series file (`series.pvd`) that opens the
//! whole run, a per-frame CSV log (`log.csv`) and a run summary (`summary.json`). Every file is
//! written to a temporary name and renamed into place, and a frame with a non-finite value is
//! never written.
//!
//! Frame fields (per face, tensors as `[xx, xy, yy]` in reference Cartesian coordinates: the
//! (x, y) frame of a flat reference mesh, otherwise each reference face's own orthonormal frame
//! `t1 = e1/|e1|`, `t2 = N × t1`): `a`, `b`, `abar`, `bbar`, `mean_curvature`,
//! `gauss_curvature`, `k1`, `k2` (principal curvatures, ascending), `max_stretch` (the larger
//! principal stretch `√λ_max(ā⁻¹a)`), `stretching_energy_density`,
//! `bending_energy_density` (J/m² of rest area), `thickness`, and `tri_tags` when the input has
//! it; with patch-fit bending, `patch_condition` (the condition number of each face's fit); with
//! edge DOFs, `edge_angles` (rad, 3 components: the DOF `φ` of the edges opposite `v0, v1, v2`;
//! each edge's value appears in both its faces, and a restart reads it back). Per
//! vertex: `displacement`, `velocity`, `constraint_indicators`, and `node_tags` when present.

use crate::geometry::curvatures;
use crate::math::{Mat2, Real, Sym2, Vec3};
use crate::mesh::io::{write_atomic, Format};
use crate::mesh::{Field, Mesh};
use crate::rest::{push_forward, reference_frame};
use crate::scene::Scene;
use crate::solve::{Potential, State};
use serde::Serialize;
use std::path::{Path, PathBuf};

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
    /// Explicit mode: its time step, time scales and cost.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub explicit: Option<ExplicitReport>,
}

impl Summary {
    /// Refuses a summary that would hold a non-finite number (serialised as `null`): the run
    /// is marked unconverged (exit 1) with an internal error naming the values, which
    /// [`Writer::summary`] leaves out. Returns whether it did.
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

/// Where a run's wall time went (s): Newton's parts (explicit mode: the force evaluations under
/// `assembly`), the moisture diffusion, writing frames, and the rest (setup, predictors,
/// bookkeeping).
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Timing {
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
    /// The sample length L (reference perimeter, m).
    pub sample_length: Real,
    /// The smallest reference altitude a_min (m).
    pub min_altitude: Real,
    /// `"window"` or `"morphoshell"`.
    pub equilibrium_test: String,
    /// Wall time per face and step (µs), the whole loop included.
    pub microseconds_per_face_step: Real,
    /// Hold points at which equilibrium was reached.
    pub holds_reached: usize,
}

/// Writes frames, the series, the log and the summary into one folder.
pub struct Writer {
    dir: PathBuf,
    format: Format,
    prefix: String,
    frames: Vec<(Real, String)>,
    log: Vec<LogRow>,
    frame_mesh: Mesh,
    frames_t: Vec<Mat2>,
    /// Extra per-face fields written into every following frame (moisture).
    extra: std::collections::BTreeMap<String, Vec<Real>>,
    /// `.vtu` compression and encoding.
    vtu: crate::mesh::vtu::VtuOptions,
    /// `[output]`: which fields are written, snapshots.
    selection: crate::settings::Output,
    /// Whether `frame_mesh` holds the frame last written.
    built_is_written: bool,
    /// The fields a restart reads: always written, always Float64.
    restart_fields: std::collections::BTreeSet<String>,
    /// Static runs: `log.csv` has no time column (the dial is the run's progress).
    static_mode: bool,
    /// `log.csv` rows of the frames a continued series keeps, verbatim, and its header.
    kept_log: Option<(String, Vec<String>)>,
    /// A continued series: the first frame (the restart state, already in the series) is not
    /// written again.
    skip_first: bool,
    /// A continued series: the summary of the run it continues, whose counts and times the new
    /// summary adds to its own.
    previous_summary: Option<serde_json::Value>,
    /// Space set aside so that a run stopped by a full disk can still write its summary.
    reserve: Option<Reserve>,
    /// The folder's lock, released when the writer is dropped (`None`: a writer that only
    /// builds fields, [`check_fields`]).
    _lock: Option<Lock>,
}

/// `.shellsim.reserve`: space set aside while a run writes, removed on drop.
struct Reserve(PathBuf);

impl Drop for Reserve {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// The resolved settings' file in a run folder ([`crate::provenance`]).
pub const RESOLVED_SETTINGS: &str = "settings.resolved.toml";

/// Writes the run's resolved settings ([`RESOLVED_SETTINGS`]) into `dir`, once per run.
fn write_resolved_settings(dir: &Path, scene: &Scene) -> Result<(), OutputError> {
    let path = dir.join(RESOLVED_SETTINGS);
    let text = toml::to_string(&scene.settings).map_err(|e| ioerr(&path, e))?;
    write_atomic(&path, text.as_bytes()).map_err(|e| ioerr(&path, e))
}

/// Bytes set aside in `.shellsim.reserve` while a run writes, released when the disk fills.
const RESERVE_BYTES: usize = 1 << 20;

/// The `(timestep, file)` entries of a `series.pvd`, in order.
pub fn series_entries(path: &Path) -> Result<Vec<(Real, String)>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let attr = |line: &str, key: &str| -> Option<String> {
        let at = line.find(&format!("{key}=\""))? + key.len() + 2;
        let rest = &line[at..];
        Some(rest[..rest.find('"')?].to_string())
    };
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if !line.contains("<DataSet") {
            continue;
        }
        let (Some(t), Some(f)) = (attr(line, "timestep"), attr(line, "file")) else {
            return Err(format!(
                "{}: line {}: a DataSet without timestep or file",
                path.display(),
                i + 1
            ));
        };
        let t: Real = t.parse().map_err(|_| {
            format!(
                "{}: line {}: timestep '{t}' is not a number",
                path.display(),
                i + 1
            )
        })?;
        if f.contains('/') || f.contains('\\') || f.starts_with('.') {
            return Err(format!(
                "{}: line {}: '{f}' is not a file of this folder",
                path.display(),
                i + 1
            ));
        }
        out.push((t, f));
    }
    Ok(out)
}

pub use crate::restart::state_file;

/// The fields a restart of `scene` reads from a frame: the velocity (dynamic modes), the edge
/// angles (edge-DOF bending) and the terms' states.
pub fn restart_fields(scene: &Scene) -> std::collections::BTreeSet<String> {
    let mut r = std::collections::BTreeSet::new();
    if scene.settings.solver.mode != crate::settings::Mode::Static {
        r.insert("velocity".to_string());
    }
    if scene.has_edge_dofs() {
        r.insert("edge_angles".to_string());
    }
    for t in scene.terms.iter().filter_map(|t| t.tracked()) {
        r.insert(t.state_field().to_string());
    }
    r
}

/// Checks the names in `output.fields` against the fields this scene's frames carry (built
/// once on the reference state, without touching the disk, and only when names are given): an
/// unknown name is an error listing the fields there are. Every field a restart reads is
/// written whatever the selection.
pub fn check_fields(
    scene: &Scene,
    settings_name: &str,
) -> Result<(), crate::settings::SettingsError> {
    let out = &scene.settings.output;
    if out.fields.iter().all(|f| f == "all" || f == "default") && out.snapshot_field.is_none() {
        return Ok(());
    }
    let pattern = crate::assembly::Pattern::for_scene(scene);
    let pot = Potential::new(scene, &pattern);
    let state = State {
        x: scene.mesh.positions.clone(),
        dofs: vec![0.0; pattern.n - 3 * scene.num_vertices()],
        terms: scene.initial_states.clone(),
    };
    let v = vec![Vec3::zeros(); scene.num_vertices()];
    let mut w = Writer::detached(scene);
    w.fill(&pot, &state.x, &state.dofs, &v);
    let mut names: Vec<String> = w
        .frame_mesh
        .face_fields
        .keys()
        .chain(w.frame_mesh.vertex_fields.keys())
        .cloned()
        .collect();
    if scene.settings.moisture.enabled {
        names.extend(crate::integrate::moisture::FRAME_FIELDS.map(String::from));
    }
    names.sort();
    let keys = out
        .fields
        .iter()
        .filter(|f| *f != "default" && *f != "all")
        .map(|f| ("output.fields", f))
        .chain(
            out.snapshot_field
                .iter()
                .map(|f| ("output.snapshot_field", f)),
        );
    for (key, f) in keys {
        let written = key == "output.fields" || Writer::writes(&w.selection, &w.restart_fields, f);
        if !names.contains(f) || !written {
            return Err(crate::settings::SettingsError::Invalid {
                path: settings_name.to_string(),
                key: key.into(),
                reason: if names.contains(f) {
                    format!("'{f}' is not among output.fields")
                } else {
                    format!(
                        "this scene's frames have no field '{f}'; they have: {}",
                        names.join(", ")
                    )
                },
            });
        }
    }
    Ok(())
}

/// `.shellsim.lock` in an output folder: created exclusively, holding the process id, removed
/// on drop. A lock whose process is gone (a killed run) is taken over.
struct Lock(std::path::PathBuf);

impl Lock {
    fn take(dir: &Path) -> Result<Lock, OutputError> {
        use std::io::Write;
        let path = dir.join(".shellsim.lock");
        for _ in 0..2 {
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
            {
                Ok(mut f) => {
                    writeln!(f, "{}", std::process::id()).map_err(|e| ioerr(&path, e))?;
                    return Ok(Lock(path));
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    if let Some(pid) = lock_owner(dir) {
                        return Err(OutputError::Locked {
                            path: dir.display().to_string(),
                            pid,
                        });
                    }
                    // Stale: its run ended without removing it.
                    let _ = std::fs::remove_file(&path);
                }
                Err(e) => return Err(ioerr(&path, e)),
            }
        }
        Err(ioerr(&path, "cannot take the lock"))
    }
}

impl Drop for Lock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// The process holding the run lock of `dir` (`.shellsim.lock`), when it is another process
/// that is alive; `None` when there is no lock or it was left by a run that ended.
pub(crate) fn lock_owner(dir: &Path) -> Option<u32> {
    let pid = std::fs::read_to_string(dir.join(".shellsim.lock"))
        .ok()
        .and_then(|t| t.trim().parse::<u32>().ok())?;
    (pid != std::process::id() && Path::new(&format!("/proc/{pid}")).exists()).then_some(pid)
}

/// Files of an earlier run in `dir`: its summary, series and log, frames `PREFIX_NNNNN.vtu|vtk`,
/// their snapshots `PREFIX_NNNNN.png` and temporary files left by an interrupted write.
pub(crate) fn previous_outputs(
    dir: &Path,
    prefix: &str,
) -> std::io::Result<Vec<std::path::PathBuf>> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir)? {
        let p = e?.path();
        let Some(name) = p.file_name().and_then(|n| n.to_str()) else {
            continue;
        };
        let frame = name
            .strip_prefix(prefix)
            .and_then(|r| r.strip_prefix('_'))
            .and_then(|r| r.split_once('.'))
            .is_some_and(|(n, ext)| {
                !n.is_empty()
                    && n.bytes().all(|c| c.is_ascii_digit())
                    && matches!(ext, "vtu" | "vtk" | "png" | "state.json")
            });
        let ours = matches!(
            name,
            "summary.json" | "series.pvd" | "log.csv" | "run.json" | RESOLVED_SETTINGS
        ) || frame
            || (name.starts_with('.') && name.ends_with(".tmp"));
        if ours && p.is_file() {
            out.push(p);
        }
    }
    // Frames an earlier run wrote under another `output.prefix`: those its series lists, with
    // their state files and pictures.
    if let Ok(listed) = series_entries(&dir.join("series.pvd")) {
        for (_, f) in listed {
            let frame = dir.join(&f);
            let png = frame.with_extension("png");
            for p in [state_file(&frame), png, frame] {
                if p.is_file() && !out.contains(&p) {
                    out.push(p);
                }
            }
        }
    }
    out.sort();
    Ok(out)
}

fn ioerr(path: &Path, e: impl ToString) -> OutputError {
    OutputError::Io {
        path: path.display().to_string(),
        reason: e.to_string(),
    }
}

/// Per-face frames mapping the scene's barycentric coordinates to reference Cartesian
/// coordinates (see module doc): on a curved reference, each face's frame starts at its first
/// edge in the input's corner order.
fn output_frames(scene: &Scene) -> Vec<Mat2> {
    let mesh = &scene.mesh;
    let flat = mesh.is_flat_xy();
    (0..mesh.faces.len())
        .map(|f| {
            if flat {
                reference_frame(mesh, f)
            } else {
                let [p0, p1, p2] = mesh.face_positions(f);
                let (e1, e2) = (p1 - p0, p2 - p0);
                let [i0, i1, _] = scene.input_face(f);
                let t1 = (mesh.positions[i1] - mesh.positions[i0]).normalize();
                let n = e1.cross(&e2).normalize();
                let t2 = n.cross(&t1);
                Mat2::new(t1.dot(&e1), t1.dot(&e2), t2.dot(&e1), t2.dot(&e2))
            }
        })
        .collect()
}

impl Writer {
    /// Creates the output folder, takes its lock (one run per folder) and checks it is
    /// writable, before any work. A folder holding an earlier run's output (summary, series,
    /// log, frames) is refused unless `overwrite`, which removes those files first.
    pub fn new(dir: &Path, scene: &Scene, overwrite: bool) -> Result<Self, OutputError> {
        std::fs::create_dir_all(dir).map_err(|e| ioerr(dir, e))?;
        let lock = Lock::take(dir)?;
        let prefix = &scene.settings.output.prefix;
        let previous = previous_outputs(dir, prefix).map_err(|e| ioerr(dir, e))?;
        if !previous.is_empty() {
            if !overwrite {
                let frames = previous
                    .iter()
                    .filter(|p| p.extension().is_some_and(|e| e == "vtu" || e == "vtk"))
                    .count();
                let names: Vec<String> = previous
                    .iter()
                    .filter_map(|p| p.file_name()?.to_str().map(String::from))
                    .filter(|n| !n.starts_with(prefix.as_str()) && !n.ends_with(".tmp"))
                    .collect();
                let mut what = names.join(", ");
                if frames > 0 {
                    what += &format!("{}{frames} frames", if what.is_empty() { "" } else { ", " });
                }
                return Err(OutputError::Used {
                    path: dir.display().to_string(),
                    what,
                });
            }
            for p in &previous {
                std::fs::remove_file(p).map_err(|e| ioerr(p, e))?;
            }
        }
        let reserve = Self::set_aside(dir)?;
        write_resolved_settings(dir, scene)?;
        Ok(Writer {
            dir: dir.to_path_buf(),
            reserve: Some(reserve),
            _lock: Some(lock),
            ..Writer::detached(scene)
        })
    }

    /// Checks that `dir` is writable by setting aside [`RESERVE_BYTES`] in
    /// `.shellsim.reserve` (released by [`Writer::release_reserve`] when the disk fills, so the
    /// summary still fits).
    fn set_aside(dir: &Path) -> Result<Reserve, OutputError> {
        let reserve = Reserve(dir.join(".shellsim.reserve"));
        std::fs::write(&reserve.0, vec![0u8; RESERVE_BYTES])
            .map_err(|e| ioerr(dir, format!("not writable: {e}")))?;
        Ok(reserve)
    }

    /// Frees the space set aside at the start (a full disk: the summary is written next).
    pub fn release_reserve(&mut self) {
        self.reserve = None;
    }

    /// Continues the series in `dir` from its frame `from` (a frame it lists): the frames
    /// after it go (with their state files, pictures and log rows), new frames are numbered on,
    /// and the first frame the run writes (the restart state, which is `from` itself) is not
    /// written again.
    pub fn continuing(dir: &Path, scene: &Scene, from: &Path) -> Result<Self, OutputError> {
        let lock = Lock::take(dir)?;
        let mut w = Writer {
            dir: dir.to_path_buf(),
            ..Writer::detached(scene)
        };
        let series = dir.join("series.pvd");
        let listed = series_entries(&series).map_err(|e| ioerr(&series, e))?;
        let name = from
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let keep = listed
            .iter()
            .position(|(_, f)| *f == name)
            .ok_or_else(|| ioerr(&series, format!("does not list {name}")))?;
        let ext = format!(".{}", w.format.extension());
        if !name.starts_with(&format!("{}_", w.prefix)) || !name.ends_with(&ext) {
            return Err(ioerr(
                from,
                format!(
                    "a continued series keeps its frames' names: this run writes {}_NNNNN{ext} \
                     (output.prefix, output.format)",
                    w.prefix
                ),
            ));
        }
        // log.csv: the header and the rows of the frames kept, verbatim.
        let log_path = dir.join("log.csv");
        let log = std::fs::read_to_string(&log_path).map_err(|e| ioerr(&log_path, e))?;
        let mut lines = log.lines();
        let header = lines.next().unwrap_or_default().to_string();
        let rows: Vec<String> = lines.take(keep + 1).map(String::from).collect();
        if rows.len() != keep + 1 {
            return Err(ioerr(
                &log_path,
                format!(
                    "has {} rows, the series {} frames",
                    rows.len(),
                    listed.len()
                ),
            ));
        }
        for (_, f) in &listed[keep + 1..] {
            let frame = dir.join(f);
            for p in [state_file(&frame), frame.with_extension("png"), frame] {
                if p.is_file() {
                    std::fs::remove_file(&p).map_err(|e| ioerr(&p, e))?;
                }
            }
        }
        w.frames = listed[..=keep].to_vec();
        w.kept_log = Some((header, rows));
        w.previous_summary = std::fs::read_to_string(dir.join("summary.json"))
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok());
        w.skip_first = true;
        w.reserve = Some(Self::set_aside(dir)?);
        write_resolved_settings(dir, scene)?;
        w._lock = Some(lock);
        w.write_series()?;
        w.write_log()?;
        Ok(w)
    }

    /// Writes `run.json` into the folder.
    pub fn provenance(&self, record: &crate::provenance::Provenance) -> Result<(), OutputError> {
        crate::provenance::write(&self.dir, record)
            .map_err(|e| ioerr(&crate::provenance::path(&self.dir), e))
    }

    /// Whether frames carry the field `name`: selected by `[output]`, or read by a restart.
    fn writes(
        selection: &crate::settings::Output,
        restart_fields: &std::collections::BTreeSet<String>,
        name: &str,
    ) -> bool {
        selection.selects(name) || restart_fields.contains(name)
    }

    /// A writer that builds frames' fields but writes nothing (no folder, no lock).
    fn detached(scene: &Scene) -> Self {
        let mesh = &scene.mesh;
        // Frames keep the input's corner order.
        let mut frame_mesh = Mesh {
            positions: mesh.positions.clone(),
            faces: scene.input_faces(),
            ..Default::default()
        };
        if let Some(t) = mesh.face_fields.get("tri_tags") {
            frame_mesh.face_fields.insert("tri_tags".into(), t.clone());
        }
        if let Some(t) = mesh.vertex_fields.get("node_tags") {
            frame_mesh
                .vertex_fields
                .insert("node_tags".into(), t.clone());
        }
        let out = &scene.settings.output;
        let restart_fields = restart_fields(scene);
        Writer {
            dir: PathBuf::new(),
            format: out.format,
            prefix: out.prefix.clone(),
            frames: Vec::new(),
            log: Vec::new(),
            frames_t: output_frames(scene),
            frame_mesh,
            extra: Default::default(),
            vtu: crate::mesh::vtu::VtuOptions {
                compression: out
                    .compression
                    .unwrap_or(crate::mesh::vtu::Compression::Zlib),
                encoding: out.encoding.unwrap_or(crate::mesh::vtu::Encoding::Appended),
            },
            selection: out.clone(),
            built_is_written: false,
            restart_fields,
            static_mode: scene.settings.solver.mode == crate::settings::Mode::Static,
            kept_log: None,
            skip_first: false,
            previous_summary: None,
            reserve: None,
            _lock: None,
        }
    }

    /// Sets an extra per-face scalar field written into the following frames.
    pub fn set_face_field(&mut self, name: &str, data: Vec<Real>) {
        self.extra.insert(name.to_string(), data);
    }

    /// Number of faces of the frames.
    pub fn num_faces(&self) -> usize {
        self.frame_mesh.faces.len()
    }

    /// Number of frames written.
    pub fn num_frames(&self) -> usize {
        self.frames.len()
    }

    /// Name of the last frame, relative to the output folder.
    pub fn last_frame(&self) -> String {
        self.frames.last().map(|f| f.1.clone()).unwrap_or_default()
    }

    /// Energies of a state by term.
    pub fn energies(pot: &Potential, state: &State, v: &[Vec3]) -> Energies {
        let pot = &Potential {
            terms: &state.terms,
            ..*pot
        };
        Self::energies_of(pot, pot.energies(&state.x, &state.dofs), v)
    }

    /// The energies record of the terms' energies and the kinetic energy at velocities `v`.
    fn energies_of(pot: &Potential, terms: Vec<(&'static str, Real)>, v: &[Vec3]) -> Energies {
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

    /// Builds every field of a frame at `x`, `phi`, `v` into `frame_mesh`; returns the terms'
    /// energies.
    fn fill(
        &mut self,
        pot: &Potential,
        x: &[Vec3],
        phi: &[Real],
        v: &[Vec3],
    ) -> Vec<(&'static str, Real)> {
        let sc = pot.scene;
        let nf = sc.num_faces();
        let (a, b) = sc.forms(x, phi);
        let mut term_energies = Vec::new();
        let mut term_fields = Vec::new();
        for (t, map) in sc.terms.iter().zip(&pot.pattern.maps) {
            let (e, f) = crate::energy::term::report(t.as_ref(), pot, map, x, phi);
            term_energies.extend(e);
            term_fields.extend(f);
        }
        let mut fa = Vec::with_capacity(3 * nf);
        let mut fb = Vec::with_capacity(3 * nf);
        let mut fab = Vec::with_capacity(3 * nf);
        let mut fbb = Vec::with_capacity(3 * nf);
        let (mut hh, mut kk, mut k1s, mut k2s, mut stretch) = (
            Vec::with_capacity(nf),
            Vec::with_capacity(nf),
            Vec::with_capacity(nf),
            Vec::with_capacity(nf),
            Vec::with_capacity(nf),
        );
        for f in 0..nf {
            let t = &self.frames_t[f];
            let (abar, bbar) = pot.rest_forms(f);
            let push = |out: &mut Vec<Real>, s: &Sym2| {
                out.extend_from_slice(push_forward(t, s).as_slice())
            };
            push(&mut fa, &a[f]);
            push(&mut fb, &b[f]);
            push(&mut fab, &abar);
            push(&mut fbb, &bbar);
            let (h, k, k1, k2) = curvatures(&a[f], &b[f]);
            hh.push(h);
            kk.push(k);
            k1s.push(k1);
            k2s.push(k2);
            // Principal stretches: √eigenvalues of ā⁻¹a.
            let c = crate::math::sym_to_mat(&abar)
                .try_inverse()
                .unwrap_or_else(Mat2::identity)
                * crate::math::sym_to_mat(&a[f]);
            stretch.push(crate::math::eig2(&c).1.max(0.0).sqrt());
        }
        let m = &mut self.frame_mesh;
        m.positions.copy_from_slice(x);
        let ff = &mut m.face_fields;
        let vec3 = |d: Vec<Real>| Field {
            components: 3,
            data: d,
        };
        ff.insert("a".into(), vec3(fa));
        ff.insert("b".into(), vec3(fb));
        ff.insert("abar".into(), vec3(fab));
        ff.insert("bbar".into(), vec3(fbb));
        ff.insert("mean_curvature".into(), Field::scalar(hh));
        ff.insert("gauss_curvature".into(), Field::scalar(kk));
        ff.insert("k1".into(), Field::scalar(k1s));
        ff.insert("k2".into(), Field::scalar(k2s));
        ff.insert("max_stretch".into(), Field::scalar(stretch));
        // The rest thickness at this dial, unless a term gives the current one.
        ff.insert(
            "thickness".into(),
            Field::scalar((0..nf).map(|f| pot.thickness(f)).collect()),
        );
        for (name, data) in term_fields {
            ff.insert(name, Field::scalar(data));
        }
        for (name, data) in &self.extra {
            ff.insert(name.clone(), Field::scalar(data.clone()));
        }
        if sc.has_edge_dofs() {
            let ea = sc.topo.face_edges.iter().flat_map(|fe| fe.map(|e| phi[e]));
            ff.insert("edge_angles".into(), vec3(ea.collect()));
        }
        for t in sc.terms.iter() {
            if let Some(tr) = t.tracked() {
                ff.insert(
                    tr.state_field().into(),
                    Field {
                        components: tr.state_components(),
                        data: tr.field(x, phi, pot.term_state(t.name())),
                    },
                );
            }
        }
        // Slot fields in the input's corner order, like the faces.
        for name in sc.slot_fields() {
            if let Some(f) = ff.get_mut(name).filter(|f| f.components == 3) {
                sc.reorder_slots(&mut f.data, true);
            }
        }
        if !sc.patches.is_empty() {
            ff.insert(
                "patch_condition".into(),
                Field::scalar(sc.patches.iter().map(|p| p.condition).collect()),
            );
        }
        if sc.settings.output.morphoshell_fields {
            morphoshell_fields(m, pot, x, phi, &a);
        }
        let vf = &mut m.vertex_fields;
        let disp: Vec<Real> = x
            .iter()
            .zip(&sc.mesh.positions)
            .flat_map(|(p, q)| (p - q).iter().copied().collect::<Vec<_>>())
            .collect();
        vf.insert("displacement".into(), vec3(disp));
        vf.insert(
            "velocity".into(),
            vec3(v.iter().flat_map(|p| [p.x, p.y, p.z]).collect()),
        );
        vf.insert(
            "constraint_indicators".into(),
            Field::scalar(sc.fixed.iter().map(|&b| b as u8 as Real).collect()),
        );
        term_energies
    }

    /// Writes one frame, the driver's state beside it (`PREFIX_NNNNN.state.json`) and its log
    /// row; rewrites the series and the log. When a write fails (a full disk) the frame and
    /// its state file go again, so frames, series and log stay in step.
    pub fn frame<D: Serialize>(
        &mut self,
        pot: &Potential,
        state: &State,
        v: &[Vec3],
        mut row: LogRow,
        driver: Option<&D>,
    ) -> Result<(), OutputError> {
        if std::mem::take(&mut self.skip_first) {
            // A continued series: this is the frame it continues from.
            return Ok(());
        }
        let pot = &Potential {
            terms: &state.terms,
            ..*pot
        };
        let (x, phi) = (&state.x[..], &state.dofs[..]);
        let sc = pot.scene;
        let index = self.frames.len();
        row.frame = index;
        self.built_is_written = false;
        let term_energies = self.fill(pot, x, phi, v);
        row.energy = Self::energies_of(pot, term_energies, v);
        row.observables = sc
            .terms
            .iter()
            .flat_map(|t| crate::energy::term::observables(t.as_ref(), pot, x, phi))
            .collect();
        let m = &mut self.frame_mesh;
        let keep = |n: &String| Self::writes(&self.selection, &self.restart_fields, n);
        m.face_fields.retain(|n, _| keep(n));
        m.vertex_fields.retain(|n, _| keep(n));
        // Never write NaN.
        if let Some(p) = m
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(OutputError::NonFinite {
                index,
                time: row.time,
                field: format!("positions (vertex {p})"),
            });
        }
        let all = m
            .face_fields
            .iter()
            .map(|f| (f, "face"))
            .chain(m.vertex_fields.iter().map(|f| (f, "vertex")));
        for ((name, fld), what) in all {
            if let Some(i) = fld.data.iter().position(|v| !v.is_finite()) {
                return Err(OutputError::NonFinite {
                    index,
                    time: row.time,
                    field: format!(
                        "{name}' at {what} {} (value {})",
                        i / fld.components.max(1),
                        crate::math::human(fld.data[i])
                    ),
                });
            }
        }
        let bad_row = row
            .energy
            .columns()
            .into_iter()
            .map(|(n, e)| (format!("energy_{n}"), e))
            .chain(row.observables.iter().cloned())
            .find(|(_, v)| !v.is_finite());
        if let Some((name, v)) = bad_row {
            return Err(OutputError::NonFinite {
                index,
                time: row.time,
                field: format!("{name}' of the log row (value {})", crate::math::human(v)),
            });
        }
        let name = format!("{}_{index:05}.{}", self.prefix, self.format.extension());
        let path = self.dir.join(&name);
        let restart = &self.restart_fields;
        let single = self.selection.precision == crate::settings::Precision::Single;
        // The displacement gives the reference positions (positions − displacement), which
        // `shellsim error` and scripts measure against: Float64 like the positions. A field
        // with a value beyond Float32's range (3.4e38) stays Float64 rather than become inf.
        let fits_f32 = |n: &str| {
            [m.face_fields.get(n), m.vertex_fields.get(n)]
                .into_iter()
                .flatten()
                .all(|f| f.data.iter().all(|&v| (v as f32).is_finite()))
        };
        let bytes = crate::mesh::io::mesh_to_bytes_with(
            m,
            self.format,
            &format!("shellsim frame {index} t={}", row.time),
            &self.vtu,
            &|n| single && n != "displacement" && !restart.contains(n) && fits_f32(n),
        );
        let state_path = state_file(&path);
        let undo = |paths: &[&Path]| {
            for p in paths {
                let _ = std::fs::remove_file(p);
            }
        };
        if let Some(d) = driver {
            let text = serde_json::to_string(d).map_err(|e| ioerr(&state_path, e))?;
            write_atomic(&state_path, text.as_bytes()).map_err(|e| ioerr(&state_path, e))?;
        }
        if let Err(e) = write_atomic(&path, &bytes) {
            undo(&[&state_path]);
            return Err(ioerr(&path, e));
        }
        self.built_is_written = true;
        self.frames.push((row.time, name));
        self.log.push(row);
        let written = self.write_log().and_then(|_| self.write_series());
        if let Err(e) = written {
            // Back to the folder as it was: the series and log rewritten without this frame
            // (the frame's space is freed first).
            undo(&[&path, &state_path]);
            self.frames.pop();
            self.log.pop();
            self.built_is_written = false;
            let _ = self.write_log().and_then(|_| self.write_series());
            return Err(e);
        }
        if self.selection.snapshots == crate::settings::Snapshots::All {
            self.snapshot(index)?;
        }
        Ok(())
    }

    /// `PREFIX_NNNNN.png` beside frame `index`, drawn from the frame last built
    /// (`output.snapshot_field`, `snapshot_view`, `snapshot_size`; [`crate::render`]).
    fn snapshot(&self, index: usize) -> Result<(), OutputError> {
        let o = &self.selection;
        let path = self.dir.join(format!("{}_{index:05}.png", self.prefix));
        let m = &self.frame_mesh;
        let field = match &o.snapshot_field {
            Some(f) => Some(f.as_str()),
            None => m
                .face_fields
                .contains_key("mean_curvature")
                .then_some("mean_curvature"),
        };
        let [w, h] = o.snapshot_size;
        crate::render::render(
            m,
            field,
            &o.snapshot_view,
            w,
            h,
            None,
            crate::render::Shading::Smooth,
        )
        .and_then(|c| c.save_png(&path))
        .map_err(|e| ioerr(&path, format!("{e:#}")))
    }

    fn write_series(&self) -> Result<(), OutputError> {
        let mut s = String::from(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n",
        );
        for (t, name) in &self.frames {
            // Shortest round-trip digits: a restart reads the exact time back.
            s.push_str(&format!(
                "    <DataSet timestep=\"{t}\" group=\"\" part=\"0\" file=\"{name}\"/>\n"
            ));
        }
        s.push_str("  </Collection>\n</VTKFile>\n");
        let path = self.dir.join("series.pvd");
        write_atomic(&path, s.as_bytes()).map_err(|e| ioerr(&path, e))
    }

    /// `log.csv`'s header for this run's rows (`None` before the first row).
    fn log_header(&self) -> Option<String> {
        let r = self.log.first()?;
        let mut s = String::from(if self.static_mode {
            "frame,dial,"
        } else {
            "frame,time,dial,"
        });
        for (name, _) in r.energy.columns() {
            s.push_str(&format!("energy_{name},"));
        }
        for (name, _) in &r.observables {
            s.push_str(&format!("{name},"));
        }
        s.push_str(
            "residual,newton_iterations,steps,shifted_iterations,gauss_newton_iterations,\
             rejected_steps,wall_seconds",
        );
        Some(s)
    }

    fn write_log(&self) -> Result<(), OutputError> {
        let path = self.dir.join("log.csv");
        let header = self.log_header();
        let mut s = String::new();
        match (&self.kept_log, &header) {
            (Some((kept, _)), Some(h)) if kept != h => {
                return Err(ioerr(
                    &path,
                    format!(
                        "the continued run logs other columns than the series it continues \
                         (it has `{kept}`, this run `{h}`): continue with the settings that \
                         wrote it"
                    ),
                ))
            }
            (Some((kept, rows)), _) => {
                s.push_str(kept);
                s.push('\n');
                for r in rows {
                    s.push_str(r);
                    s.push('\n');
                }
            }
            (None, Some(h)) => {
                s.push_str(h);
                s.push('\n');
            }
            (None, None) => {}
        }
        for r in &self.log {
            if self.static_mode {
                s.push_str(&format!("{},{:.12e},", r.frame, r.dial));
            } else {
                s.push_str(&format!("{},{:.12e},{:.12e},", r.frame, r.time, r.dial));
            }
            for (_, e) in r.energy.columns() {
                s.push_str(&format!("{e:.12e},"));
            }
            for (_, o) in &r.observables {
                s.push_str(&format!("{o:.12e},"));
            }
            s.push_str(&format!(
                "{:.6e},{},{},{},{},{},{:.6}\n",
                r.residual,
                r.newton_iterations,
                r.steps,
                r.shifted_iterations,
                r.gauss_newton_iterations,
                r.rejected_steps,
                r.wall_seconds
            ));
        }
        write_atomic(&path, s.as_bytes()).map_err(|e| ioerr(&path, e))
    }

    /// Writes `summary.json`; a continued series' summary counts the steps, iterations and
    /// times of the runs before it too.
    pub fn summary(&self, summary: &Summary) -> Result<(), OutputError> {
        let path = self.dir.join("summary.json");
        let mut summary = summary.clone();
        if let Some(prev) = &self.previous_summary {
            let n = |k: &str| prev[k].as_u64().unwrap_or(0) as usize;
            let x = |k: &str| prev[k].as_f64().unwrap_or(0.0);
            let t = |k: &str| prev["timing"][k].as_f64().unwrap_or(0.0);
            let s = &mut summary;
            s.steps += n("steps");
            s.rejected_steps += n("rejected_steps");
            s.newton_iterations += n("newton_iterations");
            s.shifted_iterations += n("shifted_iterations");
            s.gauss_newton_iterations += n("gauss_newton_iterations");
            s.indefinite_iterations += n("indefinite_iterations");
            s.saddle_escapes += n("saddle_escapes");
            s.diffusion_substeps += n("diffusion_substeps");
            s.diffusion_rejected += n("diffusion_rejected");
            s.diffusion_factorisations += n("diffusion_factorisations");
            s.diffusion_cg_iterations += n("diffusion_cg_iterations");
            s.diffusion_direct_solves += n("diffusion_direct_solves");
            s.moisture_seconds += x("moisture_seconds");
            s.wall_seconds += x("wall_seconds");
            let tm = &mut s.timing;
            tm.newton.assembly += t("assembly");
            tm.newton.factorisation += t("factorisation");
            tm.newton.solve += t("solve");
            tm.newton.line_search += t("line_search");
            tm.diffusion += t("diffusion");
            tm.output += t("output");
            tm.other += t("other");
        }
        // Never a `null`: the caller refuses such a summary first (`Summary::refuse_non_finite`).
        let (text, _) = summary_json(&summary);
        write_atomic(&path, text.as_bytes()).map_err(|e| ioerr(&path, e))?;
        // The last frame's picture, when the frame last built is the one last written (not a
        // refused non-finite state).
        if self.selection.snapshots == crate::settings::Snapshots::Final && self.built_is_written {
            self.snapshot(self.frames.len() - 1)?;
        }
        Ok(())
    }
}

/// MorphoShell's derived fields ([`crate::fields`]) into the frame `m`: `angle_deficit` and
/// `angle_deficit_gauss_curvature` per vertex; `strain_measure`, `cauchy_stress_eigval_1/2`
/// (N/m, largest first), `dimless_cauchy_stress_eigval_1/2` (over μt, as MorphoShell writes
/// them) and `cauchy_stress_eigvec_1/2` (unit 3-vectors) per face. Without a membrane term the
/// stress fields are left out.
fn morphoshell_fields(m: &mut Mesh, pot: &Potential, x: &[Vec3], phi: &[Real], a: &[Sym2]) {
    let sc = pot.scene;
    let (deficit, curvature) =
        crate::fields::angle_deficits(x, &sc.mesh.faces, &sc.topo.boundary_vertex);
    m.vertex_fields
        .insert("angle_deficit".into(), Field::scalar(deficit));
    m.vertex_fields.insert(
        "angle_deficit_gauss_curvature".into(),
        Field::scalar(curvature),
    );
    let strain = (0..sc.num_faces())
        .map(|f| crate::fields::strain_measure(&a[f], &pot.rest_forms(f).0))
        .collect();
    m.face_fields
        .insert("strain_measure".into(), Field::scalar(strain));
    let Some(ga) = sc
        .terms
        .iter()
        .filter_map(|t| t.reports())
        .find_map(|r| r.membrane_stress(pot, x, phi))
    else {
        return;
    };
    let nf = sc.num_faces();
    let (mut l1, mut l2, mut d1, mut d2) = (
        Vec::with_capacity(nf),
        Vec::with_capacity(nf),
        Vec::with_capacity(nf),
        Vec::with_capacity(nf),
    );
    let (mut u1, mut u2) = (Vec::with_capacity(3 * nf), Vec::with_capacity(3 * nf));
    for (f, face) in sc.mesh.faces.iter().enumerate() {
        let (e1, e2) = (x[face[1]] - x[face[0]], x[face[2]] - x[face[0]]);
        let (l, u) = crate::fields::cauchy_principal(&e1, &e2, &a[f], &ga[f]);
        let mu_t = sc.lame[f].beta * pot.thickness(f);
        l1.push(l[0]);
        l2.push(l[1]);
        d1.push(l[0] / mu_t);
        d2.push(l[1] / mu_t);
        u1.extend_from_slice(u[0].as_slice());
        u2.extend_from_slice(u[1].as_slice());
    }
    let ff = &mut m.face_fields;
    ff.insert("cauchy_stress_eigval_1".into(), Field::scalar(l1));
    ff.insert("cauchy_stress_eigval_2".into(), Field::scalar(l2));
    ff.insert("dimless_cauchy_stress_eigval_1".into(), Field::scalar(d1));
    ff.insert("dimless_cauchy_stress_eigval_2".into(), Field::scalar(d2));
    let vec3 = |d: Vec<Real>| Field {
        components: 3,
        data: d,
    };
    ff.insert("cauchy_stress_eigvec_1".into(), vec3(u1));
    ff.insert("cauchy_stress_eigvec_2".into(), vec3(u2));
}
