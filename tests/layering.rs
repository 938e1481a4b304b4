//! The crate's layering (`ARCHITECTURE.md`): every `crate::module` path in a source file,
//! imports and doc links alike, names a module of a lower layer or of the file's own
//! module. Unit-test modules (`#[cfg(test)]` to the end of the file) are exempt: a test may
//! use a reference problem from anywhere.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Rank of each top-level module: a file may only name modules of a lower rank.
const RANKS: &[(&str, u32)] = &[
    // engine
    ("system", 0),
    ("hb", 1),
    ("integrate", 1),
    ("input", 0),
    ("stability", 2),
    ("systems", 3),
    ("continuation", 3),
    // physics
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
    // applications
    ("figure", 60),
    ("campaign", 61),
    ("truncation", 61),
    ("report", 62),
    // command line
    ("cli", 70),
];

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
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let ranks: BTreeMap<&str, u32> = RANKS.iter().copied().collect();
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut violations = Vec::new();
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
    assert!(
        violations.is_empty(),
        "layering broken:\n{}",
        violations.join("\n")
    );
}

#[test]
fn every_top_level_module_has_a_layer() {
    let lib = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs"))
        .expect("read lib.rs");
    let ranks: BTreeMap<&str, u32> = RANKS.iter().copied().collect();
    let mods: Vec<&str> = lib
        .lines()
        .filter_map(|l| l.strip_prefix("pub mod "))
        .map(|l| l.trim_end_matches(';'))
        .collect();
    assert!(mods.len() >= 15, "found only {mods:?} in lib.rs");
    for m in mods {
        assert!(ranks.contains_key(m), "module {m} has no layer");
    }
}

#[test]
fn the_checker_sees_an_upward_path() {
    let text = "use crate::sweep::StudySettings;\n/// see [`crate::cli::run`]\n\
                #[cfg(test)]\nmod tests {\n use crate::cli::x;\n}\n";
    let found: Vec<String> = crate_paths(text).into_iter().map(|(_, m)| m).collect();
    assert_eq!(found, ["sweep", "cli"]);
}
