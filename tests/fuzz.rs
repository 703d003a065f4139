//! A short run of the in-process fuzzer ([`shellsim::fuzz`], 10⁴ executions per input path,
//! thirteen paths) and the inputs earlier runs or reports found to crash, replayed from
//! `tests/data/fuzz/`. The long run is `scripts/fuzz.sh`.

use shellsim::fuzz::{harnesses, Target};
use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn ten_thousand_mutated_inputs_per_path_never_panic() {
    let hs = harnesses(root()).unwrap();
    for h in &hs {
        let r = h.run(10_000, 7);
        println!(
            "{}: {} execs, {} accepted, {} rejected, {} panics, {:.0} execs/s",
            h.target.name(),
            r.execs,
            r.accepted,
            r.rejected,
            r.panics,
            r.execs as f64 / r.seconds
        );
        assert_eq!(r.execs, 10_000);
        let shown: Vec<String> = r
            .crashes
            .iter()
            .map(|(m, i)| format!("{m}: {:?}", String::from_utf8_lossy(&i[..i.len().min(300)])))
            .collect();
        assert_eq!(r.panics, 0, "{}: {shown:#?}", h.target.name());
        // Mutations must leave some inputs valid and break others, or the run tests nothing.
        assert!(
            r.accepted > 0 && r.rejected > 0,
            "{}: {r:?}",
            h.target.name()
        );
    }
}

#[test]
fn crash_inputs_found_before_are_rejected_cleanly() {
    let hs = harnesses(root()).unwrap();
    let dir = root().join("tests/data/fuzz");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let p = entry.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        let target =
            Target::of_file(&name).unwrap_or_else(|| panic!("{name}: names no fuzz target"));
        let h = hs.iter().find(|h| h.target == target).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        let r = h.exec(&bytes);
        assert!(r.is_ok(), "{name} must not panic: {r:?}");
        // A reader's crash input is a broken file; a command's may be a valid input it drew.
        if matches!(
            target,
            Target::Legacy
                | Target::Xml
                | Target::Settings
                | Target::Restart
                | Target::Off
                | Target::Obj
                | Target::Ply
                | Target::Stl
        ) {
            assert_eq!(r, Ok(false), "{name} must be rejected without a panic");
        }
        n += 1;
    }
    assert!(
        n >= 3,
        "the regression inputs are missing from {}",
        dir.display()
    );
}
