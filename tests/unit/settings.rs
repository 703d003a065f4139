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
