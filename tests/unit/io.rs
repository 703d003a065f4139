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

/// A corrupt appended block is an error naming the array and the byte, never a panic: a
/// truncated file, a header claiming more than the data, a bad marker, a missing offset.
#[test]
fn corrupt_appended_data_names_the_byte() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk");
    let d = tempfile::tempdir().unwrap();
    let read = |name: &str, bytes: &[u8]| {
        let p = d.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        read_mesh(&p).map(|_| ()).unwrap_err().to_string()
    };
    for src in [
        "appended.vtu",
        "appended_none.vtu",
        "appended_lz4.vtu",
        "appended_lzma.vtu",
    ] {
        let good = std::fs::read(dir.join(src)).unwrap();
        let start = good
            .windows(14)
            .position(|w| w == b"<AppendedData ")
            .unwrap();
        let marker = start + good[start..].iter().position(|&c| c == b'_').unwrap();
        let end = good.len() - 40;
        // Cut the data short (keep the closing tags).
        let mut cut = good[..marker + 60].to_vec();
        cut.extend_from_slice(b"\n</AppendedData>\n</VTKFile>\n");
        let e = read(src, &cut);
        assert!(
            e.contains(src) && e.contains("appended data at offset"),
            "{src}: {e}"
        );
        assert!(e.contains("file byte"), "{src}: {e}");
        // Flip bytes inside the data: a wrong size or a broken stream, never a panic.
        for k in (marker + 1..end).step_by(37) {
            let mut bad = good.clone();
            bad[k] ^= 0xA5;
            let _ = read_mesh(&{
                let p = d.path().join(src);
                std::fs::write(&p, &bad).unwrap();
                p
            });
        }
        // No '_' marker.
        let mut bad = good.clone();
        bad[marker] = b'#';
        let e = read(src, &bad);
        assert!(e.contains("must start with '_'"), "{src}: {e}");
        // No closing tag.
        let e = read(src, &good[..marker + 100]);
        assert!(e.contains("no </AppendedData>"), "{src}: {e}");
    }
    let e = read(
        "no_block.vtu",
        b"<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid><Piece NumberOfPoints=\"3\" \
          NumberOfCells=\"1\"><Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" \
          format=\"appended\" offset=\"0\"/></Points></Piece></UnstructuredGrid></VTKFile>",
    );
    assert!(e.contains("no <AppendedData>"), "{e}");
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

/// Files written by VTK's own writers (VTK 9.7, `scripts/make_vtk_fixtures.py`) in every
/// variant shellsim reads: each gives the script's mesh exactly (all arrays are Float64 or
/// Int32, so nothing is rounded).
#[test]
fn files_written_by_vtk_itself_are_read_in_every_variant() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk");
    let files = [
        "ascii.vtu",
        "base64.vtu",
        "zlib.vtu",
        "zlib_uint64.vtu",
        "base64_bigendian.vtu",
        "zlib.vtp",
        "ascii.vtp",
        "ascii_51.vtk",
        "binary_51.vtk",
        "ascii_42.vtk",
        "binary_42.vtk",
        "poly_ascii_51.vtk",
        "poly_binary_42.vtk",
        "appended.vtu",
        "appended_none.vtu",
        "appended_lz4.vtu",
        "appended_lzma.vtu",
        "appended_bigendian.vtu",
        "appended_bigendian_none.vtu",
        "appended_base64.vtu",
        "appended_base64_none.vtu",
        "appended.vtp",
        "appended_bigendian_lz4.vtp",
    ];
    for name in files {
        let m = read_mesh(&dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(m.positions.len(), 9, "{name}");
        for (v, p) in m.positions.iter().enumerate() {
            let (x, y) = ((v % 3) as f64 / 2.0, (v / 3) as f64 / 2.0);
            assert_eq!([p.x, p.y, p.z], [x, y, 0.1 * x * y], "{name} vertex {v}");
        }
        assert_eq!(m.faces.len(), 8, "{name}");
        assert_eq!(m.faces[0], [0, 1, 4], "{name}");
        assert_eq!(m.faces[7], [4, 8, 7], "{name}");
        let abar = &m.face_fields["abar_info"];
        assert_eq!(abar.components, 3, "{name}");
        for f in 0..8 {
            let g = f as f64;
            assert_eq!(
                abar.get(f),
                &[1.0 + g, 0.125 * g, 2.0 + g],
                "{name} face {f}"
            );
        }
        let vel = &m.vertex_fields["velocity"];
        assert_eq!(vel.get(5), &[5.0, -5.0, 2.5], "{name}");
        let tags = &m.vertex_fields["node_tags"];
        assert_eq!(
            tags.data,
            (0..9).map(|v| (7 * v - 20) as f64).collect::<Vec<_>>(),
            "{name}"
        );
        m.validate().unwrap();
    }
}

/// Bad input gets an error naming the place, never a panic: a first vertex index out of range,
/// a header count of 2³²−1 (no allocation from it), inconsistent compression headers, arrays of
/// the wrong length, coordinates beyond range.
#[test]
fn malformed_files_are_named_errors_not_panics() {
    use shellsim::mesh::io::mesh_from_bytes;
    let check = |bytes: &[u8], ext: &str, needles: &[&str]| {
        let e = match mesh_from_bytes(bytes, ext) {
            Err(e) => e,
            Ok(m) => match m.validate() {
                Err(e) => e.to_string(),
                Ok(_) => panic!("accepted: {}", String::from_utf8_lossy(bytes)),
            },
        };
        for n in needles {
            assert!(e.contains(n), "'{n}' not in: {e}");
        }
        assert!(!e.contains("{ ") && !e.contains("please report"), "{e}");
    };
    let head = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 3 double\n0 0 0 1 0 0 0 1 0\n";
    check(
        format!("{head}POLYGONS 1 4\n3 7 1 2\n").as_bytes(),
        "vtk",
        &["face 0", "vertex 7"],
    );
    check(
        format!("{head}POLYGONS 4294967295 4\n3 0 1 2\n").as_bytes(),
        "vtk",
        &["line 7", "POLYGONS", "4294967295"],
    );
    check(
        format!("{head}POLYGONS 1 4\n3 0 1 x\n").as_bytes(),
        "vtk",
        &["line 8", "POLYGONS", "'x'"],
    );
    check(
        format!("{head}POLYGONS 1 4\n3 0 1 2\nCELL_DATA 1\nFIELD f 1\nbbar_info 3 1 double\n1 0\n")
            .as_bytes(),
        "vtk",
        &["bbar_info", "2 of 3", "truncated"],
    );
    check(
        format!("{head}POLYGONS 1 4\n3 0 1 2\nCELL_DATA 2\nSCALARS t double\nLOOKUP_TABLE default\n1 2\n").as_bytes(),
        "vtk",
        &["CELL_DATA", "2 entries", "1 cells"],
    );
    check(
        b"# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 3 double\n0 0 0 1e160 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 2\n",
        "vtk",
        &["vertex 1", "1e160", "rescale"],
    );
    // Binary legacy: a signed index of −7 is named as −7, not as 4294967289.
    let mut bin =
        b"# vtk DataFile Version 3.0\nt\nBINARY\nDATASET POLYDATA\nPOINTS 3 double\n".to_vec();
    for x in [0.0f64, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend_from_slice(&x.to_be_bytes());
    }
    bin.extend_from_slice(b"\nPOLYGONS 1 4\n");
    for i in [3i32, -7, 1, 2] {
        bin.extend_from_slice(&i.to_be_bytes());
    }
    bin.push(b'\n');
    check(&bin, "vtk", &["POLYGONS", "is -7,", "not an index"]);
    // XML: a short array, and a compression header announcing more than there is.
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk");
    let ascii = std::fs::read_to_string(dir.join("ascii.vtu")).unwrap();
    let short = ascii.replacen("1 0 2 2 0.125 3", "1 0 2 2 0.125", 1);
    check(
        short.as_bytes(),
        "vtu",
        &["CellData array 'abar_info'", "23 values, expected 24"],
    );
    let zlib = std::fs::read(dir.join("zlib.vtu")).unwrap();
    // The first base64 header of the file, its block count changed from 1 to 255.
    let text = String::from_utf8(zlib).unwrap();
    let at = text.find("format=\"binary\"").unwrap();
    let start = at + text[at..].find('>').unwrap() + 1;
    let first = text[start..].trim_start();
    let off = text.len() - first.len();
    let mut bad = text.clone().into_bytes();
    // "AQAAAA" encodes 01 00 00 00 00 (1 block); "/wAAAA" encodes ff 00 00 00 00.
    assert_eq!(&text[off..off + 6], "AQAAAA", "fixture layout changed");
    bad[off..off + 6].copy_from_slice(b"/wAAAA");
    check(&bad, "vtu", &["byte", "255 blocks"]);
}

/// `summary.json` never holds `null`: a summary with a non-finite number (a drag rate that
/// overflowed) is refused, marked unconverged (exit 1) with an internal error naming the
/// value, and written without it; a finite summary is left alone.
#[test]
fn a_summary_with_a_non_finite_number_is_refused() {
    use shellsim::output::{summary_json, ExplicitReport, Summary};
    let mut s = Summary {
        converged: true,
        explicit: Some(ExplicitReport {
            damping_rate_dial: f64::INFINITY,
            stable_prefactor: Some(f64::NAN),
            ..Default::default()
        }),
        ..Default::default()
    };
    assert!(s.refuse_non_finite());
    assert!(!s.converged);
    assert!(s.reason.starts_with("internal error"), "{}", s.reason);
    assert!(
        s.reason.contains("explicit.damping_rate_dial"),
        "{}",
        s.reason
    );
    assert!(
        s.reason.contains("explicit.stable_prefactor"),
        "{}",
        s.reason
    );
    let (text, left_out) = summary_json(&s);
    assert_eq!(left_out.len(), 2, "{left_out:?}");
    assert!(!text.contains("null"), "{text}");
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["converged"], false);
    assert!(v["explicit"].get("damping_rate_dial").is_none());
    let mut fine = Summary {
        converged: true,
        explicit: Some(ExplicitReport::default()),
        ..Default::default()
    };
    assert!(!fine.refuse_non_finite());
    assert!(fine.converged);
    let (text, left_out) = summary_json(&fine);
    assert!(left_out.is_empty() && !text.contains("null"), "{text}");
}

/// A file cut short never loads as another mesh: every prefix of each text and binary fixture
/// (STL ASCII and binary, OFF, OBJ, PLY ASCII and both binaries, legacy VTK ASCII and binary)
/// is refused, or reads as the whole file does (a cut that loses nothing, such as the name
/// after `endsolid`). A number cut at the end of the file (`1.61803399` read as `1.6`), a missing
/// `endloop`/`endfacet`/`endsolid`, or a count larger than the data is an error naming the line
/// or byte offset. OBJ has no counts: a cut at a line's end loses its last lines unseen, so only
/// cuts inside a line are checked there.
#[test]
fn truncated_files_are_refused() {
    use shellsim::mesh::io::mesh_from_bytes;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    for name in [
        "shapes/ico_ascii.stl",
        "shapes/ico_binary.stl",
        "shapes/cube.off",
        "shapes/cube.obj",
        "shapes/cube_ascii.ply",
        "shapes/cube_le.ply",
        "shapes/cube_be.ply",
        "vtk/ascii_42.vtk",
        "vtk/poly_ascii_51.vtk",
        "vtk/binary_42.vtk",
    ] {
        let bytes = std::fs::read(root.join(name)).unwrap();
        let ext = name.rsplit('.').next().unwrap();
        let whole = mesh_from_bytes(&bytes, ext).unwrap();
        for cut in 0..bytes.len() {
            let part = &bytes[..cut];
            if ext == "obj" && part.last() == Some(&b'\n') {
                continue;
            }
            if let Ok(m) = mesh_from_bytes(part, ext) {
                assert!(
                    m.positions == whole.positions && m.faces == whole.faces,
                    "{name} cut at byte {cut} of {} reads as another mesh",
                    bytes.len()
                );
            }
        }
    }
    // The messages name the place.
    let ico = std::fs::read_to_string(root.join("shapes/ico_ascii.stl")).unwrap();
    // Cut inside facet 0's last coordinate, 1.61803399 read as 1.6 were the file accepted.
    let at = ico.find("vertex 0 1 1.61803399").unwrap() + "vertex 0 1 1.6".len();
    let cases: Vec<(String, &str, &str)> = vec![
        (
            ico[..at].to_string(),
            "stl",
            "line 6: the file ends inside facet 0, where 'endloop' was expected: it is cut short",
        ),
        (
            ico.replacen("    endloop\n", "", 1),
            "stl",
            "line 7: expected 'endloop' (facet 0), found 'endfacet'",
        ),
        (
            ico.replacen("  endfacet\n", "", 1),
            "stl",
            "line 8: expected 'endfacet' (facet 0), found 'facet normal 0 0 0'",
        ),
        (
            ico.replace("endsolid ico\n", ""),
            "stl",
            "the file ends inside the solid, where 'facet normal' or 'endsolid' was expected",
        ),
        (
            "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2".into(),
            "off",
            "line 6: the file ends inside the number '2', without a final newline",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 4 3 ".into(),
            "obj",
            "line 5: the file ends inside the line 'f 1 2 4 3'",
        ),
        (
            "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 3 double\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 2\nPOINT_DATA 3\nSCALARS s double 1\nLOOKUP_TABLE default\n1 2 0.8".into(),
            "vtk",
            "line 12: the file ends inside the number '0.8'",
        ),
    ];
    for (text, ext, want) in cases {
        let err = mesh_from_bytes(text.as_bytes(), ext).unwrap_err();
        assert!(err.contains(want), "'{err}' should say '{want}'");
    }
    // A binary STL whose count is larger than its data.
    let mut bin = std::fs::read(root.join("shapes/ico_binary.stl")).unwrap();
    bin.truncate(bin.len() - 7);
    let err = mesh_from_bytes(&bin, "stl").unwrap_err();
    assert!(
        err.contains("announcing 20 triangles") && err.contains("1084 bytes, this file 1077"),
        "{err}"
    );
}
