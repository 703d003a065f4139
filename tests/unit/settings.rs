//! Settings parsing, defaults and overrides.

use shellsim::settings::{apply_overrides, Settings};

#[test]
fn defaults_and_overrides() {
    let s = Settings::from_str_with("", "t", &[]).unwrap();
    assert_eq!(s.material.poisson, 0.3);
    let s = Settings::from_str_with(
        "[material]\nthickness = 0.1\n",
        "t",
        &[
            "material.thickness=0.2".into(),
            "loads.gravity=[0, 0, -9.81]".into(),
            "output.prefix=run".into(),
        ],
    )
    .unwrap();
    assert_eq!(s.material.thickness, 0.2);
    assert_eq!(s.loads.gravity[2], -9.81);
    assert_eq!(s.output.prefix, "run");
}

#[test]
fn unknown_keys_name_the_key_and_line() {
    let e = Settings::from_str_with("[solver]\ntolerance = 1e-9\nmax_iter = 3\n", "s.toml", &[])
        .unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("max_iter") && msg.contains("line 3"), "{msg}");
}

#[test]
fn poisson_one_half_is_allowed_and_above_is_not() {
    assert!(Settings::from_str_with("[material]\npoisson = 0.5\n", "t", &[]).is_ok());
    assert!(Settings::from_str_with("[material]\npoisson = 0.5000001\n", "t", &[]).is_err());
}

#[test]
fn override_syntax_errors() {
    let mut t = toml::Table::new();
    assert!(apply_overrides(&mut t, &["a..b=1".into()]).is_err());
    assert!(apply_overrides(&mut t, &["novalue".into()]).is_err());
}

/// Pullback forms as settings expressions of x, y equal the same forms given per face (seed
/// 000 Table 1's hyperboloid, programmed by `Case::program` at the face centroids), and the
/// isotropic law's `growth.s` expression equals the conformal cap's metric e^{2s} I.
#[test]
fn expressions_of_x_y_give_the_per_face_forms() {
    use shellsim::cases::Case;
    use shellsim::mesh::generate::{rectangle, Spacing};
    use shellsim::model::Scene;
    let mesh = || rectangle(-0.5, -0.5, 1.0, 1.0, 0.125, Spacing::default());
    let mut programmed = mesh();
    Case::Hyperboloid.program(&mut programmed);
    let by_fields = Scene::build(
        programmed,
        Settings::from_str_with("[rest]\ntarget = \"mesh\"\n", "t", &[]).unwrap(),
    )
    .unwrap();
    let text = "[rest]\ntarget = \"uniform\"\nabar = [\"1 + x^2\", \"-x*y\", \"1 + y^2\"]\n\
                bbar = [\"-1/sqrt(1 + x^2 + y^2)\", 0, \"1/sqrt(1 + x^2 + y^2)\"]\n";
    let by_expr = Scene::build(mesh(), Settings::from_str_with(text, "t", &[]).unwrap()).unwrap();
    for f in 0..by_expr.body.num_faces() {
        assert!((by_expr.body.rest.abar1[f] - by_fields.body.rest.abar1[f]).norm() < 1e-14);
        assert!((by_expr.body.rest.bbar1[f] - by_fields.body.rest.bbar1[f]).norm() < 1e-14);
    }
    // Isotropic growth with s(x, y): ā = e^{2s} a⁰ at each centroid.
    let text = "[growth]\nlaw = \"isotropic\"\ns = \"-log(1 + (x^2 + y^2)/4)\"\n";
    let sc = Scene::build(mesh(), Settings::from_str_with(text, "t", &[]).unwrap()).unwrap();
    for f in 0..sc.body.num_faces() {
        let [p0, p1, p2] = sc.body.mesh.face_positions(f);
        let c = (p0 + p1 + p2) / 3.0;
        let eta = 1.0 / (1.0 + 0.25 * (c.x * c.x + c.y * c.y));
        let want = sc.body.rest.abar0[f] * (eta * eta);
        assert!((sc.body.rest.abar1[f] - want).norm() < 1e-13 * want.norm());
    }
    // Bad expressions name the key; values that are not finite or not positive definite name
    // the face.
    for (text, needle) in [
        (
            "[rest]\ntarget = \"uniform\"\nabar = [\"1 + \", 0, 1]\n",
            "rest.abar[0]",
        ),
        (
            "[growth]\nlaw = \"isotropic\"\ns = \"foo(x)\"\n",
            "growth.s",
        ),
    ] {
        let e = Settings::from_str_with(text, "t", &[]).unwrap_err();
        assert!(format!("{e:#}").contains(needle), "{e:#}");
    }
    for (text, needle) in [
        (
            "[rest]\ntarget = \"uniform\"\nabar = [\"x\", 0, 1]\n",
            "not positive definite",
        ),
        (
            "[rest]\ntarget = \"uniform\"\nabar = [\"1/x\", 0, 1]\n",
            "rest.abar is not finite on an edge of face",
        ),
        (
            "[growth]\nlaw = \"isotropic\"\ns = \"log(x)\"\n",
            "growth.s is NaN at face",
        ),
    ] {
        let s = Settings::from_str_with(text, "t", &[]).unwrap();
        let e = Scene::build(mesh(), s).unwrap_err();
        assert!(format!("{e:#}").contains(needle), "{e:#}");
    }
}

/// Each section's validator (`shellsim::config`) accepts the defaults and refuses a bad value
/// in its own section, naming the key; another section's validator does not see it, and the
/// whole file is refused with the file's name and the key.
#[test]
fn each_section_validates_itself() {
    use shellsim::config::Invalid;
    type V = fn(&Settings) -> Result<(), Invalid>;
    let material: V = |s| s.material.validate(s.solver.mode);
    let rest: V = |s| s.rest.validate();
    let solver: V = |s| s.solver.validate();
    let growth: V = |s| s.growth.validate(s.rest.target);
    let moisture: V = |s| {
        s.moisture
            .validate(&s.growth, s.contact.enabled, s.solver.mode)
    };
    let time: V = |s| s.time.validate();
    let loads: V = |s| s.loads.validate();
    let contact: V = |s| s.contact.validate();
    let constraints: V = |s| s.constraints.validate();
    let output: V = |s| s.output.validate();
    let cases: [(&str, V, &str); 13] = [
        ("material.young", material, "young = -1"),
        ("rest.dial_time", rest, "dial_time = -1"),
        ("solver.tolerance", solver, "tolerance = 0"),
        ("growth.mu", growth, "mu = nan"),
        ("moisture.layers", moisture, "enabled = true\nlayers = 0"),
        ("time.dt", time, "dt = 10"),
        (
            "loads.point[0].force",
            loads,
            "point = [{ force = [nan, 0, 0], tags = [1] }]",
        ),
        ("loads.gravity", loads, "gravity = [-1e308, 0, -9.81]"),
        (
            "moisture.grading",
            moisture,
            "enabled = true\ngrading = 0.5",
        ),
        (
            "moisture.tolerance",
            moisture,
            "enabled = true\ntolerance = 1",
        ),
        (
            "contact.normal",
            contact,
            "enabled = true\nnormal = [0, 0, 0]",
        ),
        (
            "constraints.clamp[0].inside",
            constraints,
            "clamp = [{ inside = { min = [1, 0, 0], max = [0, 1, 1] } }]",
        ),
        ("output.prefix", output, "prefix = \"a/b\""),
    ];
    let defaults = Settings::default();
    for (key, validate, line) in cases {
        assert_eq!(validate(&defaults), Ok(()), "{key}: defaults refused");
        let section = key.split('.').next().unwrap();
        let text = format!("[{section}]\n{line}\n");
        let s: Settings = toml::from_str(&text).unwrap_or_else(|e| panic!("{text}: {e}"));
        assert_eq!(validate(&s).expect_err(key).key, key);
        // The whole file is refused with the same key, naming the file.
        let err = s.validate("bad.toml").expect_err(key).to_string();
        assert!(
            err.contains(key) && err.contains("bad.toml"),
            "{key}: {err}"
        );
        // Another section's validator does not look at it.
        let other = if section == "output" {
            material
        } else {
            output
        };
        assert_eq!(other(&s), Ok(()), "{key}: another validator refused it");
    }
}

/// Values that accept a number or a word say so, `--set` follows TOML's rules (a bare word is a
/// string; an out-of-range integer is an error, not a string), and numbers print as `{:e}`.
#[test]
fn messages_name_what_is_accepted() {
    let e = Settings::from_str_with(
        "[solver]\nmembrane_continuation = \"sometimes\"\n",
        "s",
        &[],
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("expected a number or \"auto\", got \"sometimes\"") && e.contains("line 2"),
        "{e}"
    );
    assert!(!e.contains("untagged"), "{e}");
    let e = Settings::from_str_with("", "s", &["solver.seed=18446744073709551615".into()])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("not a TOML value") && !e.contains("invalid type: string"),
        "{e}"
    );
    let s = Settings::from_str_with("", "s", &["solver.mode=dynamic".into()]).unwrap();
    assert_eq!(s.solver.mode, shellsim::settings::Mode::Dynamic);
    let e = Settings::from_str_with("", "s", &["material.young=1e300".into()])
        .unwrap_err()
        .to_string();
    assert!(e.contains("1e300 Pa"), "{e}");
    assert!(!e.contains("000000000000"), "{e}");
}
