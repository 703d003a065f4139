//! The command line: `shellsim SETTINGS MESH [--out DIR] [--threads N] [--set key=value]...`
//! runs a scene; `shellsim mesh ...` writes generated meshes; `shellsim error ...` measures a
//! frame against an analytic case.
//!
//! Exit codes: 0 converged, 1 ran but did not converge, 2 bad input or I/O error.

use crate::cases::{curvature_error, shape_error, Case};
use crate::integrate::{run, Progress, Quiet};
use crate::math::{Real, Vec3};
use crate::mesh::delaunay::{delaunay_annulus, delaunay_rectangle};
use crate::mesh::generate::{
    annulus, annulus_faces, check_planned_within, rectangle, rectangle_faces, Spacing, MAX_FACES,
};
use crate::mesh::io::{read_mesh, write_mesh, Format};
use crate::mesh::Topology;
use crate::model::Scene;
use crate::output::Writer;
use crate::settings::Settings;
use anyhow::{anyhow, bail, Result};
use clap::{Parser, Subcommand, ValueEnum};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

/// shellsim: thin shells whose rest shape changes.
#[derive(Parser, Debug)]
#[command(
    name = "shellsim",
    version,
    about,
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true,
    after_help = "Exit codes: 0 converged, 1 ran but did not converge, 2 bad input or I/O \
                  error, 130 / 143 interrupted by SIGINT / SIGTERM (the state reached is written \
                  first)."
)]
pub struct Cli {
    #[command(subcommand)]
    pub(crate) command: Option<Command>,
    /// Settings file (TOML); see docs/settings.md.
    #[arg(required = true)]
    settings: Option<PathBuf>,
    /// Triangle mesh: .vtk (legacy ASCII/binary), .vtu/.vtp (XML, inline or appended data, any
    /// of VTK's compressors), or .off, .obj, .ply, .stl.
    #[arg(required = true)]
    mesh: Option<PathBuf>,
    /// Output folder (created if needed). One holding an earlier run's output is refused
    /// unless --overwrite is given.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Replace an earlier run's output in --out (its frames, series, log and summary).
    #[arg(long)]
    overwrite: bool,
    /// Worker threads for assembly (default: all cores). Results do not depend on it.
    #[arg(long)]
    threads: Option<usize>,
    /// Override a settings key, e.g. --set material.thickness=0.002 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// No progress bar, and no start and end lines on stderr (errors are still printed).
    #[arg(long, short)]
    quiet: bool,
    /// Print every step (time or dial, step size, energy, residual) and every Newton iteration
    /// (energy, residual, shift, step length) to stderr, in place of the progress bar.
    #[arg(long, short)]
    verbose: bool,
    /// Start from a frame of an earlier run on the same mesh (positions, velocities, edge DOFs,
    /// and the integrator's state from the frame's `.state.json`; time or dial from the
    /// series.pvd next to it).
    #[arg(long, value_name = "FRAME")]
    restart: Option<PathBuf>,
    /// Continue the series in --out: restart from its last frame (or from --restart FRAME, a
    /// frame of that folder, dropping the frames after it), number the new frames on, and
    /// extend series.pvd, log.csv, run.json and the summary.
    #[arg(long = "continue", conflicts_with = "overwrite")]
    continue_series: bool,
}

#[derive(Subcommand, Debug)]
pub(crate) enum Command {
    /// Write a generated triangle mesh.
    Mesh(MeshArgs),
    /// Error of a frame written by shellsim against an analytic case (prints JSON).
    Error(ErrorArgs),
    /// Convert a MorphoShell settings file into a shellsim settings file with the same physics.
    #[command(name = "import-morphoshell")]
    ImportMorphoshell(ImportArgs),
    /// Expand a sweep file (a grid or a list of --set overrides) into one run folder per point,
    /// with a job list for GNU parallel (run.sh) and a SLURM job array (slurm.sh).
    Sweep(SweepArgs),
    /// Gather the overrides and summary.json fields of runs into one CSV table.
    Collect(CollectArgs),
    /// Draw a frame as a shaded surface coloured by a field, with a colour bar, into a PNG.
    Render(RenderArgs),
    /// Plot columns of a run's log.csv over time, dial or frame into a PNG.
    Plot(PlotArgs),
    /// Inverse design: find the growth factors, director angles or rest forms per face that
    /// make MESH take the shape TARGET at equilibrium (see docs/design.md).
    Design(DesignArgs),
}

#[derive(clap::Args, Debug)]
pub(crate) struct DesignArgs {
    /// Design file: a settings file (the scene) with a [design] section.
    design: PathBuf,
    /// The mesh to design (its reference shape).
    mesh: PathBuf,
    /// The target shape: a mesh with MESH's connectivity.
    target: PathBuf,
    /// Output folder (created if needed).
    #[arg(long, default_value = "design")]
    out: PathBuf,
    /// Replace an earlier design's output in --out.
    #[arg(long)]
    overwrite: bool,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long)]
    threads: Option<usize>,
    /// Override a key of the scene's settings, e.g. --set material.thickness=0.002.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// No line per iteration on stderr.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(clap::Args, Debug)]
pub(crate) struct PlotArgs {
    /// A run folder (its log.csv is read) or a log.csv.
    run: PathBuf,
    /// Output PNG (default: plot.png in the run folder).
    #[arg(short, long)]
    out: Option<PathBuf>,
    /// Columns to plot, comma-separated.
    #[arg(long, default_value = "energy_total")]
    y: String,
    /// The column along the horizontal axis (time, dial, frame, …; default: time, or the dial
    /// for a static run, whose log has no time).
    #[arg(long)]
    x: Option<String>,
    /// Picture size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "1024x768")]
    size: String,
    /// A logarithmic vertical axis (every plotted value must be above 0).
    #[arg(long)]
    log_y: bool,
}

#[derive(clap::Args, Debug)]
pub(crate) struct RenderArgs {
    /// A frame (or any mesh file shellsim reads).
    frame: PathBuf,
    /// Output PNG (default: the frame's name with .png).
    #[arg(short, long)]
    out: Option<PathBuf>,
    /// Field to colour by (default: mean_curvature if there is one; vectors by their norm).
    #[arg(long)]
    field: Option<String>,
    /// iso, top, bottom, front, back, side, or AZIMUTH,ELEVATION in degrees.
    #[arg(long, default_value = "iso", allow_hyphen_values = true)]
    view: String,
    /// Picture size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "1024x768")]
    size: String,
    /// Colour range LOW,HIGH (default: the field's minimum and maximum; a field uniform to
    /// round-off is drawn as one colour).
    #[arg(long, allow_hyphen_values = true)]
    range: Option<String>,
    /// smooth (normals interpolated from the vertices) or flat (each face its own).
    #[arg(long, default_value = "smooth")]
    shading: crate::render::Shading,
}

#[derive(clap::Args, Debug)]
pub(crate) struct SweepArgs {
    /// Sweep file (TOML: settings, mesh, [grid], [[points]], out, args).
    file: PathBuf,
    /// Sweep folder (default: the file's `out`, else its name without .toml).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Replace a sweep already in the folder.
    #[arg(long)]
    overwrite: bool,
    /// Also run the jobs now (run.sh: GNU parallel if installed, else one after another).
    #[arg(long)]
    run: bool,
}

#[derive(clap::Args, Debug)]
pub(crate) struct CollectArgs {
    /// Run folders, or folders of runs (a sweep folder).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Output file (default: print to stdout).
    #[arg(short, long)]
    out: Option<PathBuf>,
}

#[derive(clap::Args, Debug)]
pub(crate) struct ImportArgs {
    /// MorphoShell settings file (`name = value;` lines in its reader's order).
    settings: PathBuf,
    /// The mesh the settings go with (needed only to convert a moving slide's speed).
    mesh: Option<PathBuf>,
    /// Output file (default: print to stdout).
    #[arg(short, long)]
    out: Option<PathBuf>,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
enum Shape {
    /// Square of side --size.
    Square,
    /// Rectangle or strip --lx × --ly.
    Rectangle,
    /// Disk of radius --radius.
    Disk,
    /// Annulus --inner ≤ r ≤ --radius, optionally a sector of --sweep degrees.
    Annulus,
    /// Closed: a geodesic sphere of radius --radius.
    Sphere,
    /// Closed: a capsule (a tube with hemispherical ends) of radius --radius and length
    /// 3 × radius.
    Capsule,
    /// Closed: two overlapping lobes (radii --radius and 0.85 × radius) joined smoothly.
    Peanut,
    /// Closed: a teddy-like head (radius --radius) with two ears (0.38 × radius) on a body
    /// (1.25 × radius), joined smoothly.
    Teddy,
    /// Closed: a torus of major radius --radius and tube radius --tube.
    Torus,
    /// Open: a flat ovate leaf of length --size with a midrib and six pairs of secondary veins
    /// (tri_tags 1 blade, 2 midrib, 3 veins; with --thickness H the veins 2H, the midrib 3H
    /// thick); Delaunay.
    Leaf,
    /// Open: a flat film --lx × --ly with printed parallel strips at --strip-angle, --strip-width
    /// wide every --strip-pitch (tri_tags 1 bare, 2 under a strip); the strips' edges are mesh
    /// edges at any angle.
    Film,
    /// Open: a plastic spoon of total length --size, an elliptical bowl 0.28 × size long and
    /// 0.044 × size deep and a curved, tapering handle (tri_tags 1 bowl, 2 handle); Delaunay.
    Spoon,
    /// Open at both ends: a straw's paper wrapper of radius --radius and length --lx, flattened
    /// and pushed into an accordion of --folds half turns, --bunching times shorter; the vertex
    /// field original_positions holds the straight tube (for growth.law = "crease_relaxation").
    /// Needs --thickness: no fold is tighter than it.
    Wrapper,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
enum MeshFormat {
    Vtk,
    VtkAscii,
    Vtu,
}

#[derive(clap::Args, Debug)]
pub(crate) struct MeshArgs {
    /// Shape to mesh.
    shape: Shape,
    /// Output file.
    #[arg(long, short)]
    out: PathBuf,
    /// Target edge length (m).
    #[arg(long)]
    edge: Real,
    /// Side of a square, or a spoon's or leaf's length (m).
    #[arg(long, default_value_t = 1.0)]
    size: Real,
    /// Rectangle length along x (m).
    #[arg(long, default_value_t = 1.0)]
    lx: Real,
    /// Rectangle width along y (m).
    #[arg(long, default_value_t = 0.1)]
    ly: Real,
    /// Outer radius of a disk or annulus (m).
    #[arg(long, default_value_t = 1.0)]
    radius: Real,
    /// Inner radius of an annulus (m).
    #[arg(long, default_value_t = 0.5)]
    inner: Real,
    /// Tube radius of a torus (m).
    #[arg(long, default_value_t = 0.3)]
    tube: Real,
    /// Angular extent of an annulus in degrees (360 = full ring).
    #[arg(long, default_value_t = 360.0)]
    sweep: Real,
    /// Ratio of largest to smallest spacing (1 = uniform).
    #[arg(long, default_value_t = 1.0)]
    grading: Real,
    /// Random interior-vertex offset as a fraction of the local edge length (0 = none).
    #[arg(long, default_value_t = 0.0)]
    jitter: Real,
    /// Seed of the jitter.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Squares and rectangles: split cells along alternating diagonals instead of the same one.
    #[arg(long)]
    checkerboard: bool,
    /// Delaunay triangulation of well-spaced random points (seeded by --seed) instead of a
    /// structured grid: an irregular mesh. Squares, rectangles and annuli.
    #[arg(long, conflicts_with_all = ["checkerboard", "grading"])]
    delaunay: bool,
    /// Write abar_info/bbar_info for an analytic case (enlarged_square, spherical_cap,
    /// hyperboloid, rhombus, cylinder, cone, gcm_cone, bilayer_strip, conformal_cap).
    #[arg(long)]
    program: Option<String>,
    /// Film: angle of the strips to the x axis (degrees).
    #[arg(long, default_value_t = 0.0)]
    strip_angle: Real,
    /// Film: width of a strip (m; default --ly / 10).
    #[arg(long)]
    strip_width: Option<Real>,
    /// Film: distance between neighbouring strips' centre lines (m; default --ly / 5).
    #[arg(long)]
    strip_pitch: Option<Real>,
    /// Wrapper: the accordion's number of half turns.
    #[arg(long)]
    folds: Option<usize>,
    /// Wrapper: the tube's length over the accordion's.
    #[arg(long)]
    bunching: Option<Real>,
    /// Per-face thickness written as ref_thicknesses (m); a leaf's secondary veins get 2× and its
    /// midrib 3× it.
    #[arg(long)]
    thickness: Option<Real>,
    /// File format (default from the extension: .vtu → vtu, .vtk → binary legacy).
    #[arg(long, value_enum)]
    format: Option<MeshFormat>,
}

#[derive(clap::Args, Debug)]
pub(crate) struct ErrorArgs {
    /// Analytic case (enlarged_square, spherical_cap, hyperboloid, rhombus, cylinder, cone,
    /// gcm_cone, bilayer_strip, conformal_cap).
    case: String,
    /// A frame written by shellsim (its reference positions are positions − displacement).
    frame: PathBuf,
}

/// Parses arguments, runs, prints errors, returns the exit code.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    match dispatch(cli) {
        Ok(code) => ExitCode::from(code),
        Err(err) => {
            // Every error that reaches here is bad input or I/O: exit code 2.
            eprintln!("error: {err:#}");
            ExitCode::from(2)
        }
    }
}

fn dispatch(cli: Cli) -> Result<u8> {
    match cli.command {
        Some(Command::Mesh(a)) => mesh_cmd(a).map(|_| 0),
        Some(Command::Error(a)) => error_cmd(a).map(|_| 0),
        Some(Command::ImportMorphoshell(a)) => import_cmd(a).map(|_| 0),
        Some(Command::Sweep(a)) => sweep_cmd(a),
        Some(Command::Render(a)) => render_cmd(a).map(|_| 0),
        Some(Command::Plot(a)) => plot_cmd(a).map(|_| 0),
        Some(Command::Design(a)) => design_cmd(a),
        Some(Command::Collect(a)) => {
            let table = crate::sweep::collect(&a.dirs)?;
            match a.out {
                Some(p) => crate::mesh::io::write_atomic(&p, table.as_bytes())
                    .map_err(|e| anyhow!("{}: {e}", p.display()))?,
                None => print!("{table}"),
            }
            Ok(0)
        }
        None => {
            let (Some(settings), Some(mesh)) = (cli.settings.clone(), cli.mesh.clone()) else {
                bail!("usage: shellsim SETTINGS MESH [--out DIR]");
            };
            run_cmd(&cli, settings, mesh)
        }
    }
}

/// `shellsim design`: exit 0 when the design converged, 1 when it stopped without (the
/// objective reached and the reason on stderr), 2 for bad input.
fn design_cmd(a: DesignArgs) -> Result<u8> {
    let threads = thread_count(a.threads)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| anyhow!("cannot start {threads} threads: {e}"))?;
    let req = crate::design::run::Request {
        design: a.design,
        mesh: a.mesh,
        target: a.target,
        out: a.out,
        overwrite: a.overwrite,
        set: a.set,
        quiet: a.quiet,
    };
    let o = pool.install(|| crate::design::run::run(&req))?;
    let line = format!(
        "{} iterations, distance to the target {} of its size, objective {}",
        o.iterations,
        crate::math::human(o.distance),
        crate::math::human(o.objective)
    );
    if o.converged {
        if !req.quiet {
            eprintln!("shellsim design: converged ({}): {line}", o.reason);
        }
        Ok(0)
    } else {
        eprintln!("shellsim design: did not converge: {}; {line}", o.reason);
        Ok(1)
    }
}

/// The worker threads of `--threads`: at most the cores here (results do not depend on it).
fn thread_count(asked: Option<usize>) -> Result<usize> {
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    Ok(match asked {
        Some(0) => bail!("--threads must be at least 1"),
        Some(n) if n > cores => {
            eprintln!("warning: --threads {n} is more than the {cores} cores here; using {cores}");
            cores
        }
        Some(n) => n,
        None => cores,
    })
}

/// `--size WIDTHxHEIGHT`.
fn picture_size(size: &str) -> Result<(usize, usize)> {
    number_pair(size, &['x', '×'])
        .ok_or_else(|| anyhow!("--size '{size}': expected WIDTHxHEIGHT, e.g. 1024x768"))
}

/// Two numbers separated by one of `seps` (`1024x768`, `0,3`).
fn number_pair<T: std::str::FromStr>(s: &str, seps: &[char]) -> Option<(T, T)> {
    let (a, b) = s.split_once(seps)?;
    Some((a.trim().parse().ok()?, b.trim().parse().ok()?))
}

/// `shellsim plot`: reads log.csv, plots the columns, writes the PNG (nothing on an error).
fn plot_cmd(a: PlotArgs) -> Result<()> {
    let (w, h) = picture_size(&a.size)?;
    let log = if a.run.is_dir() {
        a.run.join("log.csv")
    } else {
        a.run.clone()
    };
    let name = log.display().to_string();
    let text = std::fs::read_to_string(&log).map_err(|e| anyhow!("{name}: {e}"))?;
    let canvas = plot_log(&text, &name, a.x.as_deref(), &a.y, (w, h), a.log_y)?;
    let out = a.out.unwrap_or_else(|| {
        log.parent()
            .map(|d| d.join("plot.png"))
            .unwrap_or_else(|| PathBuf::from("plot.png"))
    });
    canvas.save_png(&out)
}

/// The plot of the text of a log.csv (named `name` in messages): the columns `y`
/// (comma-separated) over `x` (default: time, else the dial), into a `size` picture.
pub(crate) fn plot_log(
    text: &str,
    name: &str,
    x: Option<&str>,
    y: &str,
    (w, h): (usize, usize),
    log_y: bool,
) -> Result<crate::render::Canvas> {
    let mut lines = text.lines();
    let head: Vec<&str> = lines
        .next()
        .ok_or_else(|| anyhow!("{name}: empty"))?
        .split(',')
        .map(str::trim)
        .collect();
    let col = |c: &str| {
        head.iter()
            .position(|h| *h == c)
            .ok_or_else(|| anyhow!("{name}: no column '{c}'; it has: {}", head.join(", ")))
    };
    let x = match x {
        Some(x) => x.trim().to_string(),
        None if head.contains(&"time") => "time".into(),
        None => "dial".into(),
    };
    let xi = col(&x)?;
    let ys: Vec<(String, usize)> = y
        .split(',')
        .map(str::trim)
        .filter(|c| !c.is_empty())
        .map(|c| col(c).map(|i| (c.to_string(), i)))
        .collect::<Result<_>>()?;
    if ys.is_empty() {
        bail!("--y names no column");
    }
    let rows: Vec<Vec<Real>> = lines
        .map(|l| {
            l.split(',')
                .map(|v| v.trim().parse::<Real>().unwrap_or(Real::NAN))
                .collect()
        })
        .collect();
    let get = |r: &Vec<Real>, i: usize| r.get(i).copied().unwrap_or(Real::NAN);
    let series: Vec<(String, Vec<[Real; 2]>)> = ys
        .iter()
        .map(|(n, i)| {
            (
                n.clone(),
                rows.iter().map(|r| [get(r, xi), get(r, *i)]).collect(),
            )
        })
        .collect();
    crate::render::plot(&x, &series, w, h, log_y).map_err(|e| anyhow!("{name}: {e}"))
}

/// `shellsim render`: reads the frame, draws it, writes the PNG (nothing on an error).
fn render_cmd(a: RenderArgs) -> Result<()> {
    let (w, h) = picture_size(&a.size)?;
    let mesh = read_mesh(&a.frame)?;
    let name = a.frame.display().to_string();
    let canvas = render_frame(
        &mesh,
        &name,
        a.field,
        &a.view,
        (w, h),
        a.range.as_deref(),
        a.shading,
    )?;
    let out = a.out.unwrap_or_else(|| a.frame.with_extension("png"));
    canvas.save_png(&out)
}

/// The picture of a frame read from `name`: checked as every reader checks a mesh, coloured by
/// `field` (default: mean_curvature if there is one) over `range` (`LOW,HIGH`; default: the
/// field's own).
pub(crate) fn render_frame(
    mesh: &crate::mesh::Mesh,
    name: &str,
    field: Option<String>,
    view: &str,
    (w, h): (usize, usize),
    range: Option<&str>,
    shading: crate::render::Shading,
) -> Result<crate::render::Canvas> {
    // The checks every reader of a mesh makes (face indices in range, finite coordinates,
    // field lengths), before anything is drawn.
    mesh.validate()?;
    let field = match field {
        Some(f) => Some(f),
        None => ["mean_curvature"]
            .into_iter()
            .map(String::from)
            .find(|f| mesh.face_fields.contains_key(f)),
    };
    let range = match range {
        None => None,
        Some(r) => Some(
            number_pair::<Real>(r, &[','])
                .filter(|(l, h)| l.is_finite() && h.is_finite() && h > l)
                .ok_or_else(|| anyhow!("--range '{r}': expected LOW,HIGH with LOW < HIGH"))?,
        ),
    };
    crate::render::render(mesh, field.as_deref(), view, w, h, range, shading)
        .map_err(|e| anyhow!("{name}: {e}"))
}

/// `shellsim sweep`: writes the sweep folder; with `--run`, runs its jobs (with this binary
/// unless `$SHELLSIM` names another), prints a tally and exits 1 unless every run converged.
fn sweep_cmd(a: SweepArgs) -> Result<u8> {
    let w = crate::sweep::sweep(&a.file, a.out.as_deref(), a.overwrite, &sweep_run_overrides)?;
    let (dir, n) = (w.dir.display(), w.runs);
    for k in &w.kept {
        eprintln!(
            "warning: {} kept: it holds files that shellsim did not write",
            k.display()
        );
    }
    if !a.run {
        eprintln!(
            "{n} runs in {dir}: run them with {dir}/run.sh (GNU parallel, else one by one) or \
             sbatch slurm.sh there ({} array tasks of up to {} runs); then shellsim collect {dir}",
            w.slurm_tasks, w.slurm_chunk
        );
        return Ok(0);
    }
    eprintln!("{n} runs in {dir}: running them with {dir}/run.sh");
    let mut cmd = std::process::Command::new("sh");
    cmd.arg(w.dir.join("run.sh"));
    if std::env::var_os("SHELLSIM").is_none() {
        if let Ok(exe) = std::env::current_exe() {
            cmd.env("SHELLSIM", exe);
        }
    }
    let status = cmd
        .status()
        .map_err(|e| anyhow!("cannot start {dir}/run.sh: {e}"))?;
    let failed: Vec<(usize, String)> = (0..n)
        .filter_map(|i| crate::sweep::failure(&w.dir, i, n).map(|f| (i, f)))
        .collect();
    eprintln!(
        "{n} runs: {} succeeded, {} failed{}",
        n - failed.len(),
        failed.len(),
        if failed.is_empty() { "" } else { ":" }
    );
    const SHOWN: usize = 20;
    for (i, why) in failed.iter().take(SHOWN) {
        let run = crate::sweep::run_name(*i, n);
        eprintln!("  {dir}/{run}: {why}");
    }
    if failed.len() > SHOWN {
        eprintln!("  and {} more", failed.len() - SHOWN);
    }
    if !status.success() && failed.is_empty() {
        eprintln!("{dir}/run.sh ended with {status}");
    }
    eprintln!("table: shellsim collect {dir}");
    Ok(if failed.is_empty() && status.success() {
        0
    } else {
        1
    })
}

/// The `--set` overrides of a sweep's extra run arguments (its `args`), parsed by this
/// binary's own parser after the arguments every job gives, as on a job's command line; an
/// argument the parser refuses is an error naming it.
pub(crate) fn sweep_run_overrides(args: &[String]) -> Result<Vec<String>> {
    let job = [
        "shellsim",
        "settings.toml",
        "mesh.vtk",
        "--out",
        "run",
        "--overwrite",
        "-q",
        "--threads",
        "1",
    ];
    let line = job
        .iter()
        .map(|s| s.to_string())
        .chain(args.iter().cloned());
    let cli = Cli::try_parse_from(line).map_err(|e| {
        use clap::error::ErrorKind;
        match e.kind() {
            ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
                anyhow!("--help and --version are not a run's arguments")
            }
            _ => {
                let text = e.to_string();
                let first = text.lines().next().unwrap_or_default();
                anyhow!("{}", first.trim_start_matches("error: "))
            }
        }
    })?;
    if cli.command.is_some() {
        bail!("a subcommand is not a run's argument");
    }
    Ok(cli.set)
}

/// `shellsim import-morphoshell`: parse, translate, check that shellsim accepts the result, and
/// write it (nothing is written on an error).
fn import_cmd(a: ImportArgs) -> Result<()> {
    let name = a.settings.display().to_string();
    let text =
        std::fs::read_to_string(&a.settings).map_err(|e| anyhow!("{name}: cannot read: {e}"))?;
    let toml = import_text(&text, &name, a.mesh.as_deref())?;
    match a.out {
        Some(p) => std::fs::write(&p, toml).map_err(|e| anyhow!("{}: {e}", p.display()))?,
        None => print!("{toml}"),
    }
    Ok(())
}

/// The shellsim settings file of the text of a MorphoShell settings file read from `name`,
/// checked to be one shellsim accepts. `mesh` is read only to convert a moving slide's speed.
pub(crate) fn import_text(
    text: &str,
    name: &str,
    mesh: Option<&std::path::Path>,
) -> Result<String> {
    let m = crate::morphoshell::parse(text, name)?;
    // A moving slide's speed is p × L / T_bend: from the mesh, with the translated material.
    let speed = match mesh {
        Some(mp) if m.get("slide_speed_prefactor") != 0.0 => {
            let draft = crate::morphoshell::to_toml(&m, name, Some(0.0))?;
            let settings = Settings::from_str_with(&draft, name, &[])?;
            let scene = Scene::build(read_mesh(mp)?, settings)?;
            let sc = crate::scales::Scales::of(&scene.body);
            let t_bend = 2.0 * std::f64::consts::PI / sc.omega_long;
            Some(m.get("slide_speed_prefactor") * sc.length / t_bend)
        }
        _ => None,
    };
    let toml = crate::morphoshell::to_toml(&m, name, speed)?;
    // The result must be a valid shellsim settings file.
    Settings::from_str_with(&toml, &format!("{name} (converted)"), &[])?;
    Ok(toml)
}

struct Bar(indicatif::ProgressBar);
impl Progress for Bar {
    fn update(&mut self, fraction: Real, message: &str) {
        self.0
            .set_position((fraction.clamp(0.0, 1.0) * 1000.0) as u64);
        self.0.set_message(message.to_string());
    }
}

/// `-v`: every step's message as a line on stderr.
struct Lines;
impl Progress for Lines {
    fn update(&mut self, _: Real, message: &str) {
        eprintln!("{message}");
    }
}

/// The frame a `--continue` run starts from: `--restart FRAME` (which must lie in `out`) or the
/// last frame that `out/series.pvd` lists.
fn continue_from(out: &std::path::Path, restart: Option<&PathBuf>) -> Result<PathBuf> {
    let series = out.join("series.pvd");
    let listed = crate::output::series_entries(&series).map_err(|e| anyhow!("--continue: {e}"))?;
    match restart {
        Some(p) => {
            let same = p
                .parent()
                .map(|d| {
                    if d.as_os_str().is_empty() {
                        std::path::Path::new(".")
                    } else {
                        d
                    }
                })
                .and_then(|d| d.canonicalize().ok())
                == out.canonicalize().ok();
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            if !same || !listed.iter().any(|(_, f)| f == name) {
                bail!(
                    "--continue --restart {}: the frame must be one that {} lists",
                    p.display(),
                    series.display()
                );
            }
            Ok(p.clone())
        }
        None => match listed.last() {
            Some((_, f)) => Ok(out.join(f)),
            None => bail!("--continue: {} lists no frame", series.display()),
        },
    }
}

fn run_cmd(cli: &Cli, settings_path: PathBuf, mesh_path: PathBuf) -> Result<u8> {
    let clock = std::time::Instant::now();
    let started = crate::provenance::now();
    let settings = Settings::load(&settings_path, &cli.set)?;
    let mesh = read_mesh(&mesh_path)?;
    let mut scene = Scene::build(mesh, settings)?;
    crate::integrate::check_scene(&scene)?;
    crate::output::check_fields(&scene, &settings_path.display().to_string())?;
    crate::integrate::check_continuation(&scene, &settings_path.display().to_string())?;
    crate::integrate::check_supports(&scene, &settings_path.display().to_string())?;
    crate::integrate::check_start(&scene, &settings_path.display().to_string())?;
    crate::solve::newton::VERBOSE.store(cli.verbose, std::sync::atomic::Ordering::Relaxed);
    let restart = if cli.continue_series {
        Some(continue_from(&cli.out, cli.restart.as_ref())?)
    } else {
        cli.restart.clone()
    };
    let initial = match &restart {
        Some(p) => {
            let (mut st, w) = crate::restart::read_restart(p, &scene)?;
            scene.body.warnings.extend(w);
            if scene.settings.dial.from == crate::settings::DialFrom::Start {
                // Dial from the starting state's forms, from dial 0 (MorphoShell's dialling
                // from an ansatz).
                scene.body.dial_from_state(&st.state.x, &st.state.dofs);
                st.time = 0.0;
                st.dial = Some(0.0);
                st.driver = None;
            }
            Some(st)
        }
        None => None,
    };
    for w in &scene.body.warnings {
        eprintln!("warning: {w}");
    }
    let threads = thread_count(cli.threads)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| anyhow!("cannot start {threads} threads: {e}"))?;
    crate::integrate::catch_signals()
        .map_err(|e| anyhow!("cannot install signal handlers: {e}"))?;
    let file = |p: &std::path::Path| {
        crate::provenance::FileRecord::of(p).map_err(|e| anyhow!("{}: {e}", p.display()))
    };
    let mut record = crate::provenance::RunRecord {
        shellsim_version: env!("CARGO_PKG_VERSION").into(),
        commit: crate::provenance::commit().into(),
        command_line: std::env::args_os()
            .map(|a| a.to_string_lossy().into_owned())
            .collect(),
        working_folder: std::env::current_dir()
            .map(|d| d.display().to_string())
            .unwrap_or_default(),
        settings: file(&settings_path)?,
        overrides: cli.set.clone(),
        resolved_settings: crate::output::RESOLVED_SETTINGS.into(),
        mesh: file(&mesh_path)?,
        vertices: scene.body.num_vertices(),
        faces: scene.body.num_faces(),
        restart: restart.as_deref().map(file).transpose()?,
        obstacle_meshes: scene
            .settings
            .obstacles
            .iter()
            .filter_map(|o| o.file.as_deref())
            .map(|f| file(std::path::Path::new(f)))
            .collect::<Result<_>>()?,
        threads,
        host: crate::provenance::host(),
        started,
        ended: None,
        status: "running".into(),
        reason: String::new(),
        exit_code: None,
        frames: 0,
        wall_seconds: 0.0,
    };
    let mut writer = match &restart {
        Some(frame) if cli.continue_series => Writer::continuing(&cli.out, &scene, frame)?,
        _ => Writer::new(&cli.out, &scene, cli.overwrite)?,
    };
    let frames_before = writer.num_frames();
    let mut history = if cli.continue_series {
        crate::provenance::read(&cli.out).map_err(|e| anyhow!("--continue: {e}"))?
    } else {
        None
    }
    .unwrap_or_default();
    history.runs.push(record.clone());
    writer.provenance(&history)?;
    let mode = format!("{:?}", scene.settings.solver.mode).to_lowercase();
    if !cli.quiet {
        eprintln!(
            "shellsim: {mode} run of {} on {} ({} vertices, {} faces, {threads} thread{}){} into {}",
            settings_path.display(),
            mesh_path.display(),
            scene.body.num_vertices(),
            scene.body.num_faces(),
            if threads == 1 { "" } else { "s" },
            match &restart {
                Some(p) => format!(" from {}", p.display()),
                None => String::new(),
            },
            cli.out.display()
        );
    }
    // Everything the user waited for before the run: the run's wall time includes it.
    scene.build_seconds = clock.elapsed().as_secs_f64();
    let ran = pool.install(|| {
        if cli.verbose {
            run(&scene, &mut writer, &mut Lines, threads, initial)
        } else if !cli.quiet && std::io::stderr().is_terminal() {
            let pb = indicatif::ProgressBar::new(1000);
            pb.set_style(
                indicatif::ProgressStyle::with_template(
                    "{bar:30} {percent:>3}% {elapsed} eta {eta} {msg}",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            let mut bar = Bar(pb);
            let r = run(&scene, &mut writer, &mut bar, threads, initial);
            bar.0.finish_and_clear();
            r
        } else {
            run(&scene, &mut writer, &mut Quiet, threads, initial)
        }
    });
    let wall = clock.elapsed().as_secs_f64();
    record.ended = Some(crate::provenance::now());
    record.wall_seconds = wall;
    record.frames = writer.num_frames() - frames_before;
    let summary = match ran {
        Ok(s) => s,
        Err(e) => {
            record.status = "failed".into();
            record.reason = format!("{e:#}");
            record.exit_code = Some(2);
            *history.runs.last_mut().expect("pushed above") = record;
            let _ = writer.provenance(&history);
            return Err(e.into());
        }
    };
    let where_ = format!(
        "{} frame{} in {}",
        record.frames,
        if record.frames == 1 { "" } else { "s" },
        cli.out.display()
    );
    let code = if let Some(sig) = crate::integrate::interrupted() {
        record.status = "interrupted".into();
        // The shell convention: 128 + the signal (130 for SIGINT, 143 for SIGTERM).
        (128 + sig) as u8
    } else if summary.converged {
        record.status = "converged".into();
        0
    } else {
        record.status = "not converged".into();
        1
    };
    record.reason = summary.reason.clone();
    record.exit_code = Some(code);
    *history.runs.last_mut().expect("pushed above") = record;
    writer.provenance(&history)?;
    let at = match summary.time {
        Some(t) => format!("t = {} s", crate::math::human(t)),
        None => format!("dial {}", crate::math::human(summary.dial)),
    };
    match code {
        0 if !cli.quiet => eprintln!(
            "shellsim: converged at {at} in {} s: {where_}",
            crate::math::human(wall)
        ),
        0 => {}
        1 => eprintln!(
            "shellsim: did not converge ({at}, {} s): {} ({where_}; see {})",
            crate::math::human(wall),
            summary.reason,
            cli.out.join("summary.json").display()
        ),
        _ => eprintln!(
            "shellsim: {} ({where_}; continue with --continue)",
            summary.reason
        ),
    }
    Ok(code)
}

/// Prints a line on stdout; a closed pipe (`shellsim error … | head`) is not an error.
fn print_out(text: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stdout(), "{text}");
}

fn mesh_cmd(a: MeshArgs) -> Result<()> {
    let mesh = build_mesh(&a, MAX_FACES)?;
    let ext = a.out.extension().and_then(|s| s.to_str()).unwrap_or("");
    let format = match (a.format, ext) {
        (Some(MeshFormat::Vtk), _) => Format::Vtk,
        (Some(MeshFormat::VtkAscii), _) => Format::VtkAscii,
        (Some(MeshFormat::Vtu), _) => Format::Vtu,
        (None, "vtu") => Format::Vtu,
        (None, "vtk") => Format::Vtk,
        (None, other) => bail!(
            "{}: unknown extension '.{other}' (use .vtk or .vtu)",
            a.out.display()
        ),
    };
    write_mesh(&a.out, &mesh, format, "shellsim generated mesh")?;
    print_out(&format!(
        "{}: {} vertices, {} faces",
        a.out.display(),
        mesh.positions.len(),
        mesh.faces.len()
    ));
    Ok(())
}

/// The mesh `shellsim mesh` writes for its arguments, checked (validation and topology), and
/// refused before anything is allocated when it would have more than `max_faces` faces.
pub(crate) fn build_mesh(a: &MeshArgs, max_faces: Real) -> Result<crate::mesh::Mesh> {
    let check_planned =
        |count: Real, what: &str, args: &str| check_planned_within(count, max_faces, what, args);
    let pos = |name: &str, v: Real| -> Result<()> {
        if !(v.is_finite() && v > 0.0) {
            bail!(
                "--{name} must be positive, got {v_h}",
                v_h = crate::math::human(v)
            );
        }
        Ok(())
    };
    pos("edge", a.edge)?;
    pos("grading", a.grading)?;
    if !(0.0..0.5).contains(&a.jitter) {
        bail!(
            "--jitter must lie in [0, 0.5), got {}",
            crate::math::human(a.jitter)
        );
    }
    let sp = Spacing {
        grading: a.grading,
        jitter: a.jitter,
        seed: a.seed,
        checkerboard: a.checkerboard,
    };
    if a.delaunay && a.jitter > 0.0 {
        bail!("--jitter does not apply to --delaunay meshes (they are irregular already)");
    }
    let closed = matches!(
        a.shape,
        Shape::Sphere | Shape::Capsule | Shape::Peanut | Shape::Teddy | Shape::Torus
    );
    if a.delaunay
        && (closed
            || matches!(
                a.shape,
                Shape::Disk | Shape::Spoon | Shape::Leaf | Shape::Film
            ))
    {
        bail!("--delaunay supports square, rectangle and annulus");
    }
    if closed && (a.jitter > 0.0 || a.grading != 1.0 || a.checkerboard || a.program.is_some()) {
        bail!(
            "--jitter, --grading, --checkerboard and --program apply to flat sheets, not to \
             closed surfaces"
        );
    }
    if matches!(a.shape, Shape::Spoon | Shape::Leaf)
        && (a.jitter > 0.0 || a.grading != 1.0 || a.checkerboard)
    {
        bail!("--jitter, --grading and --checkerboard apply to grid meshes; spoons and leaves are Delaunay meshes");
    }
    if matches!(a.shape, Shape::Film) && (a.jitter > 0.0 || a.grading != 1.0 || a.checkerboard) {
        bail!("--jitter, --grading and --checkerboard do not apply to a film: its rows follow the strips");
    }
    let film_flags = a.strip_angle != 0.0 || a.strip_width.is_some() || a.strip_pitch.is_some();
    if film_flags && !matches!(a.shape, Shape::Film) {
        bail!("--strip-angle, --strip-width and --strip-pitch describe a film's strips");
    }
    if (a.folds.is_some() || a.bunching.is_some()) && !matches!(a.shape, Shape::Wrapper) {
        bail!("--folds and --bunching describe a wrapper's accordion");
    }
    let mut mesh = match a.shape {
        Shape::Square | Shape::Rectangle => {
            let (lx, ly) = match a.shape {
                Shape::Square => {
                    pos("size", a.size)?;
                    (a.size, a.size)
                }
                _ => {
                    pos("lx", a.lx)?;
                    pos("ly", a.ly)?;
                    (a.lx, a.ly)
                }
            };
            let sides = match a.shape {
                Shape::Square => "--edge and --size",
                _ => "--edge, --lx and --ly",
            };
            if a.delaunay {
                let (faces, grid) =
                    crate::mesh::delaunay::delaunay_planned(lx * ly, lx, ly, a.edge);
                check_planned(faces, "faces", sides).map_err(|e| anyhow!(e))?;
                check_planned(grid, "cells of the point grid", sides).map_err(|e| anyhow!(e))?;
                delaunay_rectangle(-0.5 * lx, -0.5 * ly, lx, ly, a.edge, sp)
            } else {
                check_planned(rectangle_faces(lx, ly, a.edge), "faces", sides)
                    .map_err(|e| anyhow!(e))?;
                rectangle(-0.5 * lx, -0.5 * ly, lx, ly, a.edge, sp)
            }
        }
        Shape::Disk => {
            pos("radius", a.radius)?;
            let faces = annulus_faces(0.0, a.radius, 2.0 * std::f64::consts::PI, a.edge);
            check_planned(faces, "faces", "--edge and --radius").map_err(|e| anyhow!(e))?;
            annulus(0.0, a.radius, 2.0 * std::f64::consts::PI, a.edge, sp)
        }
        Shape::Annulus => {
            pos("radius", a.radius)?;
            pos("inner", a.inner)?;
            pos("sweep", a.sweep)?;
            if a.inner >= a.radius {
                bail!(
                    "--inner ({}) must be smaller than --radius ({})",
                    a.inner,
                    a.radius
                );
            }
            let sweep = a.sweep.min(360.0).to_radians();
            let args = "--edge, --radius and --inner";
            if a.delaunay {
                let area = 0.5 * sweep * (a.radius * a.radius - a.inner * a.inner);
                let box_side = 2.0 * a.radius;
                let (faces, grid) =
                    crate::mesh::delaunay::delaunay_planned(area, box_side, box_side, a.edge);
                check_planned(faces, "faces", args).map_err(|e| anyhow!(e))?;
                check_planned(grid, "cells of the point grid", args).map_err(|e| anyhow!(e))?;
            } else {
                let faces = annulus_faces(a.inner, a.radius, sweep, a.edge);
                check_planned(faces, "faces", args).map_err(|e| anyhow!(e))?;
            }
            if a.delaunay {
                delaunay_annulus(a.inner, a.radius, sweep, a.edge, sp)
            } else {
                annulus(a.inner, a.radius, sweep, a.edge, sp)
            }
        }
        Shape::Sphere | Shape::Capsule | Shape::Peanut | Shape::Teddy => {
            pos("radius", a.radius)?;
            if a.edge > a.radius {
                bail!(
                    "--edge ({}) must not exceed --radius ({}) for a closed surface",
                    a.edge,
                    a.radius
                );
            }
            let name = format!("{:?}", a.shape).to_lowercase();
            crate::mesh::surfaces::closed_shape_within(&name, a.radius, a.edge, max_faces)
                .map_err(|e| anyhow!("cannot mesh the {name}: {e}"))?
        }
        Shape::Film => {
            pos("lx", a.lx)?;
            pos("ly", a.ly)?;
            let width = a.strip_width.unwrap_or(0.1 * a.ly);
            let pitch = a.strip_pitch.unwrap_or(0.2 * a.ly);
            pos("strip-width", width)?;
            pos("strip-pitch", pitch)?;
            if !a.strip_angle.is_finite() {
                bail!("--strip-angle must be finite (degrees)");
            }
            if width >= pitch {
                bail!(
                    "--strip-width ({}) must be smaller than --strip-pitch ({}): strips that \
                     touch cover the whole film",
                    crate::math::human(width),
                    crate::math::human(pitch)
                );
            }
            if width < 0.5 * a.edge || pitch - width < 0.5 * a.edge {
                bail!(
                    "--edge ({}) must be at most twice the strip width ({}) and the gap between \
                     strips ({}) to resolve the pattern",
                    crate::math::human(a.edge),
                    crate::math::human(width),
                    crate::math::human(pitch - width)
                );
            }
            let faces = crate::mesh::film::planned_faces(a.lx, a.ly, a.edge);
            check_planned(faces, "faces", "--edge, --lx and --ly").map_err(|e| anyhow!(e))?;
            let strips = crate::mesh::film::Strips {
                angle: a.strip_angle.to_radians(),
                width,
                pitch,
            };
            crate::mesh::film::film(a.lx, a.ly, a.edge, strips).map_err(|e| anyhow!(e))?
        }
        Shape::Spoon => {
            pos("size", a.size)?;
            let faces = crate::mesh::spoon::planned_faces(a.size, a.edge);
            check_planned(faces, "faces", "--edge and --size").map_err(|e| anyhow!(e))?;
            if a.edge > 0.02 * a.size {
                bail!(
                    "--edge ({}) must be at most 0.02 × --size ({}) to resolve the spoon's \
                     handle",
                    a.edge,
                    a.size
                );
            }
            crate::mesh::spoon::spoon(a.size, a.edge, sp)
        }
        Shape::Leaf => {
            pos("size", a.size)?;
            let faces = crate::mesh::leaf::planned_faces(a.size, a.edge);
            check_planned(faces, "faces", "--edge and --size").map_err(|e| anyhow!(e))?;
            if a.edge > 0.03 * a.size {
                bail!(
                    "--edge ({}) must be at most 0.03 × --size ({}) to keep the leaf's veins \
                     connected",
                    a.edge,
                    a.size
                );
            }
            if let Some(t) = a.thickness {
                pos("thickness", t)?;
            }
            crate::mesh::leaf::leaf(a.size, a.edge, a.thickness, sp)
        }
        Shape::Wrapper => {
            pos("radius", a.radius)?;
            pos("lx", a.lx)?;
            let h = a.thickness.ok_or_else(|| {
                anyhow!("a wrapper needs --thickness: none of its folds may be tighter than it")
            })?;
            pos("thickness", h)?;
            let w = crate::mesh::wrapper::Wrapper {
                radius: a.radius,
                length: a.lx,
                folds: a.folds.unwrap_or(8),
                bunching: a.bunching.unwrap_or(8.0),
            };
            w.check(h).map_err(|e| anyhow!(e))?;
            check_planned(
                w.planned_faces(a.edge),
                "faces",
                "--edge, --lx, --radius and --folds",
            )
            .map_err(|e| anyhow!(e))?;
            crate::mesh::wrapper::wrapper(w, a.edge, Some(h))
        }
        Shape::Torus => {
            pos("radius", a.radius)?;
            pos("tube", a.tube)?;
            if a.tube >= a.radius {
                bail!(
                    "--tube ({}) must be smaller than --radius ({})",
                    a.tube,
                    a.radius
                );
            }
            if a.edge > a.tube {
                bail!("--edge ({}) must not exceed --tube ({})", a.edge, a.tube);
            }
            let faces = crate::mesh::surfaces::torus_faces(a.radius, a.tube, a.edge);
            check_planned(faces, "faces", "--edge, --radius and --tube").map_err(|e| anyhow!(e))?;
            crate::mesh::surfaces::torus(a.radius, a.tube, a.edge)
        }
    };
    if let Some(p) = &a.program {
        let case = Case::from_name(p).ok_or_else(|| {
            anyhow!(
                "unknown --program '{p}' (one of: {})",
                Case::ALL.map(|c| c.name()).join(", ")
            )
        })?;
        case.program(&mut mesh);
    }
    if let (Some(t), false) = (a.thickness, matches!(a.shape, Shape::Leaf | Shape::Wrapper)) {
        pos("thickness", t)?;
        mesh.face_fields.insert(
            "ref_thicknesses".into(),
            crate::mesh::Field::scalar(vec![t; mesh.faces.len()]),
        );
    }
    mesh.validate()?;
    Topology::build(&mesh)?;
    Ok(mesh)
}

fn error_cmd(a: ErrorArgs) -> Result<()> {
    let case = Case::from_name(&a.case).ok_or_else(|| {
        anyhow!(
            "unknown case '{}' (one of: {})",
            a.case,
            Case::ALL.map(|c| c.name()).join(", ")
        )
    })?;
    let frame = read_mesh(&a.frame)?;
    // A frame with a non-finite position or field has no error to measure.
    frame.validate()?;
    let disp = frame.vertex_field("displacement", 3)?.ok_or_else(|| {
        anyhow!(
            "{}: no 'displacement' vertex field; is it a shellsim frame?",
            a.frame.display()
        )
    })?;
    let reference: Vec<Vec3> = frame
        .positions
        .iter()
        .enumerate()
        .map(|(i, p)| p - Vec3::from_column_slice(disp.get(i)))
        .collect();
    let err = shape_error(case, &reference, &frame.positions);
    let mut ref_mesh = frame.clone();
    ref_mesh.positions = reference;
    let topo = Topology::build(&ref_mesh)?;
    let (eh, ek) = curvature_error(case, &ref_mesh, &topo, &frame.positions);
    let hd = crate::cases::hausdorff(case, &ref_mesh, &topo, &frame.positions);
    let out = serde_json::json!({
        "case": case.name(),
        "vertices": frame.positions.len(),
        "faces": frame.faces.len(),
        "hausdorff": hd,
        "hausdorff_rel": hd / err.size,
        "max_error": err.max,
        "rms_error": err.rms,
        "size": err.size,
        "max_error_rel": err.max_rel,
        "rms_error_rel": err.rms_rel,
        "worst_vertex": err.worst_vertex,
        "worst_reference_position": err.worst_reference,
        "mean_curvature_rms_error": eh,
        "gauss_curvature_rms_error": ek,
    });
    print_out(&serde_json::to_string_pretty(&out)?);
    Ok(())
}
