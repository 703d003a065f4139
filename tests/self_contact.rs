//! Self-contact from the command line: a strip rolled by an end moment past a full turn winds
//! onto itself with its layers a thickness apart. Every frame is checked by an independent
//! script (`scripts/contact_check.py`: VTK's readers and a brute-force numpy search over every
//! pair of faces, none of shellsim's code) for crossing faces and for the smallest distance
//! between mid-surfaces; the same run without self-contact is the control that the check can
//! fail; the frames are bitwise identical on 1 and 3 threads.
//!
//! Needs VTK's Python package: `scripts/test.sh` makes the project's `.venv/` with it and names
//! its interpreter in `SHELLSIM_PYTHON` (without that variable, `python3` is used).

use std::path::Path;
use std::process::Command;

mod common;
use common::{log_rows, shellsim};

/// The strip: L = 1, b = 0.04, h = 0.01, E = 1e7, ν = 0, clamped at x = −0.5, end moment
/// 1.5 × the full-circle moment 2πD/L (per unit width) at x = 0.5, 20 load steps.
const ROLL: &str = "[material]\nyoung = 1e7\npoisson = 0.0\nthickness = 0.01\n\
    [solver]\nsymmetry_breaking = 0.0\ncontinuation_step = 0.05\n\
    [output]\ncontinuation_frames = true\n\
    [[constraints.clamp]]\ninside = { min = [-1, -1, -1], max = [-0.499, 1, 1] }\n\
    [[loads.moment]]\nmoment = 7.853981633974483\n\
    inside = { min = [0.499, -1, -1], max = [1, 1, 1] }\n\
    [self_contact]\nenabled = true\n";

/// Runs `scripts/contact_check.py` on the run `out` (reference mesh `mesh`) with exclusion
/// radius `r`; returns its JSON summary.
fn check(dir: &Path, mesh: &str, out: &str, r: f64) -> serde_json::Value {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let python = std::env::var("SHELLSIM_PYTHON").unwrap_or_else(|_| "python3".into());
    let json = dir.join(format!("{out}.check.json"));
    let res = Command::new(&python)
        .arg(root.join("scripts/contact_check.py"))
        .arg(dir.join(mesh))
        .arg(dir.join(out))
        .args(["--exclusion", &r.to_string(), "--json"])
        .arg(&json)
        .output()
        .unwrap_or_else(|e| panic!("{python}: {e}"));
    let text = std::fs::read_to_string(&json).unwrap_or_else(|_| {
        panic!(
            "contact_check.py failed (is VTK in {python}? run the tests with scripts/test.sh):\n{}{}",
            String::from_utf8_lossy(&res.stdout),
            String::from_utf8_lossy(&res.stderr)
        )
    });
    serde_json::from_str(&text).unwrap()
}

#[test]
fn a_strip_rolled_past_a_full_turn_winds_onto_itself_a_thickness_apart() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    shellsim(
        &[
            "mesh",
            "rectangle",
            "--lx",
            "1",
            "--ly",
            "0.04",
            "--edge",
            "0.02",
            "-o",
            "strip.vtk",
        ],
        dir,
    );
    std::fs::write(dir.join("roll.toml"), ROLL).unwrap();
    shellsim(&["roll.toml", "strip.vtk", "--out", "on", "-q"], dir);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("on/summary.json")).unwrap())
            .unwrap();
    assert_eq!(s["converged"], true, "{s}");
    assert!(s["energy"]["self_contact"].as_f64().unwrap() > 0.0, "{s}");
    // The tip turned through one and a half turns.
    let last = log_rows(&dir.join("on")).pop().unwrap();
    let turn = last["moment_rotation"] / (2.0 * std::f64::consts::PI);
    assert!((turn - 1.5).abs() < 0.02, "{turn} turns");
    // Exclusion radius 2 (ξ + δ) with ξ = h = 0.01, δ = h/100.
    let h = 0.01;
    let r = 2.0 * (h + h / 100.0);
    let c = check(dir, "strip.vtk", "on", r);
    println!("with self-contact: {c}");
    assert_eq!(c["crossing_pairs"], 0, "{c}");
    // The layers touch: the smallest mid-surface distance is the offset less the penalty's
    // penetration (about 4e-5 here; the closed form's σ/k + δ/2 at the contact pressure).
    let dmin = c["min_distance"].as_f64().unwrap();
    assert!(dmin > 0.99 * h && dmin < 1.001 * h, "{dmin}");
    // The control: without self-contact the strip passes through itself, and the check sees it.
    shellsim(
        &[
            "roll.toml",
            "strip.vtk",
            "--out",
            "off",
            "-q",
            "--set",
            "self_contact.enabled=false",
        ],
        dir,
    );
    let c = check(dir, "strip.vtk", "off", r);
    assert!(c["crossing_pairs"].as_u64().unwrap() > 0, "{c}");
    // Bitwise identical on 1 and 3 threads (the default is 2).
    for t in ["1", "3"] {
        let out = format!("t{t}");
        shellsim(
            &[
                "roll.toml",
                "strip.vtk",
                "--out",
                &out,
                "-q",
                "--threads",
                t,
            ],
            dir,
        );
        for k in [10, 20] {
            let f = format!("frame_{k:05}.vtu");
            let a = std::fs::read(dir.join("on").join(&f)).unwrap();
            let b = std::fs::read(dir.join(&out).join(&f)).unwrap();
            assert!(a == b, "{f} differs on {t} threads");
        }
    }
}
