//! prism-geometry depends on glam only: checked with `cargo tree`.

use std::path::Path;
use std::process::Command;

const ALLOWED: &[&str] = &["glam"];

fn from_cargo_tree(workspace: &Path) -> Option<Vec<String>> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args([
            "tree",
            "-p",
            "prism-geometry",
            "-e",
            "normal",
            "--depth",
            "1",
            "--prefix",
            "none",
            "--offline",
        ])
        .current_dir(workspace)
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    let text = String::from_utf8(out.stdout).ok()?;
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let root = lines.next()?;
    assert!(root.starts_with("prism-geometry "), "unexpected cargo tree output: {text}");
    Some(lines.map(|l| l.split_whitespace().next().unwrap_or_default().to_string()).collect())
}

fn from_manifest(manifest: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(manifest).unwrap();
    let mut deps = Vec::new();
    let mut in_deps = false;
    for line in text.lines().map(str::trim) {
        if line.starts_with('[') {
            in_deps =
                line == "[dependencies]" || line.starts_with("[target.") && line.ends_with(".dependencies]");
            continue;
        }
        if in_deps && !line.is_empty() && !line.starts_with('#') {
            let name = line.split(['=', '.']).next().unwrap().trim();
            deps.push(name.to_string());
        }
    }
    deps
}

#[test]
fn depends_on_glam_only() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let workspace = crate_dir.ancestors().nth(2).unwrap();
    let manifest_deps = from_manifest(&crate_dir.join("Cargo.toml"));
    assert!(
        manifest_deps.iter().all(|d| ALLOWED.contains(&d.as_str())),
        "manifest dependencies: {manifest_deps:?}"
    );
    assert!(manifest_deps.iter().any(|d| d == "glam"));
    if let Some(tree) = from_cargo_tree(workspace) {
        assert!(!tree.is_empty(), "cargo tree listed no dependency at all");
        assert!(
            tree.iter().all(|d| ALLOWED.contains(&d.as_str())),
            "cargo tree: direct dependencies {tree:?}"
        );
    }
}
