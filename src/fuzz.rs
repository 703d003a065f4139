//! An in-process fuzzer on stable Rust for shellsim's input paths: legacy VTK, XML VTK, the
//! shape-collection formats (OFF, OBJ, PLY, STL), the settings (through [`Scene::build`]),
//! restart frames, and the commands' own inputs: frames drawn by `render`, logs drawn by
//! `plot`, `mesh`'s arguments, sweep files and MorphoShell settings files.
//!
//! Each execution takes a seed input, applies one to four structured mutations (truncation,
//! bit flips, a number replaced by an extreme one, a count edited, a span deleted, duplicated or
//! filled with random bytes) and runs the target under `catch_unwind`. Every outcome but a panic
//! is fine: an error is a rejected input, `Ok` an accepted one. A panic (including one caught by
//! the mesh readers' own guard) is a crash, kept with its input.
//!
//! Run from `cargo test` (10⁴ executions per target) and from `scripts/fuzz.sh` (10⁶ or more).

use crate::mesh::generate::Rng;
use crate::mesh::io::mesh_from_bytes;
use crate::mesh::{Mesh, Topology};
use crate::model::Scene;
use crate::settings::Settings;

/// An input path under test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// `.vtk` bytes → mesh → validation → topology.
    Legacy,
    /// `.vtu`/`.vtp` bytes → mesh → validation → topology.
    Xml,
    /// Settings text → settings → scene on a fixed mesh.
    Settings,
    /// `.vtu` frame bytes → restart state for a fixed scene.
    Restart,
    /// `.off` bytes → mesh → validation → topology.
    Off,
    /// `.obj` bytes → mesh → validation → topology.
    Obj,
    /// `.ply` bytes (ASCII and binary) → mesh → validation → topology.
    Ply,
    /// `.stl` bytes (ASCII and binary) → mesh → validation → topology.
    Stl,
    /// `.vtu`/`.vtk` frame bytes → mesh → `render`'s checks and picture (small), coloured by
    /// the default field, by one of the mesh's fields and by a field it lacks.
    Render,
    /// `log.csv` bytes → `plot`'s columns and picture (small).
    Plot,
    /// `shellsim mesh` arguments, one a line → the real parser → the mesh (at most
    /// [`MESH_FACES`] faces), checked, not written.
    Mesh,
    /// Sweep file text → the sweep's checks and run count, nothing read or written.
    Sweep,
    /// MorphoShell settings text → `import-morphoshell`'s translation → settings.
    ImportMorphoshell,
}

/// The most faces a mesh of the `mesh` target may have (larger ones are refused before they
/// are generated, as `shellsim mesh` refuses more than [`crate::mesh::generate::MAX_FACES`]).
pub const MESH_FACES: crate::math::Real = 2000.0;

/// The picture size of the `render` target (the smallest `render` draws).
const RENDER_SIZE: (usize, usize) = (64, 64);

/// The picture size of the `plot` target (the smallest `plot` draws).
const PLOT_SIZE: (usize, usize) = (200, 150);

impl Target {
    /// All targets, in order.
    pub const ALL: [Target; 13] = [
        Target::Legacy,
        Target::Xml,
        Target::Settings,
        Target::Restart,
        Target::Off,
        Target::Obj,
        Target::Ply,
        Target::Stl,
        Target::Render,
        Target::Plot,
        Target::Mesh,
        Target::Sweep,
        Target::ImportMorphoshell,
    ];
    /// Its name in reports and crash files.
    pub fn name(self) -> &'static str {
        match self {
            Target::Legacy => "legacy",
            Target::Xml => "xml",
            Target::Settings => "settings",
            Target::Restart => "restart",
            Target::Off => "off",
            Target::Obj => "obj",
            Target::Ply => "ply",
            Target::Stl => "stl",
            Target::Render => "render",
            Target::Plot => "plot",
            Target::Mesh => "mesh",
            Target::Sweep => "sweep",
            Target::ImportMorphoshell => "import-morphoshell",
        }
    }

    /// The file extension of its inputs.
    pub fn ext(self) -> &'static str {
        match self {
            Target::Legacy => "vtk",
            Target::Xml | Target::Restart | Target::Render => "vtu",
            Target::Settings | Target::Sweep => "toml",
            Target::Plot => "csv",
            Target::Mesh => "args",
            Target::ImportMorphoshell => "txt",
            Target::Off => "off",
            Target::Obj => "obj",
            Target::Ply => "ply",
            Target::Stl => "stl",
        }
    }

    /// The target of an extension or name (`vtk` and `legacy` alike; an extension names the
    /// first target reading it).
    pub fn from_name(name: &str) -> Option<Target> {
        Target::ALL
            .into_iter()
            .find(|t| t.name() == name)
            .or_else(|| Target::ALL.into_iter().find(|t| t.ext() == name))
    }

    /// The target of a crash file's name, `TARGET-…` (the longest target name it starts with).
    pub fn of_file(file: &str) -> Option<Target> {
        Target::ALL
            .into_iter()
            .filter(|t| file.starts_with(&format!("{}-", t.name())))
            .max_by_key(|t| t.name().len())
    }
}

/// What one target needs: seed inputs, and for settings and restarts the fixed mesh or scene.
pub struct Harness {
    /// The target.
    pub target: Target,
    /// Seed inputs the mutations start from.
    pub seeds: Vec<Vec<u8>>,
    /// The mesh settings are built on (settings target).
    pub mesh: Option<Mesh>,
    /// The scene frames are restarted into (restart target).
    pub scene: Option<Scene>,
    /// The settings every run of a sweep starts from (sweep target).
    pub base_settings: Option<String>,
}

/// Counts of one fuzzing run.
#[derive(Clone, Debug, Default)]
pub struct Report {
    /// Executions.
    pub execs: u64,
    /// Inputs accepted.
    pub accepted: u64,
    /// Inputs rejected with an error.
    pub rejected: u64,
    /// Inputs that panicked, with the panic message (at most 20 kept).
    pub crashes: Vec<(String, Vec<u8>)>,
    /// Panics in all (the kept ones and the rest).
    pub panics: u64,
    /// Wall time (s).
    pub seconds: f64,
}

/// Uniform in `0..n` (`n > 0`) from the mesh generator's seeded generator.
fn below(rng: &mut Rng, n: usize) -> usize {
    (rng.next_u64() % n.max(1) as u64) as usize
}

/// Numbers that break careless readers.
const EXTREMES: [&str; 16] = [
    "0",
    "-1",
    "-7",
    "4294967295",
    "4294967296",
    "18446744073709551615",
    "9223372036854775807",
    "9.2e18",
    "1e308",
    "-1e308",
    "1e-320",
    "nan",
    "inf",
    "-inf",
    "1e160",
    "3",
];

/// Byte ranges of the number tokens of `b`.
fn numbers(b: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let starts = c.is_ascii_digit()
            || ((c == b'-' || c == b'.') && i + 1 < b.len() && b[i + 1].is_ascii_digit());
        if starts && (i == 0 || !b[i - 1].is_ascii_alphanumeric()) {
            let s = i;
            i += 1;
            while i < b.len()
                && (b[i].is_ascii_digit() || matches!(b[i], b'.' | b'e' | b'E' | b'-' | b'+'))
            {
                i += 1;
            }
            out.push((s, i));
        } else {
            i += 1;
        }
    }
    out
}

/// One random structured mutation of `b`.
pub fn mutate(b: &mut Vec<u8>, rng: &mut Rng) {
    let len = b.len();
    match below(rng, 8) {
        0 if len > 0 => b.truncate(below(rng, len)),
        1 if len > 0 => {
            for _ in 0..1 + below(rng, 8) {
                let i = below(rng, len);
                b[i] ^= 1 << below(rng, 8);
            }
        }
        2 | 3 => {
            let nums = numbers(b);
            if nums.is_empty() {
                return;
            }
            let (s, e) = nums[below(rng, nums.len())];
            let new: Vec<u8> = if below(rng, 2) == 0 {
                EXTREMES[below(rng, EXTREMES.len())].as_bytes().to_vec()
            } else {
                // A count edit: ±1, ×2, ×1000 or 0 of the value.
                let v: f64 = std::str::from_utf8(&b[s..e])
                    .ok()
                    .and_then(|t| t.parse().ok())
                    .unwrap_or(0.0);
                let w = match below(rng, 5) {
                    0 => v + 1.0,
                    1 => v - 1.0,
                    2 => v * 2.0,
                    3 => v * 1000.0,
                    _ => 0.0,
                };
                if w.fract() == 0.0 && w.abs() < 1e15 {
                    format!("{}", w as i64).into_bytes()
                } else {
                    format!("{w:e}").into_bytes()
                }
            };
            b.splice(s..e, new);
        }
        4 if len > 0 => {
            let s = below(rng, len);
            let e = (s + 1 + below(rng, 64)).min(len);
            b.drain(s..e);
        }
        5 if len > 0 => {
            let s = below(rng, len);
            let e = (s + 1 + below(rng, 256)).min(len);
            let chunk = b[s..e].to_vec();
            let at = below(rng, len);
            b.splice(at..at, chunk);
        }
        6 if len > 0 => {
            let s = below(rng, len);
            let e = (s + 1 + below(rng, 16)).min(len);
            for c in &mut b[s..e] {
                *c = rng.next_u64() as u8;
            }
        }
        _ if len > 0 => {
            // A whole line removed or repeated.
            let lines: Vec<usize> = std::iter::once(0)
                .chain(
                    b.iter()
                        .enumerate()
                        .filter(|(_, &c)| c == b'\n')
                        .map(|(i, _)| i + 1),
                )
                .filter(|&i| i < len)
                .collect();
            let k = below(rng, lines.len());
            let s = lines[k];
            let e = lines.get(k + 1).copied().unwrap_or(len);
            if below(rng, 2) == 0 {
                b.drain(s..e);
            } else {
                let l = b[s..e].to_vec();
                b.splice(s..s, l);
            }
        }
        _ => {}
    }
}

impl Harness {
    /// Runs the target once on `input`: `Ok(true)` accepted, `Ok(false)` rejected, `Err` a
    /// panic (its message).
    pub fn exec(&self, input: &[u8]) -> Result<bool, String> {
        let run = || -> Result<bool, String> {
            Ok(match self.target {
                Target::Legacy
                | Target::Xml
                | Target::Off
                | Target::Obj
                | Target::Ply
                | Target::Stl => match mesh_from_bytes(input, self.target.ext()) {
                    Err(e) if e.contains("please report") => return Err(e),
                    Err(_) => false,
                    Ok(m) => m.validate().is_ok() && Topology::build(&m).is_ok(),
                },
                Target::Settings => {
                    let text = String::from_utf8_lossy(input);
                    match Settings::from_str_with(&text, "fuzz", &[]) {
                        Err(_) => false,
                        Ok(s) => match &self.mesh {
                            Some(m) => Scene::build(m.clone(), s)
                                .and_then(|sc| crate::integrate::check_scene(&sc))
                                .is_ok(),
                            None => true,
                        },
                    }
                }
                Target::Restart => {
                    let Some(scene) = &self.scene else {
                        return Ok(false);
                    };
                    match mesh_from_bytes(input, "vtu") {
                        Err(e) if e.contains("please report") => return Err(e),
                        Err(_) => false,
                        Ok(m) => crate::restart::restart_from_frame(m, "fuzz", scene).is_ok(),
                    }
                }
                Target::Render => render(input)?,
                Target::Plot => plot(input),
                Target::Mesh => mesh(input),
                Target::Sweep => {
                    let text = String::from_utf8_lossy(input);
                    let base = self.base_settings.as_deref().unwrap_or_default();
                    crate::sweep::check_text(&text, "fuzz", base, &crate::cli::sweep_run_overrides)
                        .is_ok()
                }
                Target::ImportMorphoshell => {
                    crate::cli::import_text(&String::from_utf8_lossy(input), "fuzz", None).is_ok()
                }
            })
        };
        crate::mesh::io::catch_quietly(run).and_then(|r| r)
    }

    /// `execs` mutated executions from RNG seed `seed`.
    pub fn run(&self, execs: u64, seed: u64) -> Report {
        let rng = &mut Rng::new(seed ^ (self.target as u64).wrapping_mul(0x51_7CC1_B727_220A));
        let mut rep = Report::default();
        let start = std::time::Instant::now();
        // An abort (an allocation beyond memory) cannot be caught: with this variable set, each
        // input is written to the file it names before it runs, so the last one survives.
        let last = std::env::var_os("SHELLSIM_FUZZ_LAST");
        for _ in 0..execs {
            let mut input = self.seeds[below(rng, self.seeds.len())].clone();
            for _ in 0..1 + below(rng, 4) {
                mutate(&mut input, rng);
            }
            if let Some(p) = &last {
                let _ = std::fs::write(p, &input);
            }
            rep.execs += 1;
            match self.exec(&input) {
                Ok(true) => rep.accepted += 1,
                Ok(false) => rep.rejected += 1,
                Err(msg) => {
                    rep.panics += 1;
                    if rep.crashes.len() < 20 {
                        rep.crashes.push((msg, input));
                    }
                }
            }
        }
        rep.seconds = start.elapsed().as_secs_f64();
        rep
    }
}

/// The `render` target: the frame read (`.vtu`, else `.vtk`), then drawn as `render` draws it,
/// with the default field, the input's choice of its fields (with a view and a range) and a
/// field it lacks. Accepted when the first picture is drawn.
fn render(input: &[u8]) -> Result<bool, String> {
    use crate::render::Shading;
    let ext = if input.starts_with(b"<") {
        "vtu"
    } else {
        "vtk"
    };
    let m = match mesh_from_bytes(input, ext) {
        Err(e) if e.contains("please report") => return Err(e),
        Err(_) => return Ok(false),
        Ok(m) => m,
    };
    let draw = |field: Option<String>, view: &str, range: Option<&str>, shading| {
        crate::cli::render_frame(&m, "fuzz", field, view, RENDER_SIZE, range, shading).is_ok()
    };
    let accepted = draw(None, "iso", None, Shading::Smooth);
    // A choice from the input's bytes, so that a saved input replays the same calls.
    let pick = input
        .iter()
        .fold(0usize, |h, &c| h.wrapping_mul(31) ^ c as usize);
    let fields: Vec<&String> = m.face_fields.keys().chain(m.vertex_fields.keys()).collect();
    if !fields.is_empty() {
        let f = fields[pick % fields.len()].clone();
        let view = ["top", "side", "30,-95", "nan,1e308", "back"][pick / 7 % 5];
        let range = [None, Some("-1,1"), Some("0,1e-300"), Some("1,0")][pick / 3 % 4];
        let shading = [Shading::Smooth, Shading::Flat][pick / 11 % 2];
        draw(Some(f), view, range, shading);
    }
    draw(Some("no_such_field".into()), "iso", None, Shading::Flat);
    Ok(accepted)
}

/// The `plot` target: the log drawn as `plot` draws it by default, then with every column on a
/// logarithmic axis over the frame number. Accepted when the first picture is drawn.
fn plot(input: &[u8]) -> bool {
    let Ok(text) = std::str::from_utf8(input) else {
        return false;
    };
    let plot = |x, y: &str, log_y| crate::cli::plot_log(text, "fuzz", x, y, PLOT_SIZE, log_y);
    let accepted = plot(None, "energy_total", false).is_ok();
    let all = text.lines().next().unwrap_or_default();
    let _ = plot(Some("frame"), all, true);
    accepted
}

/// The `mesh` target: the input's lines are the arguments after `shellsim`, parsed by the
/// command line's parser; a `mesh` command is generated (not written).
fn mesh(input: &[u8]) -> bool {
    use clap::Parser;
    let text = String::from_utf8_lossy(input);
    let args = std::iter::once("shellsim").chain(text.lines());
    match crate::cli::Cli::try_parse_from(args) {
        Ok(crate::cli::Cli {
            command: Some(crate::cli::Command::Mesh(a)),
            ..
        }) => crate::cli::build_mesh(&a, MESH_FACES).is_ok(),
        _ => false,
    }
}

/// The harnesses of all targets, with seeds from a source tree at `root`: the VTK files under
/// `tests/data/vtk` and `tests/data/shapes`, the scenes under `settings/` and the sweeps under
/// `settings/sweeps/`, logs, `mesh` arguments, a sweep file and a MorphoShell settings file
/// under `tests/data/fuzz_seeds/`, and files shellsim writes itself (a small programmed sheet in
/// every output format, a restart frame with velocities and edge angles).
pub fn harnesses(root: &std::path::Path) -> Result<Vec<Harness>, String> {
    use crate::mesh::io::{mesh_to_bytes, Format};
    use crate::mesh::Field;
    let read_dir = |dir: &str, exts: &[&str]| -> Result<Vec<Vec<u8>>, String> {
        let d = root.join(dir);
        let mut files: Vec<_> = std::fs::read_dir(&d)
            .map_err(|e| format!("{}: {e}", d.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.extension()
                    .and_then(|e| e.to_str())
                    .is_some_and(|e| exts.contains(&e))
            })
            .collect();
        files.sort();
        files
            .iter()
            .map(|p| std::fs::read(p).map_err(|e| format!("{}: {e}", p.display())))
            .collect()
    };
    let mut sheet = crate::mesh::generate::rectangle(
        -0.5,
        -0.5,
        1.0,
        1.0,
        0.34,
        crate::mesh::generate::Spacing::default(),
    );
    crate::cases::Case::SphericalCap.program(&mut sheet);
    let own =
        |m: &Mesh, f: Format| -> Result<Vec<u8>, String> { Ok(mesh_to_bytes(m, f, "fuzz seed")) };
    let mut legacy = read_dir("tests/data/vtk", &["vtk"])?;
    legacy.push(own(&sheet, Format::Vtk)?);
    legacy.push(own(&sheet, Format::VtkAscii)?);
    let mut xml = read_dir("tests/data/vtk", &["vtu", "vtp"])?;
    xml.push(own(&sheet, Format::Vtu)?);
    let settings = read_dir("settings", &["toml"])?;
    let s = Settings::from_str_with(
        "[solver]\nmode = \"dynamic\"\n[material]\nthickness = 0.05\nbending = \"midedge_sin\"\n\
         [rest]\ntarget = \"mesh\"\n[time]\nend = 0.1\n",
        "fuzz",
        &[],
    )
    .map_err(|e| e.to_string())?;
    let scene = Scene::build(sheet.clone(), s).map_err(|e| e.to_string())?;
    let mut frame = sheet.clone();
    let nv = frame.positions.len();
    frame.vertex_fields.insert(
        "velocity".into(),
        Field {
            components: 3,
            data: (0..3 * nv).map(|i| 0.01 * i as f64).collect(),
        },
    );
    frame.face_fields.insert(
        "edge_angles".into(),
        Field {
            components: 3,
            data: vec![0.0; 3 * frame.faces.len()],
        },
    );
    let restart = vec![own(&frame, Format::Vtu)?];
    // Frames to draw: the XML files and shellsim's own frames (legacy and XML, with fields).
    let mut render = read_dir("tests/data/vtk", &["vtu"])?;
    render.push(own(&frame, Format::Vtu)?);
    render.push(own(&frame, Format::Vtk)?);
    render.push(own(&sheet, Format::VtkAscii)?);
    let lce_cone = std::fs::read_to_string(root.join("settings/lce_cone.toml"))
        .map_err(|e| format!("settings/lce_cone.toml: {e}"))?;
    let mut sweeps = read_dir("settings/sweeps", &["toml"])?;
    sweeps.extend(read_dir("tests/data/fuzz_seeds", &["toml"])?);
    let seeded = |t: Target, base: Option<String>| -> Result<Harness, String> {
        let seeds = match t {
            Target::Sweep => sweeps.clone(),
            _ => read_dir("tests/data/fuzz_seeds", &[t.ext()])?,
        };
        Ok(Harness {
            target: t,
            seeds,
            mesh: None,
            scene: None,
            base_settings: base,
        })
    };
    let shapes = |t: Target| -> Result<Harness, String> {
        Ok(Harness {
            target: t,
            seeds: read_dir("tests/data/shapes", &[t.ext()])?,
            mesh: None,
            scene: None,
            base_settings: None,
        })
    };
    Ok(vec![
        Harness {
            target: Target::Legacy,
            seeds: legacy,
            mesh: None,
            scene: None,
            base_settings: None,
        },
        Harness {
            target: Target::Xml,
            seeds: xml,
            mesh: None,
            scene: None,
            base_settings: None,
        },
        Harness {
            target: Target::Settings,
            seeds: settings,
            mesh: Some(sheet),
            scene: None,
            base_settings: None,
        },
        Harness {
            target: Target::Restart,
            seeds: restart,
            mesh: None,
            scene: Some(scene),
            base_settings: None,
        },
        shapes(Target::Off)?,
        shapes(Target::Obj)?,
        shapes(Target::Ply)?,
        shapes(Target::Stl)?,
        Harness {
            target: Target::Render,
            seeds: render,
            mesh: None,
            scene: None,
            base_settings: None,
        },
        seeded(Target::Plot, None)?,
        seeded(Target::Mesh, None)?,
        seeded(Target::Sweep, Some(lce_cone))?,
        seeded(Target::ImportMorphoshell, None)?,
    ])
}
