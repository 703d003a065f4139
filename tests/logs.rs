//! What a run reports about itself: `-v` prints every Newton iteration, and `summary.json`'s
//! `timing` splits the wall time, from the start of the command, into parts that are
//! non-negative and add up to it.

mod common;

#[test]
fn verbose_newton_lines_and_the_timing_breakdown() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let (c, _, e) = common::run_status(
        &[
            "mesh", "square", "--size", "1", "--edge", "0.2", "-o", "sq.vtk",
        ],
        p,
    );
    assert_eq!(c, 0, "{e}");
    std::fs::write(
        p.join("s.toml"),
        "[material]\nyoung = 1.0e6\nthickness = 0.01\n[rest]\ntarget = \"uniform\"\n\
         bbar = [2.0, 0.0, 0.0]\n",
    )
    .unwrap();
    let (c, _, e) = common::run_status(&["s.toml", "sq.vtk", "--out", "o", "-v"], p);
    assert_eq!(c, 0, "{e}");
    let lines: Vec<&str> = e.lines().filter(|l| l.starts_with("newton")).collect();
    assert!(lines.len() >= 2, "{e}");
    assert!(lines.iter().any(|l| l.contains("converged")), "{e}");
    assert!(lines.iter().all(|l| l.contains("residual")), "{e}");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p.join("o/summary.json")).unwrap()).unwrap();
    let t = &s["timing"];
    let parts = [
        "build",
        "analysis",
        "assembly",
        "factorisation",
        "solve",
        "line_search",
        "diffusion",
        "output",
        "other",
    ];
    let mut sum = 0.0;
    for k in parts {
        let v = t[k]
            .as_f64()
            .unwrap_or_else(|| panic!("no timing.{k}: {t}"));
        assert!(v >= 0.0, "timing.{k} = {v}");
        sum += v;
    }
    let wall = s["wall_seconds"].as_f64().unwrap();
    assert!(t["assembly"].as_f64().unwrap() > 0.0, "{t}");
    // The wall time counts from the start of the command: reading and building the scene too.
    assert!(t["build"].as_f64().unwrap() > 0.0, "{t}");
    assert!(t["output"].as_f64().unwrap() > 0.0, "{t}");
    // A static run factorises: its ordering and symbolic factorisation are timed.
    assert!(t["analysis"].as_f64().unwrap() > 0.0, "{t}");
    let ls = &s["linear_system"];
    assert!(ls["unknowns"].as_u64().unwrap() > 0, "{ls}");
    assert_eq!(ls["ordering"], "amd", "{ls}");
    assert!(
        ls["factorisations"].as_u64().unwrap() >= s["newton_iterations"].as_u64().unwrap(),
        "{ls}"
    );
    // The parts are measured inside the wall time; `other` is the remainder.
    assert!(
        (sum - wall).abs() <= 1e-6 * wall.max(1.0),
        "{sum} vs {wall}: {t}"
    );
}
