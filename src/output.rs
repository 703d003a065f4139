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

use crate::energy::Potential;
use crate::geometry::curvatures;
pub use crate::integrate::report::{
    summary_json, Energies, ExplicitReport, LogRow, OutputError, Summary, Timing,
};
use crate::math::{Mat2, Real, Sym2, Vec3};
use crate::mesh::io::{write_atomic, Format};
use crate::mesh::{Field, Mesh};
use crate::model::Scene;
use crate::rest::{push_forward, reference_frame};
use crate::solve::State;
use serde::Serialize;
use std::path::{Path, PathBuf};

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
    if scene.body.has_edge_dofs() {
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
        x: scene.body.mesh.positions.clone(),
        dofs: vec![0.0; pattern.n - 3 * scene.body.num_vertices()],
        terms: scene.initial_states.clone(),
    };
    let v = vec![Vec3::zeros(); scene.body.num_vertices()];
    let mut w = Writer::detached(scene);
    w.fill(&pot, &state.x, &state.dofs, &v);
    let mut names: Vec<String> = w
        .frame_mesh
        .face_fields
        .keys()
        .chain(w.frame_mesh.vertex_fields.keys())
        .cloned()
        .collect();
    names.extend(
        crate::integrate::transport::frame_fields(&scene.settings)
            .iter()
            .map(|f| f.to_string()),
    );
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
    let mesh = &scene.body.mesh;
    let flat = mesh.is_flat_xy();
    (0..mesh.faces.len())
        .map(|f| {
            if flat {
                reference_frame(mesh, f)
            } else {
                let [p0, p1, p2] = mesh.face_positions(f);
                let (e1, e2) = (p1 - p0, p2 - p0);
                let [i0, i1, _] = scene.body.input_face(f);
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
        let mesh = &scene.body.mesh;
        // Frames keep the input's corner order.
        let mut frame_mesh = Mesh {
            positions: mesh.positions.clone(),
            faces: scene.body.input_faces(),
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

    /// Builds every field of a frame at `x`, `phi`, `v` into `frame_mesh`; returns the terms'
    /// energies.
    fn fill(
        &mut self,
        pot: &Potential,
        x: &[Vec3],
        phi: &[Real],
        v: &[Vec3],
    ) -> Vec<(&'static str, Real)> {
        let sc = pot.body;
        let nf = sc.num_faces();
        let (a, b) = sc.forms(x, phi);
        let mut term_energies = Vec::new();
        let mut term_fields = Vec::new();
        for (t, map) in pot.terms.iter().zip(&pot.pattern.maps) {
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
        for t in pot.terms.iter() {
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
        for name in crate::energy::term::slot_fields(pot.terms) {
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
        if self.selection.morphoshell_fields {
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
            states: &state.terms,
            ..*pot
        };
        let (x, phi) = (&state.x[..], &state.dofs[..]);
        let index = self.frames.len();
        row.frame = index;
        self.built_is_written = false;
        let term_energies = self.fill(pot, x, phi, v);
        row.energy = crate::integrate::report::energies_of(pot, term_energies, v);
        row.observables = pot
            .terms
            .iter()
            .flat_map(|t| crate::energy::term::observables(t.as_ref(), pot, x, phi))
            .chain(row.path.iter().cloned())
            .chain(row.reactions.iter().flat_map(|r| r.columns()))
            .collect();
        if !row.reaction_field.is_empty() {
            self.frame_mesh.vertex_fields.insert(
                "reaction".into(),
                Field {
                    components: 3,
                    data: row
                        .reaction_field
                        .iter()
                        .flat_map(|r| [r.x, r.y, r.z])
                        .collect(),
                },
            );
        }
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
        let s = crate::mesh::io::series_xml(&self.frames);
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
            s.chord_iterations += n("chord_iterations");
            s.gradient_only_checks += n("gradient_only_checks");
            s.indefinite_iterations += n("indefinite_iterations");
            s.saddle_escapes += n("saddle_escapes");
            s.diffusion_substeps += n("diffusion_substeps");
            s.diffusion_rejected += n("diffusion_rejected");
            s.diffusion_factorisations += n("diffusion_factorisations");
            s.diffusion_cg_iterations += n("diffusion_cg_iterations");
            s.diffusion_direct_solves += n("diffusion_direct_solves");
            s.moisture_seconds += x("moisture_seconds");
            s.wall_seconds += x("wall_seconds");
            if let Some(ls) = &mut s.linear_system {
                let l = |k: &str| prev["linear_system"][k].as_u64().unwrap_or(0) as usize;
                ls.factorisations += l("factorisations");
                ls.failed_factorisations += l("failed_factorisations");
                let steps = s.steps.max(1) as Real;
                ls.factorisations_per_step = ls.factorisations as Real / steps;
                ls.iterations_per_step = s.newton_iterations as Real / steps;
            }
            let tm = &mut s.timing;
            tm.build += t("build");
            tm.analysis += t("analysis");
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
    let sc = pot.body;
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
    let Some(ga) = pot
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
        let mu_t = pot.lame(f).beta * pot.thickness(f);
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

impl crate::integrate::Sink for Writer {
    fn frame(
        &mut self,
        pot: &Potential,
        state: &State,
        v: &[Vec3],
        row: LogRow,
        driver: Option<&crate::integrate::DriverState>,
    ) -> Result<(), OutputError> {
        Writer::frame(self, pot, state, v, row, driver)
    }
    fn set_face_field(&mut self, name: &str, data: Vec<Real>) {
        Writer::set_face_field(self, name, data)
    }
    fn num_faces(&self) -> usize {
        Writer::num_faces(self)
    }
    fn num_frames(&self) -> usize {
        Writer::num_frames(self)
    }
    fn last_frame(&self) -> String {
        Writer::last_frame(self)
    }
    fn release_reserve(&mut self) {
        Writer::release_reserve(self)
    }
    fn summary(&self, summary: &Summary) -> Result<(), OutputError> {
        Writer::summary(self, summary)
    }
}
