//! Closed meshes from shape files and generators: the OFF, OBJ, PLY (ASCII, both binary byte
//! orders) and STL (ASCII, binary) fixtures of `tests/data/shapes/` (written by
//! `scripts/make_shape_fixtures.py`) read into the closed solids they describe, malformed files
//! are refused naming the line, byte offset, face or vertex, and the generated closed surfaces
//! are closed, outward and enclose the volumes of their shapes.

use shellsim::math::Real;
use shellsim::mesh::closed::check_closed_outward;
use shellsim::mesh::io::{mesh_from_bytes, read_mesh};
use shellsim::mesh::surfaces::{closed_shape, geodesic_sphere, torus};
use shellsim::mesh::{Mesh, Topology};
use std::f64::consts::PI;
use std::path::Path;

fn data(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/shapes")
        .join(name)
}

/// Validated, closed, outward: the enclosed volume.
fn closed_volume(m: &Mesh) -> Real {
    m.validate().unwrap();
    let topo = Topology::build(m).unwrap();
    check_closed_outward(m, &topo).unwrap()
}

#[test]
fn shape_files_read_into_their_solids() {
    for name in [
        "cube.off",
        "cube.obj",
        "cube_ascii.ply",
        "cube_le.ply",
        "cube_be.ply",
    ] {
        let m = read_mesh(&data(name)).unwrap();
        assert_eq!(m.positions.len(), 8, "{name}");
        assert_eq!(m.faces.len(), 12, "{name}: 6 quads, 2 triangles each");
        let v = closed_volume(&m);
        assert!((v - 1.0).abs() < 1e-12, "{name}: volume {v}");
        if name.ends_with(".ply") {
            let t = m.face_field("ref_thicknesses", 1).unwrap().unwrap();
            assert!(t.data.iter().all(|&h| h == 0.001), "{name}: {t:?}");
        }
    }
    // The icosahedron of edge 2: V = 5(3 + √5)/12 · 8.
    let exact = 5.0 * (3.0 + 5f64.sqrt()) / 12.0 * 8.0;
    for name in ["ico_ascii.stl", "ico_binary.stl"] {
        let m = read_mesh(&data(name)).unwrap();
        assert_eq!(m.positions.len(), 12, "{name}: corners merged");
        assert_eq!(m.faces.len(), 20, "{name}");
        let v = closed_volume(&m);
        assert!((v - exact).abs() < 1e-6 * exact, "{name}: {v} vs {exact}");
    }
}

/// Each malformed input is an error naming where, never a panic.
#[test]
fn malformed_shape_files_are_refused_with_their_position() {
    let cases: &[(&str, &str, &str)] = &[
        ("off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n", "ends after 3 of the 4 vertices"),
        ("off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "line 6: vertex index 7 is out of range"),
        ("off", "OFF\n3 1 0\n0 0 0\n1 0 x\n0 1 0\n3 0 1 2\n", "line 4: vertex 1's z must be a number"),
        ("off", "OFF\n4 1 0\n0 0 0\n1 0 0\n2 0 0\n3 0 0\n4 0 1 2 3\n", "line 7, face 0: a polygon of 4 vertices that cannot be triangulated"),
        ("off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "line 6, face 0: a face needs at least 3 vertices"),
        ("off", "PLY\n", "expected the header 'OFF'"),
        ("obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "line 4: vertex index 3 is out of range"),
        ("obj", "v 0 0 0\nv 1 0 0\nf 1 2 0\n", "line 3: vertex index 0"),
        ("obj", "v 0 0 0\n", "no faces"),
        ("ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n", "line 12"),
        ("ply", "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n\u{0}\u{0}", "byte offset"),
        ("ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n", "no scalar property 'y'"),
        ("stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nvertex 1 1 0\nendloop\nendfacet\nendsolid\n", "line 8: facet 0 has 4 vertices"),
        ("stl", "garbage", "neither a binary STL"),
        ("dxf", "", "unknown mesh extension '.dxf'"),
    ];
    for (ext, text, want) in cases {
        let err = mesh_from_bytes(text.as_bytes(), ext)
            .err()
            .unwrap_or_else(|| panic!("{ext}: {text:?} accepted"));
        assert!(err.contains(want), "{ext}: '{err}' should say '{want}'");
    }
    // A NaN coordinate reads, then validation names the vertex, as for VTK.
    let m = mesh_from_bytes(b"OFF\n3 1 0\n0 0 0\nNaN 0 0\n0 1 0\n3 0 1 2\n", "off").unwrap();
    let err = m.validate().unwrap_err().to_string();
    assert!(
        err.contains("vertex 1 has a non-finite coordinate"),
        "{err}"
    );
    // Two faces with opposite orientation: the topology names them, as for VTK.
    let m = mesh_from_bytes(
        b"OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n3 1 2 3\n",
        "off",
    )
    .unwrap();
    let err = Topology::build(&m).unwrap_err().to_string();
    assert!(err.contains("orient"), "{err}");
}

/// The generated closed surfaces are closed, consistently oriented, outward, and enclose the
/// volume of the smooth shape to second order in the edge (sphere, capsule, torus: closed
/// forms; the inscribed polyhedra hold slightly less).
#[test]
fn generated_closed_surfaces_enclose_their_shapes() {
    let r = 0.05;
    let cases: [(&str, Real); 3] = [
        ("sphere", 4.0 / 3.0 * PI * r * r * r),
        // A tube of length r between two hemispheres of radius r.
        ("capsule", PI * r * r * r + 4.0 / 3.0 * PI * r * r * r),
        ("torus", 2.0 * PI * PI * r * (0.4 * r).powi(2)),
    ];
    for (name, exact) in cases {
        let mut errs = Vec::new();
        for edge in [r / 8.0, r / 16.0] {
            let m = if name == "torus" {
                torus(r, 0.4 * r, 0.4 * edge)
            } else {
                closed_shape(name, r, edge).unwrap()
            };
            let v = closed_volume(&m);
            errs.push((exact - v) / exact);
        }
        println!("{name}: relative volume errors {errs:?}");
        assert!(
            errs.iter().all(|&e| e > 0.0 && e < 0.03),
            "{name}: {errs:?}"
        );
        assert!(
            errs[1] < 0.35 * errs[0],
            "{name}: second order expected, {errs:?}"
        );
    }
    for name in ["peanut", "teddy"] {
        let m = closed_shape(name, r, r / 10.0).unwrap();
        let v = closed_volume(&m);
        assert!(
            v > 4.0 / 3.0 * PI * r * r * r,
            "{name}: larger than its head ({v})"
        );
    }
    let g = geodesic_sphere(1.0, 5);
    assert_eq!(g.positions.len(), 10 * 25 + 2);
    assert_eq!(g.faces.len(), 20 * 25);
    closed_volume(&g);
}
