//! shellsim's frames read by VTK itself: every output variant (`.vtu` appended raw or inline
//! base64, zlib / LZ4 / uncompressed, single or double derived fields; legacy binary and ASCII)
//! of a short dynamic run is read by VTK's Python readers (`scripts/vtk_check.py`), which must
//! find the point and cell counts, the field names and component counts shellsim's own reader
//! finds, the positions bit for bit and sampled field values (exactly, or to Float32's 6e-8
//! for single-precision fields in legacy ASCII, where the two readers round the text apart), and
//! each `series.pvd` (parsed by VTK's XML parser) listing the frames in time order.
//!
//! Needs VTK's Python package: `scripts/test.sh` makes the project's `.venv/` with it and names its
//! interpreter in `SHELLSIM_PYTHON` (without that variable, `python3` is used).

use serde_json::{json, Value};
use std::path::Path;
use std::process::Command;

mod common;

fn samples(data: &[f64], comps: usize) -> Vec<Value> {
    let n = data.len() / comps;
    [0, n / 2, n - 1]
        .iter()
        .map(|&i| {
            let mut s = vec![json!(i)];
            s.extend(data[i * comps..(i + 1) * comps].iter().map(|v| json!(v)));
            Value::Array(s)
        })
        .collect()
}

fn fields(f: &std::collections::BTreeMap<String, shellsim::mesh::Field>, tol: f64) -> Value {
    Value::Object(
        f.iter()
            .map(|(name, fl)| {
                (
                    name.clone(),
                    json!({"components": fl.components, "samples": samples(&fl.data, fl.components), "tol": tol}),
                )
            })
            .collect(),
    )
}

#[test]
fn vtk_reads_every_kind_of_frame_shellsim_writes() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let variants: &[(&str, &[&str])] = &[
        ("appended_zlib", &[]),
        ("appended_lz4", &["output.compression=lz4"]),
        ("appended_none", &["output.compression=none"]),
        ("base64_zlib", &["output.encoding=base64"]),
        (
            "base64_lz4",
            &["output.encoding=base64", "output.compression=lz4"],
        ),
        (
            "base64_none",
            &["output.encoding=base64", "output.compression=none"],
        ),
        (
            "appended_double_all",
            &["output.precision=double", "output.fields=[\"all\"]"],
        ),
        ("legacy_binary", &["output.format=vtk"]),
        ("legacy_ascii", &["output.format=vtk_ascii"]),
        (
            "legacy_ascii_double",
            &["output.format=vtk_ascii", "output.precision=double"],
        ),
    ];
    let mut frames = Vec::new();
    let mut series = Vec::new();
    for (name, sets) in variants {
        let mut args = vec![
            root.join("settings/dynamic_cylinder.toml")
                .display()
                .to_string(),
            root.join("meshes/strip.vtk").display().to_string(),
            "--out".into(),
            name.to_string(),
            "-q".into(),
            "--set".into(),
            "time.end=0.1".into(),
        ];
        for s in *sets {
            args.extend(["--set".to_string(), s.to_string()]);
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        common::shellsim(&args, p);
        let out = p.join(name);
        let ext = if name.starts_with("legacy") {
            "vtk"
        } else {
            "vtu"
        };
        let single_ascii = *name == "legacy_ascii";
        let mut files = Vec::new();
        for k in 0.. {
            let f = out.join(format!("frame_{k:05}.{ext}"));
            if !f.exists() {
                break;
            }
            files.push(format!("frame_{k:05}.{ext}"));
            let m = shellsim::mesh::io::read_mesh(&f).unwrap();
            let nv = m.positions.len();
            let positions: Vec<Value> = [0, nv / 2, nv - 1]
                .iter()
                .map(|&i| {
                    let x = m.positions[i];
                    json!([i, x.x, x.y, x.z])
                })
                .collect();
            let tol = if single_ascii { 6e-8 } else { 0.0 };
            frames.push(json!({
                "file": f.display().to_string(),
                "points": nv,
                "cells": m.faces.len(),
                "positions": positions,
                "point_fields": fields(&m.vertex_fields, tol),
                "cell_fields": fields(&m.face_fields, tol),
            }));
        }
        assert!(files.len() >= 3, "{name}: {} frames", files.len());
        // The times the run logged, in frame order.
        let log = std::fs::read_to_string(out.join("log.csv")).unwrap();
        let mut lines = log.lines();
        let head: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = head.iter().position(|h| *h == "time").unwrap();
        let times: Vec<f64> = lines
            .map(|l| l.split(',').nth(col).unwrap().parse().unwrap())
            .collect();
        series.push(json!({
            "pvd": out.join("series.pvd").display().to_string(),
            "files": files,
            "times": times,
        }));
    }
    let spec = p.join("expect.json");
    std::fs::write(
        &spec,
        json!({"frames": frames, "series": series}).to_string(),
    )
    .unwrap();
    let python = std::env::var("SHELLSIM_PYTHON").unwrap_or_else(|_| "python3".into());
    let r = Command::new(&python)
        .arg(root.join("scripts/vtk_check.py"))
        .arg(&spec)
        .output()
        .unwrap_or_else(|e| panic!("{python}: {e}"));
    assert!(
        r.status.success(),
        "VTK disagrees with shellsim (or is missing from {python}: run the tests with \
         scripts/test.sh):\n{}{}",
        String::from_utf8_lossy(&r.stdout),
        String::from_utf8_lossy(&r.stderr)
    );
    eprintln!("{}", String::from_utf8_lossy(&r.stdout));
}
