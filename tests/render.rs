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
