//! The `shellsim` binary: all work happens in the library (`shellsim::cli`).
fn main() -> std::process::ExitCode {
    shellsim::cli::main()
}
