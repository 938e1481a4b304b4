//! The layering inside each crate (`ARCHITECTURE.md`). Between crates the compiler
//! enforces it (the engine cannot name the rotor library, the rotor library cannot name
//! the applications); inside a crate, every `crate::module` path in a source file,
//! imports and doc links alike, names a module of a lower layer or of the file's own
//! module. Unit-test modules (`#[cfg(test)]` to the end of the file) are exempt: a test may
//! use a reference problem from anywhere. What cargo does not check either is checked
//! here too: the library crates depend on no command-line, terminal, figure or allocator
//! crate, and never print or exit the process.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Rank of each top-level module: a file may only name modules of a lower rank.
const RANKS: &[(&str, u32)] = &[
    // engine (crates/engine)
    ("system", 0),
    ("hb", 1),
    ("integrate", 1),
    ("stability", 2),
    ("systems", 3),
    ("continuation", 3),
    // rotor library (crates/rotor): physics
    ("input", 0),
    ("bearing", 10),
    ("model", 11),
    ("linear", 12),
    ("thermal", 12),
    ("coupled", 13),
    // recording, study, quantities, driver
    ("record", 20),
    ("study", 30),
    ("derive", 40),
    ("sweep", 50),
    ("transient", 50),
    // applications (the root crate); the figures of every kind draw what those compute
    ("campaign", 61),
    ("truncation", 61),
    ("report", 62),
    ("figure", 65),
    // command line
    ("cli", 70),
];

/// The `src` folders of the workspace's crates: the applications, the rotor library and
/// the engine.
fn crate_sources() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    vec![
        root.join("src"),
        root.join("crates/rotor/src"),
        root.join("crates/engine/src"),
    ]
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("read src") {
        let path = entry.expect("dir entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level module a file belongs to (`None` for the crate root and the binaries).
fn module_of(src: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src).ok()?;
    let first = rel.components().next()?.as_os_str().to_str()?.to_string();
    let name = first.trim_end_matches(".rs").to_string();
    match name.as_str() {
        "lib" | "main" | "bin" => None,
        _ => Some(name),
    }
}

/// `crate::name` paths in `text` (outside a trailing `#[cfg(test)]` module).
fn crate_paths(text: &str) -> Vec<(usize, String)> {
    let body = match text.find("#[cfg(test)]\nmod tests") {
        Some(i) => &text[..i],
        None => text,
    };
    let mut out = Vec::new();
    for (n, line) in body.lines().enumerate() {
        let mut rest = line;
        while let Some(i) = rest.find("crate::") {
            let before = &rest[..i];
            let after = &rest[i + "crate::".len()..];
            let name: String = after
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            // `tmrotor::crate::` does not occur; skip `super::crate` look-alikes
            if !before.ends_with(|c: char| c.is_alphanumeric() || c == '_') {
                out.push((n + 1, name));
            }
            rest = after;
        }
    }
    out
}

#[test]
fn no_module_names_a_higher_layer() {
    let ranks: BTreeMap<&str, u32> = RANKS.iter().copied().collect();
    let mut violations = Vec::new();
    for src in crate_sources() {
        let mut files = Vec::new();
        rust_files(&src, &mut files);
        files.sort();
        for file in &files {
            let Some(module) = module_of(&src, file) else {
                continue;
            };
            let Some(&own) = ranks.get(module.as_str()) else {
                violations.push(format!(
                    "{}: module `{module}` has no layer in tests/layering.rs (and ARCHITECTURE.md)",
                    file.display()
                ));
                continue;
            };
            let text = std::fs::read_to_string(file).expect("read source");
            for (line, target) in crate_paths(&text) {
                if target == module {
                    continue;
                }
                // crate-root items (functions in lib.rs) are not modules
                let Some(&theirs) = ranks.get(target.as_str()) else {
                    continue;
                };
                if theirs >= own {
                    violations.push(format!(
                    "{}:{line}: `{module}` (layer {own}) names `crate::{target}` (layer {theirs})",
                    file.display()
                ));
                }
            }
        }
    }
    assert!(
        violations.is_empty(),
        "layering broken:\n{}",
        violations.join("\n")
    );
}

#[test]
fn every_top_level_module_has_a_layer() {
    let ranks: BTreeMap<&str, u32> = RANKS.iter().copied().collect();
    let mut all = Vec::new();
    for src in crate_sources() {
        let lib = std::fs::read_to_string(src.join("lib.rs")).expect("read lib.rs");
        let mods: Vec<String> = lib
            .lines()
            .filter_map(|l| l.strip_prefix("pub mod "))
            .map(|l| l.trim_end_matches(';').to_string())
            .collect();
        assert!(mods.len() >= 5, "found only {mods:?} in {}", src.display());
        all.extend(mods);
    }
    assert!(all.len() >= 20, "found only {all:?}");
    for m in all {
        assert!(ranks.contains_key(m.as_str()), "module {m} has no layer");
    }
}

/// Crates the libraries must not depend on: command line, terminal, signals, figures,
/// the allocator choice and error-reporting glue are the applications' business.
const APPLICATION_CRATES: &[&str] = &[
    "clap",
    "indicatif",
    "ctrlc",
    "plotters",
    "plotters-backend",
    "png",
    "mimalloc",
    "libmimalloc-sys",
    "anyhow",
];

#[test]
fn the_libraries_have_no_application_dependencies() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for krate in ["crates/engine", "crates/rotor"] {
        let manifest =
            std::fs::read_to_string(root.join(krate).join("Cargo.toml")).expect("read manifest");
        let doc: toml::Table = manifest.parse().expect("manifest is TOML");
        for section in ["dependencies", "build-dependencies"] {
            let Some(deps) = doc.get(section).and_then(|d| d.as_table()) else {
                continue;
            };
            for name in deps.keys() {
                assert!(
                    !APPLICATION_CRATES.contains(&name.as_str()),
                    "{krate}/Cargo.toml [{section}] names `{name}`, an application dependency"
                );
            }
        }
    }
}

#[test]
fn the_libraries_neither_print_nor_exit() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut found = Vec::new();
    for krate in ["crates/engine/src", "crates/rotor/src"] {
        let mut files = Vec::new();
        rust_files(&root.join(krate), &mut files);
        for file in files {
            let text = std::fs::read_to_string(&file).expect("read source");
            let body = match text.find("#[cfg(test)]\nmod tests") {
                Some(i) => &text[..i],
                None => &text,
            };
            for (n, line) in body.lines().enumerate() {
                let code = line.split("//").next().unwrap_or("");
                for bad in ["println!", "print!(", "process::exit", "ctrlc::"] {
                    if code.contains(bad) {
                        found.push(format!("{}:{}: {bad}", file.display(), n + 1));
                    }
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "library code prints or exits:\n{}",
        found.join("\n")
    );
}

#[test]
fn the_checker_sees_an_upward_path() {
    let text = "use crate::sweep::StudySettings;\n/// see [`crate::cli::run`]\n\
                #[cfg(test)]\nmod tests {\n use crate::cli::x;\n}\n";
    let found: Vec<String> = crate_paths(text).into_iter().map(|(_, m)| m).collect();
    assert_eq!(found, ["sweep", "cli"]);
}
