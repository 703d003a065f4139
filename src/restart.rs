//! Restart from a frame written by shellsim (seed 001, "restart from an earlier frame").
//!
//! A frame holds the deformed positions, the per-vertex `velocity`, with an edge-DOF bending
//! model the per-face `edge_angles`, and the state of terms that track one across steps (an end
//! moment's `moment_turn`, [`crate::energy::term::Tracked::state_field`]). The reference geometry, rest forms and material come from
//! the mesh file and settings of the new run, so the frame must have the same vertices and faces
//! as that mesh. The frame's time (dynamics) or dial (statics) is looked up in the `series.pvd`
//! next to it; without one the run starts its clock at 0 and says so in a warning.

use crate::integrate::InitialState;
use crate::math::{Real, Vec3};
use crate::mesh::io::read_mesh;
use crate::mesh::MeshError;
use crate::model::Scene;
use crate::solve::State;
use std::path::Path;

/// Largest disagreement tolerated between the two faces' copies of an edge angle (rad). Frames
/// written by shellsim repeat the same value exactly; text formats round to ~1e-16 relative.
const EDGE_ANGLE_TOLERANCE: Real = 1e-9;

/// Reads a restart state for `scene` from `path`. Returns the state and any warnings.
pub fn read_restart(path: &Path, scene: &Scene) -> Result<(InitialState, Vec<String>), MeshError> {
    let name = path.display().to_string();
    if let Some((dial, positions)) = read_ansatz(path, scene.body.num_vertices())? {
        let frame = crate::mesh::Mesh {
            positions,
            faces: scene.body.input_faces(),
            ..Default::default()
        };
        let (state, v, warnings) = restart_from_frame(frame, &name, scene)?;
        return Ok((
            InitialState {
                state,
                v,
                time: 0.0,
                dial: Some(dial),
                driver: None,
            },
            warnings,
        ));
    }
    let frame = read_mesh(path)?;
    let bad = |reason: String| MeshError::Invalid {
        path: name.clone(),
        reason,
    };
    let driver = read_driver_state(path)?;
    // An arc-length frame's series time is its path coordinate; its dial is in its state file.
    let arc_dial = driver
        .as_ref()
        .filter(|d| !d.arc_length.is_empty())
        .map(|d| d.dial);
    let time = match series_time(path) {
        Some(t) => {
            let t = t.map_err(&bad)?;
            match arc_dial {
                Some(d) => {
                    if !(t.is_finite() && t >= 0.0) {
                        return Err(bad(format!(
                            "series.pvd gives the arc-length frame the path coordinate {}, \
                             not a finite number ≥ 0",
                            crate::math::human(t)
                        )));
                    }
                    check_time(scene, d).map_err(&bad)?;
                }
                None => check_time(scene, t).map_err(&bad)?,
            }
            Some(t)
        }
        None => None,
    };
    let (state, v, mut warnings) = restart_from_frame(frame, &name, scene)?;
    if time.is_none() {
        warnings.push(format!(
            "{name}: not listed in a series.pvd next to it; the restart starts at time 0"
        ));
    }
    let mut state = state;
    if !scene.globals.is_empty() {
        // The global DOFs (a force-controlled obstacle's offset) are in the state file only.
        let ne = scene.body.num_edge_dofs();
        match &driver {
            Some(d) if d.globals.len() == scene.globals.len() => {
                if let Some(k) = d.globals.iter().position(|q| !q.is_finite()) {
                    return Err(bad(format!(
                        "its state file gives {} the value {}",
                        scene.globals[k].name, d.globals[k]
                    )));
                }
                state.dofs[ne..].copy_from_slice(&d.globals);
            }
            _ => warnings.push(format!(
                "{name}: its state file gives no value for {}; {} from the settings' start",
                scene
                    .globals
                    .iter()
                    .map(|g| g.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
                if scene.globals.len() == 1 {
                    "it starts"
                } else {
                    "they start"
                }
            )),
        }
    }
    if driver.is_none() {
        warnings.push(format!(
            "{name}: no {} beside it; the step control, holds and moisture start afresh, so \
             the run does not follow the uninterrupted one exactly",
            state_file(path)
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default()
        ));
    }
    Ok((
        InitialState {
            state,
            v,
            time: time.unwrap_or(0.0),
            dial: arc_dial,
            driver,
        },
        warnings,
    ))
}

/// The state file written beside a frame (`frame_00003.vtu` → `frame_00003.state.json`): the
/// driver's state that a restart reads ([`crate::integrate::DriverState`]).
pub fn state_file(frame: &Path) -> std::path::PathBuf {
    let stem = frame
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    frame.with_file_name(format!("{stem}.state.json"))
}

/// The driver's state written beside the frame `path` (`None` when there is none); a file that
/// is not one is an error naming it.
fn read_driver_state(path: &Path) -> Result<Option<crate::integrate::DriverState>, MeshError> {
    let p = state_file(path);
    let text = match std::fs::read_to_string(&p) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => {
            return Err(MeshError::Read {
                path: p.display().to_string(),
                reason: e.to_string(),
            })
        }
    };
    serde_json::from_str(&text)
        .map(Some)
        .map_err(|e| MeshError::Invalid {
            path: p.display().to_string(),
            reason: format!("not a shellsim frame state: {e}"),
        })
}

/// A restart's time must be finite and inside the run: the dial in [0, 1] in statics, the time
/// in [0, time.end] in dynamics.
fn check_time(scene: &Scene, t: Real) -> Result<(), String> {
    let (what, hi) = match scene.settings.solver.mode {
        crate::settings::Mode::Static => ("dial", 1.0),
        crate::settings::Mode::Dynamic => ("time", scene.settings.time.end),
        crate::settings::Mode::Explicit => ("time", Real::MAX),
    };
    if !(t.is_finite() && (0.0..=hi).contains(&t)) {
        return Err(format!(
            "series.pvd gives the frame the {what} {t_h}, outside this run's [0, {hi_h}]",
            t_h = crate::math::human(t),
            hi_h = crate::math::human(hi)
        ));
    }
    Ok(())
}

/// Positions, velocities (if the frame has them) and edge DOFs of a restart frame for `scene`,
/// with warnings; `name` names the frame in messages.
#[allow(clippy::type_complexity)]
pub fn restart_from_frame(
    frame: crate::mesh::Mesh,
    name: &str,
    scene: &Scene,
) -> Result<(State, Option<Vec<Vec3>>, Vec<String>), MeshError> {
    let bad = |reason: String| MeshError::Invalid {
        path: name.to_string(),
        reason,
    };
    let mut warnings = Vec::new();
    let mut frame = frame;
    // Frames keep the input's corner order; the scene may start slivers at another corner.
    if frame.positions.len() != scene.body.num_vertices() || frame.faces != scene.body.input_faces()
    {
        return Err(bad(format!(
            "restart frame has {} vertices and {} faces, the mesh {} has {} and {} (or the faces \
             differ): a restart needs the frame of a run on the same mesh",
            frame.positions.len(),
            frame.faces.len(),
            scene.body.mesh.name(),
            scene.body.num_vertices(),
            scene.body.num_faces()
        )));
    }
    frame.faces = scene.body.mesh.faces.clone();
    for name in scene.slot_fields() {
        if let Some(f) = frame.face_fields.get_mut(name) {
            if f.components == 3 && f.data.len() == 3 * scene.body.num_faces() {
                scene.body.reorder_slots(&mut f.data, false);
            }
        }
    }
    if let Some(v) = frame
        .positions
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
    {
        return Err(bad(format!("vertex {v} has a non-finite position")));
    }
    // A face collapsed to a line or a point has no normal and no forms to restart from.
    for (f, face) in frame.faces.iter().enumerate() {
        let [a, b, c] = face.map(|v| frame.positions[v]);
        if crate::mesh::area_ratio(&a, &b, &c) <= 1e-12 {
            return Err(bad(format!(
                "face {f} {face:?} is collapsed in the restart frame (zero area): no state to \
                 restart from"
            )));
        }
    }
    let v = match frame.vertex_field("velocity", 3)? {
        Some(f) => {
            // Beyond 1e30 m/s the kinetic energy overflows: no state to restart from.
            if let Some(i) = f
                .data
                .iter()
                .position(|c| !c.is_finite() || c.abs() > crate::mesh::MAX_COORDINATE)
            {
                return Err(bad(format!(
                    "field 'velocity' at vertex {} is {} m/s, beyond ±{} m/s",
                    i / 3,
                    crate::math::human(f.data[i]),
                    crate::math::human(crate::mesh::MAX_COORDINATE)
                )));
            }
            Some(
                (0..frame.positions.len())
                    .map(|i| Vec3::from_column_slice(f.get(i)))
                    .collect(),
            )
        }
        None => None,
    };
    let mut phi = vec![0.0; scene.num_scalar_dofs()];
    if scene.body.has_edge_dofs() {
        match frame.face_field("edge_angles", 3)? {
            Some(f) => {
                let mut seen = vec![false; phi.len()];
                for (fi, fe) in scene.body.topo.face_edges.iter().enumerate() {
                    for (i, &e) in fe.iter().enumerate() {
                        let val = f.get(fi)[i];
                        if !val.is_finite() {
                            return Err(bad(format!(
                                "field 'edge_angles' is not finite at face {fi}, edge {i}"
                            )));
                        }
                        if !seen[e] {
                            phi[e] = val;
                            seen[e] = true;
                        } else if (phi[e] - val).abs() > EDGE_ANGLE_TOLERANCE {
                            return Err(bad(format!(
                                "field 'edge_angles': the two faces of edge {:?} disagree ({} \
                                 at face {fi} vs {})",
                                scene.body.topo.edges[e],
                                crate::math::human(val),
                                crate::math::human(phi[e])
                            )));
                        }
                    }
                }
            }
            None => warnings.push(format!(
                "{name}: no 'edge_angles' field; the edge DOFs start at 0 (the mid-edge average \
                 normals)"
            )),
        }
    }
    // Terms that track a state across steps (an end moment's turns) restart from their fields
    // (the restart file beside the frame, when there is one, then gives the exact state).
    let mut terms = scene.initial_states.clone();
    for t in scene.terms.iter() {
        let Some(tr) = t.tracked() else {
            continue;
        };
        let data = frame.face_field(tr.state_field(), tr.state_components())?;
        match tr.restore(
            &frame.positions,
            &phi,
            data.as_ref().map(|f| f.data.as_slice()),
            terms.get_mut(t.name()),
        ) {
            Ok(Some(w)) => warnings.push(format!("{name}: {w}")),
            Ok(None) => {}
            Err(e) => return Err(bad(e.to_string())),
        }
    }
    Ok((
        State {
            x: frame.positions,
            dofs: phi,
            terms,
        },
        v,
        warnings,
    ))
}

/// The `timestep` of `path`'s entry in the `series.pvd` of its folder: `None` without an entry,
/// an error when the entry's value is not a number.
fn series_time(path: &Path) -> Option<Result<Real, String>> {
    let dir = path.parent()?;
    let file = path.file_name()?.to_str()?;
    let text = std::fs::read_to_string(dir.join("series.pvd")).ok()?;
    text.lines()
        .filter(|l| l.contains(&format!("file=\"{file}\"")))
        .find_map(|l| {
            let rest = &l[l.find("timestep=\"")? + 10..];
            let v = &rest[..rest.find('"')?];
            Some(v.parse::<Real>().map_err(|_| {
                format!("series.pvd gives the frame the timestep '{v}', not a number")
            }))
        })
}

/// A MorphoShell ansatz file: legacy ASCII VTK whose title line reads
/// `dial_factor = <s>[, stepcount = <n>]`, as MorphoShell writes its frames and reads its
/// ansatz files. The title and the `POINTS` block are read (exactly 3 × the count of
/// coordinates); the `POLYGONS` block MorphoShell writes next must be there and complete, and
/// the file must end with a newline, as MorphoShell's writer ends it: a file cut short is an
/// error, not a shape with a cut coordinate. The face and vertex data after the polygons are
/// ignored, as in MorphoShell. Returns `None` when `path` is not one (any other frame), else the
/// dial factor and the positions; errors name the file and line.
pub fn read_ansatz(path: &Path, vertices: usize) -> Result<Option<(Real, Vec<Vec3>)>, MeshError> {
    let name = path.display().to_string();
    let bad = |line: usize, reason: String| MeshError::Invalid {
        path: if line > 0 {
            format!("{name}:{line}")
        } else {
            name.clone()
        },
        reason,
    };
    // The title is the second line; a binary file or another title is not an ansatz. Only the
    // first two lines (at most 4 KiB) are read to tell: a shellsim frame is read once, by
    // read_mesh.
    let head = {
        use std::io::{BufRead, Read};
        let Ok(file) = std::fs::File::open(path) else {
            return Ok(None); // read_mesh names the I/O error
        };
        let mut r = std::io::BufReader::new(file.take(4096));
        let mut head = Vec::new();
        for _ in 0..2 {
            if r.read_until(b'\n', &mut head).is_err() {
                return Ok(None);
            }
        }
        head
    };
    let Some(title) = head.split(|&b| b == b'\n').nth(1) else {
        return Ok(None);
    };
    let Ok(title) = std::str::from_utf8(title) else {
        return Ok(None);
    };
    let Some(rest) = title.trim_start().strip_prefix("dial_factor") else {
        return Ok(None);
    };
    let bytes = std::fs::read(path).map_err(|e| bad(0, e.to_string()))?;
    let Ok(text) = std::str::from_utf8(&bytes) else {
        return Err(bad(
            0,
            "a MorphoShell ansatz file must be ASCII text".into(),
        ));
    };
    let value = rest
        .trim_start()
        .strip_prefix('=')
        .map(|r| r.split(',').next().unwrap_or("").trim());
    let dial: Real = match value.map(str::parse) {
        Some(Ok(d)) => d,
        _ => {
            return Err(bad(
                2,
                format!(
                    "the title '{}' must read 'dial_factor = <number>, ...'",
                    title.trim()
                ),
            ))
        }
    };
    if !(0.0..=1.0).contains(&dial) {
        return Err(bad(2, format!("dial_factor {dial} is outside [0, 1]")));
    }
    let all: Vec<&str> = text.lines().collect();
    if all.get(2).map(|l| l.trim()) != Some("ASCII") {
        return Err(bad(
            3,
            "a MorphoShell ansatz file is legacy VTK in ASCII (third line 'ASCII')".into(),
        ));
    }
    let Some(at) = all
        .iter()
        .position(|l| l.trim_start().starts_with("POINTS"))
    else {
        return Err(bad(0, "no POINTS line".into()));
    };
    let n: usize = all[at]
        .split_whitespace()
        .nth(1)
        .and_then(|t| t.parse().ok())
        .ok_or_else(|| bad(at + 1, format!("'{}': no point count", all[at].trim())))?;
    if n != vertices {
        return Err(bad(
            at + 1,
            format!("{n} points; the mesh has {vertices} vertices (the ansatz must be of the same mesh)"),
        ));
    }
    // MorphoShell writes every line with its newline: a file ending inside a number was cut.
    crate::mesh::ends_mid_number(&bytes).map_err(|e| {
        let (l, reason) = e
            .strip_prefix("line ")
            .and_then(|r| r.split_once(": "))
            .and_then(|(l, r)| Some((l.parse().ok()?, r.to_string())))
            .unwrap_or((0, e.clone()));
        bad(l, reason)
    })?;
    let mut coords = Vec::with_capacity(3 * n);
    let mut line = at + 1;
    while coords.len() < 3 * n {
        let Some(l) = all.get(line) else {
            return Err(bad(
                line,
                format!(
                    "the file ends after {} of {} point coordinates",
                    coords.len(),
                    3 * n
                ),
            ));
        };
        for tok in l.split_whitespace() {
            if coords.len() == 3 * n {
                return Err(bad(
                    line + 1,
                    format!("'{tok}' is more than the {} point coordinates", 3 * n),
                ));
            }
            let v: Real = tok
                .parse()
                .map_err(|_| bad(line + 1, format!("'{tok}' is not a coordinate")))?;
            if !v.is_finite() || v.abs() > crate::mesh::MAX_COORDINATE {
                return Err(bad(
                    line + 1,
                    format!(
                        "coordinate {tok} is not finite or beyond ±{}",
                        crate::math::human(crate::mesh::MAX_COORDINATE)
                    ),
                ));
            }
            coords.push(v);
        }
        line += 1;
    }
    ansatz_polygons(&all, line, n).map_err(|(l, reason)| bad(l, reason))?;
    Ok(Some((
        dial,
        coords
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect(),
    )))
}

/// Checks what follows an ansatz file's points, from line index `from` of `lines`: MorphoShell
/// writes `POLYGONS <faces> <4 × faces>` and one `3 i j k` line per face (indices below
/// `points`) next, then the face and vertex data, which are not read. A file that ends before
/// the polygons are complete was cut short. Errors carry the line (1-based).
fn ansatz_polygons(lines: &[&str], from: usize, points: usize) -> Result<(), (usize, String)> {
    let cut = |l: usize, what: String| {
        (
            l,
            format!("the file ends {what}, where MorphoShell writes more: it is cut short"),
        )
    };
    let Some(at) = (from..lines.len()).find(|&i| !lines[i].trim().is_empty()) else {
        return Err(cut(
            lines.len(),
            format!("after the {points} points, without the POLYGONS block"),
        ));
    };
    let head: Vec<&str> = lines[at].split_whitespace().collect();
    let counts = match head[..] {
        ["POLYGONS", f, size] => f
            .parse::<usize>()
            .ok()
            .zip(size.parse::<usize>().ok())
            .filter(|&(f, size)| f.checked_mul(4) == Some(size)),
        _ => None,
    };
    let Some((faces, _)) = counts else {
        return Err((
            at + 1,
            format!(
                "after the {points} points, expected 'POLYGONS <faces> <4 × faces>' (triangles), \
                 found '{}'",
                lines[at].trim()
            ),
        ));
    };
    for k in 0..faces {
        let l = at + 1 + k;
        let Some(text) = lines.get(l) else {
            return Err(cut(l, format!("after {k} of the {faces} polygons")));
        };
        let ok = match text.split_whitespace().collect::<Vec<_>>()[..] {
            ["3", a, b, c] => [a, b, c]
                .iter()
                .all(|i| i.parse::<usize>().is_ok_and(|i| i < points)),
            _ => false,
        };
        if !ok {
            return Err((
                l + 1,
                format!(
                    "polygon {k} is '{}', not '3 i j k' with indices below {points}",
                    text.trim()
                ),
            ));
        }
    }
    Ok(())
}
