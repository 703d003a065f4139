//! Mesh I/O round trips and formats.

use shellsim::mesh::generate::{annulus, rectangle, Spacing};
use shellsim::mesh::io::{read_mesh, write_mesh, Format};
use shellsim::mesh::{Field, Topology};

#[test]
fn round_trip_in_every_format_keeps_positions_faces_and_fields() {
    let d = tempfile::tempdir().unwrap();
    let mut m = rectangle(
        0.0,
        0.0,
        1.0,
        0.5,
        0.1,
        Spacing {
            jitter: 0.2,
            seed: 9,
            ..Default::default()
        },
    );
    let nf = m.faces.len();
    let nv = m.positions.len();
    m.face_fields.insert(
        "abar_info".into(),
        Field {
            components: 3,
            data: (0..3 * nf).map(|i| i as f64 * 0.5).collect(),
        },
    );
    m.vertex_fields.insert(
        "node_tags".into(),
        Field::scalar((0..nv).map(|i| (i % 3) as f64).collect()),
    );
    for (fmt, name) in [
        (Format::Vtu, "a.vtu"),
        (Format::Vtk, "b.vtk"),
        (Format::VtkAscii, "c.vtk"),
    ] {
        let p = d.path().join(name);
        write_mesh(&p, &m, fmt, "test").unwrap();
        let r = read_mesh(&p).unwrap();
        assert_eq!(r.faces, m.faces, "{name}");
        for (a, b) in r.positions.iter().zip(&m.positions) {
            assert!((a - b).norm() < 1e-12 * (1.0 + b.norm()), "{name}");
        }
        assert_eq!(
            r.face_fields["abar_info"], m.face_fields["abar_info"],
            "{name}"
        );
        assert_eq!(
            r.vertex_fields["node_tags"], m.vertex_fields["node_tags"],
            "{name}"
        );
    }
}

#[test]
fn legacy_5_1_offsets_and_polydata_scalars_are_read() {
    let d = tempfile::tempdir().unwrap();
    let text = "# vtk DataFile Version 5.1\nt\nASCII\nDATASET POLYDATA\nPOINTS 4 double\n0 0 0 1 0 0 1 1 0 0 1 0\nPOLYGONS 3 6\nOFFSETS vtktypeint64\n0 3 6\nCONNECTIVITY vtktypeint64\n0 1 2 0 2 3\nCELL_DATA 2\nSCALARS ref_thicknesses double 1\nLOOKUP_TABLE default\n0.1 0.2\nPOINT_DATA 4\nVECTORS v double\n0 0 1 0 0 1 0 0 1 0 0 1\n";
    let p = d.path().join("m.vtk");
    std::fs::write(&p, text).unwrap();
    let m = read_mesh(&p).unwrap();
    assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(m.face_fields["ref_thicknesses"].data, vec![0.1, 0.2]);
    assert_eq!(m.vertex_fields["v"].components, 3);
}

#[test]
fn generated_meshes_are_valid_and_oriented() {
    for m in [
        rectangle(
            0.0,
            0.0,
            1.0,
            1.0,
            0.1,
            Spacing {
                grading: 3.0,
                jitter: 0.25,
                seed: 2,
                ..Default::default()
            },
        ),
        rectangle(
            0.0,
            0.0,
            1.0,
            1.0,
            0.1,
            Spacing {
                checkerboard: true,
                ..Default::default()
            },
        ),
        annulus(
            0.0,
            1.0,
            2.0 * std::f64::consts::PI,
            0.1,
            Spacing {
                jitter: 0.25,
                seed: 1,
                ..Default::default()
            },
        ),
        annulus(0.5, 1.0, 5.0, 0.05, Spacing::default()),
    ] {
        m.validate().unwrap();
        Topology::build(&m).unwrap();
        for f in 0..m.faces.len() {
            let [a, b, c] = m.face_positions(f);
            assert!(
                (b - a).cross(&(c - a)).z > 0.0,
                "face {f} not counter-clockwise"
            );
        }
    }
}

#[test]
fn raw_appended_xml_gets_a_clear_message() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("paraview.vtu");
    std::fs::write(
        &p,
        "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid><Piece NumberOfPoints=\"3\" NumberOfCells=\"1\">\
         </Piece></UnstructuredGrid><AppendedData encoding=\"raw\">_</AppendedData></VTKFile>",
    )
    .unwrap();
    let e = read_mesh(&p).unwrap_err().to_string();
    assert!(e.contains("paraview.vtu") && e.contains("appended"), "{e}");
}

#[test]
fn delaunay_rectangle_is_valid_delaunay_and_well_shaped() {
    use shellsim::mesh::delaunay::delaunay_rectangle;
    let make = || {
        delaunay_rectangle(
            -0.5,
            -0.5,
            1.0,
            1.0,
            0.08,
            Spacing {
                seed: 7,
                ..Default::default()
            },
        )
    };
    let m = make();
    m.validate().unwrap();
    Topology::build(&m).unwrap();
    let area: f64 = (0..m.faces.len())
        .map(|f| {
            let [a, b, c] = m.face_positions(f);
            0.5 * (b - a).cross(&(c - a)).z
        })
        .sum();
    assert!(
        (area - 1.0).abs() < 1e-12,
        "triangles do not tile the square: area {area}"
    );
    let mut min_angle = f64::INFINITY;
    for f in 0..m.faces.len() {
        let [a, b, c] = m.face_positions(f);
        assert!(
            (b - a).cross(&(c - a)).z > 0.0,
            "face {f} not counter-clockwise"
        );
        for (p, q, r) in [(a, b, c), (b, c, a), (c, a, b)] {
            let (u, v) = (q - p, r - p);
            min_angle = min_angle.min((u.dot(&v) / (u.norm() * v.norm())).acos().to_degrees());
        }
        // Empty circumcircle: no vertex strictly inside (brute force).
        let (ax, ay, bx, by, cx, cy) = (a.x, a.y, b.x, b.y, c.x, c.y);
        let d = 2.0 * (ax * (by - cy) + bx * (cy - ay) + cx * (ay - by));
        let ux = ((ax * ax + ay * ay) * (by - cy)
            + (bx * bx + by * by) * (cy - ay)
            + (cx * cx + cy * cy) * (ay - by))
            / d;
        let uy = ((ax * ax + ay * ay) * (cx - bx)
            + (bx * bx + by * by) * (ax - cx)
            + (cx * cx + cy * cy) * (bx - ax))
            / d;
        let r2 = (ax - ux).powi(2) + (ay - uy).powi(2);
        for p in &m.positions {
            assert!(
                (p.x - ux).powi(2) + (p.y - uy).powi(2) >= r2 * (1.0 - 1e-9),
                "face {f} not Delaunay"
            );
        }
    }
    // Dart throwing keeps points ≥ 0.7 h apart: no slivers.
    assert!(min_angle > 15.0, "min angle {min_angle}");
    assert_eq!(make().faces, m.faces, "not deterministic");
}
