//! The in-process fuzzer ([`shellsim::fuzz`]) over every input path, from the command line:
//!
//!     cargo run --release --example fuzz -- [EXECS_PER_TARGET] [SEED] [CRASH_DIR] [TARGET,…]
//!
//! (all targets unless some are named). With `SHELLSIM_FUZZ_LAST=FILE` set, each input is
//! written to FILE before it runs, so that the input of an abort (which no guard catches) is
//! kept.
//! Prints executions, accepted, rejected and panics per target, and executions per second.
//! Inputs that panic are written to CRASH_DIR (default `fuzz-crashes/`) as
//! `TARGET-N.EXT`; copy them to `tests/data/fuzz/` to make them regression tests. Exits 1 if
//! anything panicked.
use std::path::{Path, PathBuf};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let execs: u64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(80_000);
    let seed: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    let crash_dir = PathBuf::from(args.get(3).map_or("fuzz-crashes", |s| s.as_str()));
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let hs = match shellsim::fuzz::harnesses(root) {
        Ok(h) => h,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let (mut total, mut panics, mut secs) = (0u64, 0u64, 0.0);
    println!("target             execs      accepted   rejected   panics  execs/s");
    let only: Vec<&str> = args.get(4).map_or(Vec::new(), |s| s.split(',').collect());
    for h in hs
        .iter()
        .filter(|h| only.is_empty() || only.contains(&h.target.name()))
    {
        let r = h.run(execs, seed);
        println!(
            "{:<18} {:<10} {:<10} {:<10} {:<7} {:.0}",
            h.target.name(),
            r.execs,
            r.accepted,
            r.rejected,
            r.panics,
            r.execs as f64 / r.seconds
        );
        for (i, (msg, input)) in r.crashes.iter().enumerate() {
            let ext = h.target.ext();
            let _ = std::fs::create_dir_all(&crash_dir);
            let p = crash_dir.join(format!("{}-{i}.{ext}", h.target.name()));
            let _ = std::fs::write(&p, input);
            eprintln!("  panic: {msg} -> {}", p.display());
        }
        total += r.execs;
        panics += r.panics;
        secs += r.seconds;
    }
    println!(
        "total              {total:<10} panics {panics}, {:.0} execs/s, {secs:.1} s",
        total as f64 / secs
    );
    if panics > 0 {
        std::process::exit(1);
    }
}
