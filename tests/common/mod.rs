//! Helpers shared by the integration-test crates.

use std::path::Path;
use std::process::Command;

/// Runs the binary in `dir`, asserts success (with its stderr in the message) and returns its
/// stdout.
pub fn shellsim(args: &[&str], dir: &Path) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_shellsim"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "shellsim {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}
