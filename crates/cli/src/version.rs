//! `prism --version`: the version, the git commit of the build and the
//! SIMD paths this machine enables, detected at run time.

use std::sync::OnceLock;

/// The git commit the binary was built from (12 hex digits), or `unknown`
/// (recorded by `build.rs`).
pub const COMMIT: &str = env!("PRISM_GIT_COMMIT");

/// The SIMD paths of prism and whether this CPU (and environment) enables
/// each: `(path, enabled)`. Two today, both chosen when the structure is
/// built and both off with `PRISM_BVH_NO_SIMD`: the AVX2 compilation of
/// the closest-hit and packet queries' walks (`bvh-avx2`), and an intrinsics kernel for the node test
/// of the wide (8-child) hierarchies (`bvh8-avx512` where the CPU has
/// AVX-512 F and VL, else `bvh8-avx2` where it has AVX2, unless
/// `PRISM_BVH_KERNEL` names another; see [`prism_bvh::Kernel::detect`]).
/// A new run-time path adds a line here.
#[must_use]
pub fn simd_paths() -> Vec<(&'static str, bool)> {
    let forced_off = std::env::var_os("PRISM_BVH_NO_SIMD").is_some();
    let kernel = prism_bvh::Kernel::detect();
    vec![
        // The same CPU features as the AVX2 kernel: avx2 fma bmi1 bmi2 lzcnt popcnt.
        ("bvh-avx2", !forced_off && prism_bvh::Kernel::Avx2.supported()),
        ("bvh8-avx512", kernel == prism_bvh::Kernel::Avx512),
        ("bvh8-avx2", kernel == prism_bvh::Kernel::Avx2),
    ]
}

/// The SIMD paths enabled here, space-separated (`scalar` if none).
#[must_use]
pub fn enabled_simd() -> String {
    let on: Vec<&str> = simd_paths().into_iter().filter(|p| p.1).map(|p| p.0).collect();
    if on.is_empty() { "scalar".to_owned() } else { on.join(" ") }
}

/// The text after `prism ` printed by `prism --version`:
///
/// ```text
/// 0.1.0
/// commit: 4645439abcde
/// simd:   bvh-avx2 bvh8-avx2 (detected at run time; scalar fallback always present)
/// ```
pub fn long() -> &'static str {
    static TEXT: OnceLock<String> = OnceLock::new();
    TEXT.get_or_init(|| {
        format!(
            "{}\ncommit: {COMMIT}\nsimd:   {} (detected at run time; scalar fallback always present)",
            env!("CARGO_PKG_VERSION"),
            enabled_simd()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_long_version_names_version_commit_and_simd() {
        let text = long();
        assert!(text.starts_with(env!("CARGO_PKG_VERSION")), "{text}");
        assert!(text.contains(&format!("commit: {COMMIT}")), "{text}");
        assert!(COMMIT == "unknown" || (COMMIT.len() == 12 && COMMIT.bytes().all(|b| b.is_ascii_hexdigit())));
        // The third line names known paths only (which ones this CPU
        // enables is checked against its features in tests/conventions.rs).
        let simd = text.lines().nth(2).and_then(|l| l.strip_prefix("simd:   ")).unwrap_or_default();
        let (names, rest) = simd.split_once(" (").unwrap_or_default();
        assert_eq!(rest, "detected at run time; scalar fallback always present)", "{text}");
        let known: Vec<&str> = simd_paths().iter().map(|p| p.0).chain(["scalar"]).collect();
        assert!(!names.is_empty() && names.split(' ').all(|n| known.contains(&n)), "{text}");
        assert_eq!(names == "scalar", simd_paths().iter().all(|p| !p.1), "{text}");
    }
}
