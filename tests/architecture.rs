//! Architecture invariants (ARCHITECTURE.md), checked from `cargo metadata`
//! and the sources: the layering of the crates, the dependencies algorithm
//! crates may not have, no I/O or printing in algorithm crates, parry2d only
//! in sim, file-format crates only in io, printing only in cli, and a `//!`
//! doc opening every source file.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The algorithm crates and the workspace crates each may depend on.
const LAYERS: &[(&str, &[&str])] = &[
    ("pcaline-geometry", &[]),
    ("pcaline-segmentation", &["pcaline-geometry"]),
    ("pcaline-fitting", &["pcaline-geometry"]),
    ("pcaline-mapping", &["pcaline-geometry", "pcaline-fitting"]),
    ("pcaline-aiding", &["pcaline-geometry", "pcaline-fitting", "pcaline-mapping"]),
];

/// Crates no algorithm crate may depend on.
const FORBIDDEN: &[&str] = &["parry2d", "clap", "anyhow", "indicatif", "rayon"];

fn metadata() -> Value {
    let out = Command::new(env!("CARGO"))
        .args(["metadata", "--format-version", "1", "--no-deps", "--offline"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo metadata runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).expect("cargo metadata prints JSON")
}

#[test]
fn algorithm_crates_respect_the_layering() {
    let meta = metadata();
    let packages = meta["packages"].as_array().unwrap();
    let workspace: Vec<&str> = packages.iter().map(|p| p["name"].as_str().unwrap()).collect();
    let mut checked = 0;
    for package in packages {
        let name = package["name"].as_str().unwrap();
        let Some((_, allowed)) = LAYERS.iter().find(|(n, _)| *n == name) else { continue };
        checked += 1;
        for dep in package["dependencies"].as_array().unwrap() {
            let dep_name = dep["name"].as_str().unwrap();
            if dep["kind"].as_str() == Some("dev") {
                continue;
            }
            assert!(!FORBIDDEN.contains(&dep_name), "{name} must not depend on {dep_name}");
            if workspace.contains(&dep_name) {
                assert!(allowed.contains(&dep_name), "{name} may not depend on {dep_name}");
            }
        }
    }
    assert!(checked >= 3, "found only {checked} algorithm crates");
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn every_source_file_opens_with_a_module_doc() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = vec![];
    for dir in ["src", "crates", "tests", "benches", "python/src"] {
        if root.join(dir).exists() {
            rust_files(&root.join(dir), &mut files);
        }
    }
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap();
        let first = text.lines().find(|l| !l.trim().is_empty()).unwrap_or("");
        assert!(first.starts_with("//!"), "{} does not open with //!", file.display());
    }
}

#[test]
fn algorithm_crates_do_no_io_and_print_nothing() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (name, _) in LAYERS {
        let dir = root.join("crates").join(name.trim_start_matches("pcaline-")).join("src");
        if !dir.exists() {
            continue;
        }
        let mut files = vec![];
        rust_files(&dir, &mut files);
        for file in files {
            let text = std::fs::read_to_string(&file).unwrap();
            // Only the non-test part of the file counts.
            let code = text.split("#[cfg(test)]").next().unwrap();
            for banned in [
                "std::fs",
                "std::io",
                "std::net",
                "println!",
                "eprintln!",
                "print!(",
                "std::process",
            ] {
                assert!(!code.contains(banned), "{} uses {banned}", file.display());
            }
        }
    }
}

/// Third-party crates only one workspace crate may depend on (dev
/// dependencies aside): ray casting lives in sim, file formats in io.
const OWNED_BY: &[(&str, &str)] = &[
    ("parry2d", "pcaline-sim"),
    ("rosbag", "pcaline-io"),
    ("rusqlite", "pcaline-io"),
    ("mcap", "pcaline-io"),
];

#[test]
fn only_sim_knows_parry2d_and_only_io_knows_file_formats() {
    let meta = metadata();
    let mut owners_seen = 0;
    for package in meta["packages"].as_array().unwrap() {
        let name = package["name"].as_str().unwrap();
        for dep in package["dependencies"].as_array().unwrap() {
            if dep["kind"].as_str() == Some("dev") {
                continue;
            }
            let dep_name = dep["name"].as_str().unwrap();
            if let Some((_, owner)) = OWNED_BY.iter().find(|(d, _)| *d == dep_name) {
                assert_eq!(name, *owner, "{name} depends on {dep_name}, which only {owner} may");
                owners_seen += 1;
            }
        }
    }
    assert_eq!(owners_seen, OWNED_BY.len(), "each owned crate is used by its owner");
}

#[test]
fn only_cli_prints() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = vec![];
    rust_files(&root.join("src"), &mut files);
    // The Python bindings report through exceptions, never stdout.
    rust_files(&root.join("python/src"), &mut files);
    for entry in std::fs::read_dir(root.join("crates")).unwrap() {
        let dir = entry.unwrap().path();
        if dir.file_name().is_some_and(|n| n != "cli") {
            rust_files(&dir.join("src"), &mut files);
        }
    }
    assert!(files.len() > 50, "found only {} source files", files.len());
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap();
        // Code outside the tests and the docs (doc examples may print).
        let code: String = text
            .split("#[cfg(test)]")
            .next()
            .unwrap()
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect();
        for banned in ["println!", "eprintln!", "print!(", "eprint!(", "dbg!("] {
            assert!(!code.contains(banned), "{} uses {banned}: only cli prints", file.display());
        }
    }
}
