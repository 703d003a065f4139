//! `shellsim render` end to end: the PNG has the asked size, the surface where the projection
//! puts it (a flat square seen from the top fills a square), the colour bar's ends in the
//! viridis end colours, and bad input (a missing field, a bad size or view) exits 2 naming what
//! exists and writes no picture.

use std::path::Path;

mod common;

fn run(args: &[&str], dir: &Path) -> (i32, String) {
    let (c, _, e) = common::run_status(args, dir);
    (c, e)
}

/// Width, height and RGB pixels of a PNG.
fn decode(path: &Path) -> (usize, usize, Vec<[u8; 3]>) {
    let d = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut r = d.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let px = buf[..info.buffer_size()]
        .chunks(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    (info.width as usize, info.height as usize, px)
}

#[test]
fn render_draws_the_frame_where_the_view_puts_it() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let (c, e) = run(
        &[
            "mesh", "square", "--size", "1", "--edge", "0.1", "-o", "sq.vtk",
        ],
        p,
    );
    assert_eq!(c, 0, "{e}");
    std::fs::write(
        p.join("s.toml"),
        "[material]\nyoung = 1.0e6\nthickness = 0.01\n[rest]\ntarget = \"uniform\"\n\
         abar = [1.1, 0.0, 1.1]\n",
    )
    .unwrap();
    let (c, e) = run(&["s.toml", "sq.vtk", "--out", "o", "-q"], p);
    assert_eq!(c, 0, "{e}");
    // Grown isotropically and left flat: from the top, a square.
    let (c, e) = run(
        &[
            "render",
            "o/frame_00001.vtu",
            "-o",
            "top.png",
            "--view",
            "top",
            "--field",
            "max_stretch",
            "--size",
            "400x300",
        ],
        p,
    );
    assert_eq!(c, 0, "{e}");
    let (w, h, px) = decode(&p.join("top.png"));
    assert_eq!((w, h), (400, 300));
    // The surface's pixels in the picture area (left 80%): not white.
    let (mut x0, mut x1, mut y0, mut y1) = (w, 0, h, 0);
    for y in 0..h {
        for x in 0..w * 4 / 5 {
            if px[y * w + x] != [255, 255, 255] {
                x0 = x0.min(x);
                x1 = x1.max(x);
                y0 = y0.min(y);
                y1 = y1.max(y);
            }
        }
    }
    let (sw, sh) = ((x1 - x0 + 1) as f64, (y1 - y0 + 1) as f64);
    assert!((sw - sh).abs() <= 2.0, "the square is drawn {sw} × {sh} px");
    // It fills the height but for the 6% margins, centred in the picture area.
    assert!((sh - 0.88 * h as f64).abs() <= 2.0, "height {sh}");
    let cx = 0.5 * (x0 + x1) as f64;
    assert!((cx - 0.4 * w as f64).abs() <= 2.0, "centre {cx}");
    // The colour bar runs from viridis' top colour to its bottom one.
    let bar_x = w * 4 / 5 + w / 40 + 2;
    let top = px[(h / 8 + 1) * w + bar_x];
    let bottom = px[(h - h / 8 - 2) * w + bar_x];
    let near = |a: [u8; 3], b: [u8; 3]| {
        a.iter()
            .zip(b)
            .all(|(x, y)| (*x as i32 - y as i32).abs() <= 4)
    };
    assert!(near(top, [253, 231, 37]), "bar top {top:?}");
    assert!(near(bottom, [68, 1, 84]), "bar bottom {bottom:?}");

    // A negative azimuth is a value, not a flag, written either way.
    for view in [&["--view", "-60,15"][..], &["--view=-60,15"][..]] {
        let mut args = vec![
            "render",
            "o/frame_00001.vtu",
            "-o",
            "neg.png",
            "--size",
            "200x150",
        ];
        args.extend_from_slice(view);
        let (c, e) = run(&args, p);
        assert_eq!(c, 0, "{view:?}: {e}");
        assert_eq!(decode(&p.join("neg.png")).0, 200);
    }

    // Bad input: exit 2, what exists named, no picture.
    let cases: [(&[&str], &str); 5] = [
        (&["--field", "curvature_of_nothing"], "mean_curvature"),
        (&["--range", "1,0"], "LOW < HIGH"),
        (&["--size", "10x10"], "64"),
        (&["--size", "big"], "WIDTHxHEIGHT"),
        (&["--view", "sideways"], "iso"),
    ];
    for (extra, named) in cases {
        let mut args = vec!["render", "o/frame_00001.vtu", "-o", "bad.png"];
        args.extend_from_slice(extra);
        let (c, e) = run(&args, p);
        assert_eq!(c, 2, "{extra:?}: {e}");
        assert!(e.contains(named), "{extra:?}: {e}");
        assert!(!p.join("bad.png").exists(), "{extra:?} wrote a picture");
    }
}

/// `shellsim plot`: each series is drawn in its palette colour inside the axes, and a missing
/// column is an error listing the columns there are, with no picture written.
#[test]
fn plot_draws_log_columns_and_names_missing_ones() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    std::fs::write(
        p.join("log.csv"),
        "frame,time,energy_total,energy_bending\n0,0.0,1.0,0.0\n1,0.5,0.5,0.25\n2,1.0,0.0,0.5\n",
    )
    .unwrap();
    let (c, e) = run(
        &[
            "plot",
            ".",
            "--y",
            "energy_total,energy_bending",
            "--size",
            "400x300",
        ],
        p,
    );
    assert_eq!(c, 0, "{e}");
    let (w, h, px) = decode(&p.join("plot.png"));
    assert_eq!((w, h), (400, 300));
    let count = |c: [u8; 3]| px.iter().filter(|&&q| q == c).count();
    // Two diagonal lines across the plot, each about as long as the plot is wide, 2 px thick.
    let (blue, orange) = (count([0, 114, 178]), count([213, 94, 0]));
    assert!(blue > 2 * 250 && orange > 2 * 250, "{blue} {orange}");
    // The first series falls: its leftmost pixel is above (smaller y) its rightmost.
    let (mut first, mut last) = ((w, 0), (0, 0));
    for y in 40..h {
        for x in 0..w {
            if px[y * w + x] == [0, 114, 178] {
                if x < first.0 {
                    first = (x, y);
                }
                if x > last.0 {
                    last = (x, y);
                }
            }
        }
    }
    assert!(first.1 + 100 < last.1, "{first:?} {last:?}");
    let (c, e) = run(&["plot", ".", "--y", "energy_stretch", "-o", "bad.png"], p);
    assert_eq!(c, 2, "{e}");
    assert!(
        e.contains("energy_bending") && e.contains("energy_stretch"),
        "{e}"
    );
    assert!(!p.join("bad.png").exists());
}

/// `output.snapshots`: a PNG beside every frame (`"all"`) or beside the last one (`"final"`),
/// of the asked size; a snapshot field that the frames do not carry is refused before the run.
#[test]
fn snapshots_are_written_beside_frames() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let (c, e) = run(
        &[
            "mesh", "square", "--size", "1", "--edge", "0.2", "-o", "sq.vtk",
        ],
        p,
    );
    assert_eq!(c, 0, "{e}");
    std::fs::write(
        p.join("s.toml"),
        "[material]\nyoung = 1.0e6\nthickness = 0.01\n[rest]\ntarget = \"uniform\"\n\
         bbar = [2.0, 0.0, 0.0]\n[solver]\nmax_continuation_step = 0.5\n\
         [output]\ncontinuation_frames = true\nsnapshot_size = [160, 120]\n",
    )
    .unwrap();
    for (mode, out) in [("all", "a"), ("final", "f")] {
        let set = format!("output.snapshots={mode}");
        let (c, e) = run(&["s.toml", "sq.vtk", "--out", out, "-q", "--set", &set], p);
        assert_eq!(c, 0, "{e}");
        let frames: Vec<_> = (0..)
            .take_while(|k| p.join(out).join(format!("frame_{k:05}.vtu")).exists())
            .collect();
        assert!(frames.len() >= 3, "{frames:?}");
        for &k in &frames {
            let png = p.join(out).join(format!("frame_{k:05}.png"));
            let want = mode == "all" || k == *frames.last().unwrap();
            assert_eq!(png.exists(), want, "{mode}: frame {k}");
            if want {
                let (w, h, _) = decode(&png);
                assert_eq!((w, h), (160, 120));
            }
        }
    }
    let (c, e) = run(
        &[
            "s.toml",
            "sq.vtk",
            "--out",
            "x",
            "-q",
            "--set",
            "output.snapshots=all",
            "--set",
            "output.snapshot_field=nothing",
        ],
        p,
    );
    assert_eq!(c, 2, "{e}");
    assert!(
        e.contains("snapshot_field") && e.contains("mean_curvature"),
        "{e}"
    );
    assert!(!p.join("x").exists());
}

/// Smooth shading (the default) interpolates vertex normals, so a sphere's shading changes
/// gradually from pixel to pixel; flat shading shows the facets as steps between neighbours.
#[test]
fn smooth_shading_hides_facets_and_flat_shows_them() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let (c, e) = run(
        &[
            "mesh", "sphere", "--radius", "1", "--edge", "0.25", "-o", "s.vtk",
        ],
        p,
    );
    assert_eq!(c, 0, "{e}");
    // Steps of more than 4 levels between horizontal neighbours, both on the surface.
    let steps = |shading: &str| {
        let out = format!("{shading}.png");
        let (c, e) = run(
            &[
                "render",
                "s.vtk",
                "-o",
                &out,
                "--size",
                "300x300",
                "--shading",
                shading,
            ],
            p,
        );
        assert_eq!(c, 0, "{e}");
        let (w, h, px) = decode(&p.join(&out));
        let surface = |q: [u8; 3]| q != [255, 255, 255];
        let mut n = 0;
        for y in 0..h {
            for x in 1..w - 2 {
                let (a, b) = (px[y * w + x], px[y * w + x + 1]);
                // Interior pixels only (their neighbours on both sides on the surface).
                if surface(px[y * w + x - 1])
                    && surface(a)
                    && surface(b)
                    && surface(px[y * w + x + 2])
                {
                    n += (a[0] as i32 - b[0] as i32).abs().gt(&4) as usize;
                }
            }
        }
        n
    };
    let (smooth, flat) = (steps("smooth"), steps("flat"));
    assert!(smooth * 10 < flat, "smooth {smooth} steps, flat {flat}");
    let (c, e) = run(
        &["render", "s.vtk", "-o", "x.png", "--shading", "gouraud"],
        p,
    );
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("flat") && e.contains("smooth"), "{e}");
}

/// A field uniform but for round-off (2e-6 of its value) is drawn in the middle colour of the
/// map, not stretched over all of it; the colour bar says so (its ends ±1% of the value).
#[test]
fn a_field_uniform_to_round_off_is_one_colour() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    std::fs::write(
        p.join("u.vtk"),
        "# vtk DataFile Version 3.0\nu\nASCII\nDATASET POLYDATA\nPOINTS 4 double\n0 0 0\n\
         1 0 0\n1 1 0\n0 1 0\nPOLYGONS 2 8\n3 0 1 2\n3 0 2 3\nCELL_DATA 2\nSCALARS u double 1\n\
         LOOKUP_TABLE default\n0.75 0.7500015\n",
    )
    .unwrap();
    for shading in ["flat", "smooth"] {
        let (c, e) = run(
            &[
                "render",
                "u.vtk",
                "--field",
                "u",
                "-o",
                "u.png",
                "--view",
                "top",
                "--size",
                "300x200",
                "--shading",
                shading,
            ],
            p,
        );
        assert_eq!(c, 0, "{e}");
        let (w, h, px) = decode(&p.join("u.png"));
        let mut n = 0;
        for y in 0..h {
            for x in 0..w * 4 / 5 {
                let q = px[y * w + x].map(|v| v as f64);
                if q == [255.0; 3] {
                    continue;
                }
                n += 1;
                // Viridis' middle, [33, 145, 140], shaded: far from its purple and yellow ends.
                assert!(
                    q[0] < 0.4 * q[1] && (q[1] / q[2] - 145.0 / 140.0).abs() < 0.1,
                    "{shading}: pixel ({x}, {y}) is {q:?}"
                );
            }
        }
        assert!(n > 10_000, "{n}");
    }
}

/// The largest picture is one the renderer can allocate: a side beyond it is refused (exit 2,
/// nothing written), on the command line and as `output.snapshot_size` before a run starts.
#[test]
fn picture_sizes_beyond_the_maximum_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let (c, e) = run(
        &[
            "mesh", "square", "--size", "1", "--edge", "0.25", "-o", "sq.vtk",
        ],
        p,
    );
    assert_eq!(c, 0, "{e}");
    for size in ["16384x16384", "8193x64", "64x8193"] {
        for cmd in ["render", "plot"] {
            let input = if cmd == "render" { "sq.vtk" } else { "log.csv" };
            std::fs::write(p.join("log.csv"), "time,energy_total\n0,1\n1,2\n").unwrap();
            let (c, e) = run(&[cmd, input, "-o", "big.png", "--size", size], p);
            assert_eq!(c, 2, "{cmd} {size}: {e}");
            assert!(e.contains("8192") && !e.contains("panicked"), "{e}");
            assert!(!p.join("big.png").exists());
        }
    }
    std::fs::write(
        p.join("s.toml"),
        "[material]\nyoung = 1.0e6\nthickness = 0.01\n[rest]\ntarget = \"uniform\"\n\
         abar = [1.1, 0.0, 1.1]\n[output]\nsnapshots = \"all\"\nsnapshot_size = [16384, 16384]\n",
    )
    .unwrap();
    let (c, e) = run(&["s.toml", "sq.vtk", "--out", "o", "-q"], p);
    assert_eq!(c, 2, "{e}");
    assert!(
        e.contains("output.snapshot_size") && e.contains("8192"),
        "{e}"
    );
    assert!(!p.join("o").exists());
}

/// `render` checks a frame as every other reader does: a face naming a vertex that does not
/// exist is exit 2 naming the file and the face, not a panic, and nothing is drawn.
#[test]
fn render_refuses_a_frame_with_a_face_out_of_range() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    std::fs::write(
        p.join("bad.vtk"),
        "# vtk DataFile Version 3.0\nbad\nASCII\nDATASET POLYDATA\nPOINTS 3 double\n0 0 0\n\
         1 0 0\n0 1 0\nPOLYGONS 1 4\n3 0 1 5\n",
    )
    .unwrap();
    let (c, e) = run(&["render", "bad.vtk", "-o", "bad.png"], p);
    assert_eq!(c, 2, "{e}");
    assert!(
        e.contains("bad.vtk") && e.contains("face 0") && e.contains("vertex 5"),
        "{e}"
    );
    assert!(!p.join("bad.png").exists());
}

/// `plot --log-y`: a logarithmic axis over positive data; zero or negative data is refused
/// (exit 2) naming the column and where, with no picture. The vertical axis is labelled.
#[test]
fn plot_log_axis_and_its_refusals() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    std::fs::write(
        p.join("log.csv"),
        "frame,time,energy_total,residual\n0,0.0,1.0,1e-1\n1,0.5,0.5,1e-4\n2,1.0,0.0,1e-9\n",
    )
    .unwrap();
    let (c, e) = run(
        &[
            "plot", ".", "--y", "residual", "--log-y", "--size", "400x300", "-o", "r.png",
        ],
        p,
    );
    assert_eq!(c, 0, "{e}");
    let (w, h, px) = decode(&p.join("r.png"));
    // On a log axis the residual's three points fall in equal-ish steps: the middle one sits
    // between the others, nearer the first (3 decades down of 8), unlike on a linear axis.
    let blue: Vec<(usize, usize)> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| px[y * w + x] == [0, 114, 178] && y > 40)
        .collect();
    let ys = |x0: usize, x1: usize| {
        let v: Vec<usize> = blue
            .iter()
            .filter(|q| (x0..x1).contains(&q.0))
            .map(|q| q.1)
            .collect();
        v.iter().sum::<usize>() as f64 / v.len().max(1) as f64
    };
    let xs: Vec<usize> = blue.iter().map(|q| q.0).collect();
    let (xmin, xmax) = (*xs.iter().min().unwrap(), *xs.iter().max().unwrap());
    let xmid = (xmin + xmax) / 2;
    let (y0, ym, y1) = (
        ys(xmin, xmin + 3),
        ys(xmid - 1, xmid + 2),
        ys(xmax - 2, xmax + 1),
    );
    let frac = (ym - y0) / (y1 - y0);
    assert!((frac - 3.0 / 8.0).abs() < 0.08, "{y0} {ym} {y1}: {frac}");
    // The vertical label: dark pixels in the leftmost column band, about the plot's middle.
    let dark = (h / 3..2 * h / 3)
        .flat_map(|y| (0..12).map(move |x| (x, y)))
        .filter(|&(x, y)| px[y * w + x].iter().all(|&v| v < 128))
        .count();
    assert!(dark > 20, "{dark}");
    let (c, e) = run(
        &[
            "plot",
            ".",
            "--y",
            "residual,energy_total",
            "--log-y",
            "-o",
            "bad.png",
        ],
        p,
    );
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("energy_total") && e.contains("--log-y"), "{e}");
    assert!(!p.join("bad.png").exists());
}
