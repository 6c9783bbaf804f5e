//! Build script of `prism`: records the git commit the binary is built
//! from (`PRISM_GIT_COMMIT`, shown by `prism --version`), or `unknown`
//! when git or the repository is absent (a source tarball, `cargo install`
//! from a copy).

use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    if !out.status.success() {
        return None;
    }
    let s = String::from_utf8(out.stdout).ok()?.trim().to_owned();
    (!s.is_empty()).then_some(s)
}

fn main() {
    let commit = git(&["rev-parse", "--short=12", "HEAD"]).unwrap_or_else(|| "unknown".to_owned());
    println!("cargo:rustc-env=PRISM_GIT_COMMIT={commit}");
    // Rebuild when HEAD moves: a commit, checkout or reset rewrites the
    // (worktree's) HEAD or appends to its reflog.
    for p in ["HEAD", "logs/HEAD"] {
        if let Some(path) = git(&["rev-parse", "--git-path", p]).filter(|p| std::path::Path::new(p).exists())
        {
            println!("cargo:rerun-if-changed={path}");
        }
    }
    println!("cargo:rerun-if-changed=build.rs");
}
