//! The floors of the module layout (docs/ARCHITECTURE.md): each top-level module of `src/` sits
//! on a floor and may import only from its own floor or below, and the import graph between
//! top-level modules has no cycle. Imports are the `crate::NAME` paths in code (comments and
//! doc comments are skipped), and `main.rs`'s `shellsim::NAME`.
//!
//! The imports that still break a rule are listed in `tests/data/floors_known.txt`, one per
//! line. The test fails on any break not listed there, and on any listed one that no longer
//! occurs, so the list can only shrink: delete a line when its import is gone.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The floor of every top-level module, lowest first.
const FLOORS: &[(&str, u32)] = &[
    // 1: scalars, small vectors, sparse Cholesky, the thread team, units.
    ("math", 1),
    ("linalg", 1),
    ("team", 1),
    ("units", 1),
    // 2: configuration; mesh and geometry; contact laws; expressions of x, y.
    ("config", 2),
    ("settings", 2),
    ("expr", 2),
    ("mesh", 2),
    ("geometry", 2),
    ("contact", 2),
    ("fields", 2),
    // 3: rest forms, their laws and the fields that drive them; the element loops.
    ("rest", 3),
    ("elements", 3),
    ("diffusion", 3),
    // 4: the body and its scales.
    ("body", 4),
    ("scales", 4),
    // 5: energy terms and their registry.
    ("energy", 5),
    ("model", 5),
    // 6: assembly.
    ("assembly", 6),
    // 7: physics-free solvers.
    ("solve", 7),
    // 8: drivers.
    ("integrate", 8),
    ("design", 8),
    // 9: output and what reads it back.
    ("output", 9),
    ("provenance", 9),
    ("restart", 9),
    ("render", 9),
    // 10: commands and tools.
    ("cases", 10),
    ("morphoshell", 10),
    ("sweep", 10),
    ("fuzz", 10),
    ("cli", 10),
    ("main", 10),
    ("lib", 10),
];

fn floor(module: &str) -> Option<u32> {
    FLOORS.iter().find(|(m, _)| *m == module).map(|f| f.1)
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The top-level module a file belongs to (`src/energy/gas.rs` → `energy`).
fn module_of(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).unwrap();
    let first = rel
        .components()
        .next()
        .unwrap()
        .as_os_str()
        .to_string_lossy();
    first.trim_end_matches(".rs").to_string()
}

/// The top-level modules a source text names as `crate::NAME` (or `shellsim::NAME`), outside
/// comments, with the line of each first mention.
fn imports(text: &str, prefix: &str) -> BTreeMap<String, usize> {
    let mut out = BTreeMap::new();
    let mut in_test = false;
    for (i, line) in text.lines().enumerate() {
        let code = line.trim_start();
        if code.starts_with("//") {
            continue;
        }
        // Unit tests may reach anywhere (they test the floor they sit on with higher floors'
        // help); the layering is about the code they test.
        if code.starts_with("#[cfg(test)]") {
            in_test = true;
        }
        if in_test {
            continue;
        }
        let code = code.split("//").next().unwrap_or("");
        let mut rest = code;
        while let Some(k) = rest.find(prefix) {
            let after = &rest[k + prefix.len()..];
            let name: String = after
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                out.entry(name).or_insert(i + 1);
            }
            rest = after;
        }
        // `use crate::{a, b::c}` names several.
        if let Some(k) = code.find(&format!("{prefix}{{")) {
            let inner = &code[k + prefix.len() + 1..];
            let inner = inner.split('}').next().unwrap_or("");
            for part in inner.split(',') {
                let name: String = part
                    .trim()
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    out.entry(name).or_insert(i + 1);
                }
            }
        }
    }
    out
}

#[test]
fn modules_import_only_from_their_floor_or_below_and_form_no_cycle() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let src = root.join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    // module → imported module → first place (file:line).
    let mut graph: BTreeMap<String, BTreeMap<String, String>> = BTreeMap::new();
    for f in &files {
        let m = module_of(&src, f);
        assert!(
            floor(&m).is_some(),
            "src/{m}: a new top-level module needs its floor in tests/floors.rs"
        );
        let text = std::fs::read_to_string(f).unwrap();
        let prefix = if m == "main" { "shellsim::" } else { "crate::" };
        for (to, line) in imports(&text, prefix) {
            if to == m || floor(&to).is_none() {
                continue;
            }
            let at = format!("{}:{line}", f.strip_prefix(root).unwrap().display());
            graph.entry(m.clone()).or_default().entry(to).or_insert(at);
        }
    }
    let mut breaks = BTreeSet::new();
    let mut places = BTreeMap::new();
    for (from, tos) in &graph {
        for (to, at) in tos {
            if floor(to) > floor(from) {
                let b = format!("{from} -> {to}");
                places.insert(b.clone(), at.clone());
                breaks.insert(b);
            }
        }
    }
    // Cycles within a floor: pairs that reach each other through imports on that floor.
    for (from, tos) in &graph {
        for to in tos.keys() {
            if floor(to) == floor(from) && reaches(&graph, to, from) && from < to {
                let b = format!("{from} <-> {to} (cycle)");
                places.insert(b.clone(), tos[to].clone());
                breaks.insert(b);
            }
        }
    }
    let known_path = root.join("tests/data/floors_known.txt");
    let known: BTreeSet<String> = std::fs::read_to_string(&known_path)
        .unwrap()
        .lines()
        .map(|l| l.split('#').next().unwrap().trim().to_string())
        .filter(|l| !l.is_empty())
        .collect();
    let new: Vec<String> = breaks
        .difference(&known)
        .map(|b| format!("{b}   (first at {})", places[b]))
        .collect();
    let gone: Vec<&String> = known.difference(&breaks).collect();
    println!("{} known breaks of the floors remain:", breaks.len());
    for b in &breaks {
        println!("  {b}   ({})", places[b]);
    }
    assert!(
        new.is_empty(),
        "imports from a higher floor or cycles that are new (see docs/ARCHITECTURE.md):\n{}",
        new.join("\n")
    );
    assert!(
        gone.is_empty(),
        "these breaks are fixed: delete them from {}:\n{gone:#?}",
        known_path.display()
    );
}

/// True when `to` is reachable from `from` along imports that stay on `from`'s floor.
fn reaches(graph: &BTreeMap<String, BTreeMap<String, String>>, from: &str, to: &str) -> bool {
    let fl = floor(from);
    let mut seen = BTreeSet::new();
    let mut stack = vec![from.to_string()];
    while let Some(m) = stack.pop() {
        if m == to {
            return true;
        }
        if !seen.insert(m.clone()) {
            continue;
        }
        if let Some(tos) = graph.get(&m) {
            for t in tos.keys() {
                if floor(t) == fl {
                    stack.push(t.clone());
                }
            }
        }
    }
    false
}

/// The parser sees through `use crate::{…}` groups and skips comments.
#[test]
fn the_import_parser_reads_groups_and_skips_comments() {
    let text = "use crate::math::Real;\nuse crate::{mesh::Mesh, scene};\n// crate::cli\n\
                /// [`crate::output`]\nlet x = crate::energy::f(); // crate::render\n\
                #[cfg(test)]\nmod tests { use crate::sweep; }\n";
    let got: Vec<String> = imports(text, "crate::").into_keys().collect();
    assert_eq!(got, ["energy", "math", "mesh", "scene"]);
}
