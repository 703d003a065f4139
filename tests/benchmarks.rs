//! Seed 000 Table 1 through the real pipeline: generate a programmed unit-square mesh, run the
//! binary to static equilibrium, measure the frame with `shellsim error`. Coarse (edge 0.1),
//! fine (0.05) and non-uniform (graded 2.5× and jittered 20%, edge 0.05) meshes; thickness 0.05.
//!
//! Bounds are the errors measured when the test was written plus about 20%; the flat cases are
//! exact up to the solver tolerance. The curved cases converge at first order on uniform meshes:
//! their error sits at the corners and comes from seed 000's boundary rule (the mid-edge normal
//! of a boundary edge is the face normal), the mid-edge average's known limit.

use std::path::Path;
use std::process::Command;

fn shellsim(args: &[&str], dir: &Path) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_shellsim"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "shellsim {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

struct Row {
    hausdorff: f64,
    max_err: f64,
    curv_h: f64,
    newton: u64,
}

fn run_case(case: &str, mesh_args: &[&str], dir: &Path, tag: &str) -> Row {
    let mesh = format!("{case}_{tag}.vtk");
    let mut args = vec!["mesh", "square", "-o", &mesh, "--program", case];
    args.extend_from_slice(mesh_args);
    shellsim(&args, dir);
    let out = format!("out_{case}_{tag}");
    std::fs::write(
        dir.join("s.toml"),
        "[material]\nthickness = 0.05\n[rest]\ntarget = \"mesh\"\n",
    )
    .unwrap();
    shellsim(&["s.toml", &mesh, "--out", &out, "-q"], dir);
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join(&out).join("summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(summary["converged"], true, "{case} {tag}");
    let frame = format!("{out}/{}", summary["final_frame"].as_str().unwrap());
    let e: serde_json::Value =
        serde_json::from_str(&shellsim(&["error", case, &frame], dir)).unwrap();
    Row {
        hausdorff: e["hausdorff_rel"].as_f64().unwrap(),
        max_err: e["max_error_rel"].as_f64().unwrap(),
        curv_h: e["mean_curvature_rms_error"].as_f64().unwrap(),
        newton: summary["newton_iterations"].as_u64().unwrap(),
    }
}

#[test]
fn table1_analytic_benchmarks() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let meshes: [(&str, Vec<&str>); 3] = [
        ("coarse", vec!["--edge", "0.1"]),
        ("fine", vec!["--edge", "0.05"]),
        (
            "nonuniform",
            vec![
                "--edge",
                "0.05",
                "--grading",
                "2.5",
                "--jitter",
                "0.2",
                "--seed",
                "5",
            ],
        ),
    ];
    println!(
        "{:<16} {:<11} {:>12} {:>12} {:>10} {:>7}",
        "case", "mesh", "hausdorff", "max err", "H rms", "newton"
    );
    for case in [
        "enlarged_square",
        "spherical_cap",
        "hyperboloid",
        "rhombus",
        "cylinder",
    ] {
        let rows: Vec<Row> = meshes
            .iter()
            .map(|(tag, a)| run_case(case, a, dir, tag))
            .collect();
        for ((tag, _), r) in meshes.iter().zip(&rows) {
            println!(
                "{case:<16} {tag:<11} {:>12.3e} {:>12.3e} {:>10.3e} {:>7}",
                r.hausdorff, r.max_err, r.curv_h, r.newton
            );
        }
        let (c, f, n) = (&rows[0], &rows[1], &rows[2]);
        match case {
            "enlarged_square" | "rhombus" => {
                for r in &rows {
                    assert!(
                        r.max_err < 1e-6,
                        "{case}: flat target not reached: {}",
                        r.max_err
                    );
                    assert!(r.hausdorff < 1e-6, "{case}: Hausdorff {}", r.hausdorff);
                }
            }
            _ => {
                assert!(
                    f.max_err < 0.7 * c.max_err,
                    "{case}: no convergence {} -> {}",
                    c.max_err,
                    f.max_err
                );
                assert!(f.curv_h < c.curv_h, "{case}: curvature error does not fall");
                let bound = match case {
                    "spherical_cap" => 0.03,
                    "cylinder" => 0.0105,
                    _ => 0.0022,
                };
                assert!(
                    f.hausdorff < bound,
                    "{case}: fine Hausdorff {} ≥ {bound}",
                    f.hausdorff
                );
                assert!(
                    n.hausdorff < 0.1,
                    "{case}: non-uniform Hausdorff {}",
                    n.hausdorff
                );
            }
        }
    }
}

/// A metric that asks for a cone: the flat start is a saddle. With the default symmetry
/// breaking the sheet buckles; with it switched off, Newton first finds the flat saddle, the
/// stability check rejects it, and a perturbation escapes to the cone. Never a flat "equilibrium".
#[test]
fn cone_metric_buckles_out_of_the_flat_saddle() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    shellsim(
        &[
            "mesh",
            "annulus",
            "--inner",
            "0.3",
            "--radius",
            "1",
            "--edge",
            "0.1",
            "--program",
            "cone",
            "-o",
            "cone.vtk",
        ],
        dir,
    );
    std::fs::write(
        dir.join("s.toml"),
        "[material]\nthickness = 0.02\n[rest]\ntarget = \"mesh\"\n",
    )
    .unwrap();
    for (sb, escapes_min) in [("1e-3", 0), ("0", 1)] {
        let out = format!("o{sb}");
        shellsim(
            &[
                "s.toml",
                "cone.vtk",
                "--out",
                &out,
                "-q",
                "--set",
                &format!("solver.symmetry_breaking={sb}"),
            ],
            dir,
        );
        let s: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.join(&out).join("summary.json")).unwrap(),
        )
        .unwrap();
        assert_eq!(s["converged"], true);
        assert!(
            s["saddle_escapes"].as_u64().unwrap() >= escapes_min,
            "sb {sb}: {s}"
        );
        let frame = format!("{out}/{}", s["final_frame"].as_str().unwrap());
        let e: serde_json::Value =
            serde_json::from_str(&shellsim(&["error", "cone", &frame], dir)).unwrap();
        let h = e["hausdorff_rel"].as_f64().unwrap();
        println!(
            "cone, symmetry_breaking {sb}: Hausdorff {h:.3e}, saddle escapes {}",
            s["saddle_escapes"]
        );
        // Measured 0.165% at edge 0.1; a flat sheet would be about 30% off.
        assert!(h < 0.002, "cone not reached: {h}");
    }
}
