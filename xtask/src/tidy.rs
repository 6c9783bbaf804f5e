//! Tidy tests: rules about the source tree itself, checked by reading it
//! (in the spirit of rust-analyzer's `xtask/src/tidy.rs`). They run with the
//! workspace's tests (`cargo test --workspace`, so also `cargo xtask ci`).
//!
//! - every `.rs` file under `crates/`, `xtask/` and `fuzz/` opens with a
//!   `//!` line saying what it holds;
//! - no `#[ignore]` and no `should_panic` anywhere: a test runs, and says
//!   what it expects;
//! - only `crates/cli` prints or exits; library code returns values and
//!   errors (tests, examples, benchmarks, xtask and the listed exceptions
//!   may print);
//! - `unsafe` only in the listed places, each with a `// SAFETY:` comment
//!   just above it;
//! - no hand-written skips: a test that cannot run says so through
//!   `prism_testkit::skip`, which fails under `CI=true`, never with its
//!   own print and `return` (which would pass in CI);
//! - the crate layering, from `cargo metadata`, for every workspace crate.
//!
//! Each failure names the file and line (or the crate and dependency).
//! Each rule is a function of the sources it reads, and a self-test feeds
//! it a made-up file that breaks it, so that a rule which stopped
//! reporting would fail rather than pass in silence.

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Workspace crates each crate may depend on (normal and build
/// dependencies), lowest layer first: nothing points up. Dev-dependencies
/// may use these and `prism-testkit`. A crate missing here fails the test:
/// give it a row.
const LAYERS: &[(&str, &[&str])] = &[
    ("prism-geometry", &[]),
    ("prism-testkit", &["prism-geometry"]),
    ("prism-bvh", &["prism-geometry"]),
    ("prism-shade", &["prism-bvh", "prism-geometry"]),
    ("prism-scene", &["prism-shade", "prism-bvh", "prism-geometry"]),
    ("prism-view", &["prism-scene", "prism-shade", "prism-bvh", "prism-geometry"]),
    ("prism-cli", &["prism-view", "prism-scene", "prism-shade", "prism-bvh", "prism-geometry"]),
    // The benchmark harness measures the BVH; shared test support is fine.
    ("prism-bench", &["prism-bvh", "prism-geometry", "prism-testkit"]),
    // xtask drives the other crates through cargo, never links them.
    ("xtask", &[]),
];

/// The crates whose outside (crates.io) dependencies are fixed, and the list.
const EXTERNAL: &[(&str, &[&str])] = &[
    // The geometry kernel: vectors and nothing else.
    ("prism-geometry", &["glam"]),
    // The BVH: obvhs builds the trees, rayon builds them in parallel.
    ("prism-bvh", &["obvhs", "rayon"]),
];

/// Crate-source paths (a file, or a folder ending in `/`) outside `crates/cli`
/// that may print, and why. Everywhere else under `crates/*/src`, printing
/// is refused outside test code. Not checked at all, so free to print:
/// every crate's `tests/`, `examples/` and `benches/`, `#[cfg(test)]`
/// modules, `xtask/` (automation) and `fuzz/` (harnesses).
const MAY_PRINT: &[(&str, &str)] = &[
    ("crates/bench/src/", "the benchmark binary: its output is the measurements"),
    ("crates/testkit/src/", "test support: prints why a test skips itself"),
    (
        "crates/view/src/window.rs",
        "the viewer's window loop: reports saves, reloads and errors as they happen",
    ),
    (
        "crates/view/src/lib.rs",
        "the viewer prints the warnings of a scene it (re)loads while its window runs \
         (candidate to move to the caller), and defines errln!/outln!, its prints that \
         ignore a closed stream",
    ),
];

/// Where `unsafe` may appear at all (each still needs its `// SAFETY:`
/// comment): prism-bvh's ray queries (SIMD intrinsics, run-time selected
/// AVX2 walks). docs/fuzzing.md ("Unsafe code") lists them; keep it true.
const MAY_USE_UNSAFE: &[&str] = &["crates/bvh/src/"];

/// The macros that print.
const PRINTS: [&str; 5] = ["println", "eprintln", "print", "eprint", "dbg"];

/// What a line does that only the CLI may: print (a macro, or a handle on
/// stdout/stderr to write to) or end the process.
fn prints(line: &str) -> Option<&'static str> {
    if let Some(m) = PRINTS.iter().find(|m| has_token(line, m, Some('!'))) {
        return Some(m);
    }
    [("stdout", "stdout()"), ("stderr", "stderr()"), ("exit", "process::exit")]
        .into_iter()
        .find(|(f, _)| has_token(line, f, Some('(')) && (*f != "exit" || line.contains("process::exit")))
        .map(|(_, what)| what)
}

fn root() -> PathBuf {
    crate::project_root()
}

/// Every `.rs` file under `crates/`, `xtask/` and `fuzz/` (not build
/// output, fuzz corpora or hidden folders), relative to the root, sorted.
fn rust_files() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else { return };
        for e in entries.flatten() {
            let p = e.path();
            let name = e.file_name().to_string_lossy().into_owned();
            if p.is_dir() {
                if !(name.starts_with('.') || matches!(name.as_str(), "target" | "corpus" | "artifacts")) {
                    walk(&p, out);
                }
            } else if name.ends_with(".rs") {
                out.push(p);
            }
        }
    }
    let root = root();
    let mut files = Vec::new();
    for top in ["crates", "xtask", "fuzz"] {
        walk(&root.join(top), &mut files);
    }
    let mut files: Vec<PathBuf> =
        files.into_iter().filter_map(|p| p.strip_prefix(&root).ok().map(Path::to_path_buf)).collect();
    files.sort();
    files
}

/// A source file: its path (relative, with `/`), raw lines, and the same
/// lines with comments and the contents of string and character literals
/// blanked out, so that a word in a comment or a string is not code.
struct Source {
    path: String,
    raw: Vec<String>,
    code: Vec<String>,
}

impl Source {
    fn new(path: String, text: &str) -> Self {
        Source { path, raw: text.lines().map(str::to_string).collect(), code: strip(text) }
    }
}

fn read(rel: &Path) -> Source {
    let text = std::fs::read_to_string(root().join(rel))
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", rel.display()));
    Source::new(rel.to_string_lossy().replace('\\', "/"), &text)
}

/// The lines of `text` with comments and literal contents replaced by spaces
/// (string quotes kept). Handles line and nested block comments, escapes,
/// raw strings (`r#"…"#`) and tells character literals from lifetimes.
fn strip(text: &str) -> Vec<String> {
    #[derive(Clone, Copy, PartialEq)]
    enum State {
        Code,
        Line,
        Block(u32),
        Str,
        Raw(usize),
    }
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut state = State::Code;
    let mut i = 0;
    let blank = |c: char| if c == '\n' { '\n' } else { ' ' };
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        match state {
            State::Code => {
                let prev_ident = i > 0 && (chars[i - 1].is_alphanumeric() || chars[i - 1] == '_');
                if c == '/' && next == Some('/') {
                    state = State::Line;
                    out.push(' ');
                } else if c == '/' && next == Some('*') {
                    state = State::Block(1);
                    out.push_str("  ");
                    i += 1;
                } else if c == '"' {
                    state = State::Str;
                    out.push('"');
                } else if (c == 'r' || (c == 'b' && next == Some('r'))) && !prev_ident {
                    // r"…", r#"…"#, br"…"
                    let start = if c == 'b' { i + 2 } else { i + 1 };
                    let hashes = chars[start..].iter().take_while(|&&h| h == '#').count();
                    if chars.get(start + hashes) == Some(&'"') {
                        for _ in i..=start + hashes {
                            out.push(' ');
                        }
                        out.pop();
                        out.push('"');
                        i = start + hashes + 1;
                        state = State::Raw(hashes);
                        continue;
                    }
                    out.push(c);
                } else if c == '\'' {
                    // A character literal ('x', '\n', '\u{..}') or a lifetime ('a).
                    let end = if next == Some('\\') {
                        chars.get(i + 3..).and_then(|r| r.iter().position(|&q| q == '\'')).map(|p| i + 3 + p)
                    } else if chars.get(i + 2) == Some(&'\'') {
                        Some(i + 2)
                    } else {
                        None
                    };
                    match end {
                        Some(end) => {
                            out.push('\'');
                            for _ in i + 1..end {
                                out.push(' ');
                            }
                            out.push('\'');
                            i = end + 1;
                            continue;
                        }
                        None => out.push(c),
                    }
                } else {
                    out.push(c);
                }
            }
            State::Line => {
                if c == '\n' {
                    state = State::Code;
                }
                out.push(blank(c));
            }
            State::Block(depth) => {
                if c == '*' && next == Some('/') {
                    state = if depth == 1 { State::Code } else { State::Block(depth - 1) };
                    out.push_str("  ");
                    i += 1;
                } else if c == '/' && next == Some('*') {
                    state = State::Block(depth + 1);
                    out.push_str("  ");
                    i += 1;
                } else {
                    out.push(blank(c));
                }
            }
            State::Str => {
                if c == '\\' {
                    out.push(' ');
                    if let Some(n) = next {
                        out.push(blank(n));
                    }
                    i += 1;
                } else if c == '"' {
                    state = State::Code;
                    out.push('"');
                } else {
                    out.push(blank(c));
                }
            }
            State::Raw(hashes) => {
                if c == '"' && chars[i + 1..].iter().take(hashes).filter(|&&h| h == '#').count() == hashes {
                    out.push('"');
                    for _ in 0..hashes {
                        out.push(' ');
                    }
                    i += hashes + 1;
                    state = State::Code;
                    continue;
                }
                out.push(blank(c));
            }
        }
        i += 1;
    }
    out.lines().map(str::to_string).collect()
}

/// Whether `word` occurs in `line` as a whole identifier; if `then` is
/// given, the next non-space character after it must be `then`.
fn has_token(line: &str, word: &str, then: Option<char>) -> bool {
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    line.match_indices(word).any(|(at, _)| {
        let before = line[..at].chars().next_back();
        let mut after = line[at + word.len()..].chars();
        let first = after.clone().next();
        before.is_none_or(|c| !ident(c))
            && first.is_none_or(|c| !ident(c))
            && then.is_none_or(|t| after.find(|c| !c.is_whitespace()) == Some(t))
    })
}

/// Runs `check` on every Rust file and fails listing every complaint.
fn check_all(rule: &str, check: impl Fn(&Source, &mut Vec<String>)) {
    let mut problems = Vec::new();
    for rel in rust_files() {
        check(&read(&rel), &mut problems);
    }
    assert!(problems.is_empty(), "{rule}:\n{}", problems.join("\n"));
}

#[test]
fn the_tree_has_rust_files() {
    // The other rules pass trivially on an empty walk: make sure it is not empty.
    let files = rust_files();
    for must in ["xtask/src/tidy.rs", "crates/cli/src/main.rs", "crates/geometry/src/lib.rs"] {
        assert!(files.iter().any(|f| f == Path::new(must)), "the walk missed {must}: {files:?}");
    }
    assert!(files.iter().any(|f| f.starts_with("fuzz/fuzz_targets")), "the walk missed fuzz/");
}

/// Rule: the file opens with a `//!` line.
fn doc_line_rule(src: &Source, out: &mut Vec<String>) {
    if !src.raw.first().is_some_and(|l| l.starts_with("//!")) {
        out.push(format!("{}:1: no `//!` doc line", src.path));
    }
}

#[test]
fn every_file_opens_with_a_doc_line() {
    check_all("every .rs file must open with a `//!` line saying what it holds", doc_line_rule);
}

/// Rule: no `#[ignore]` attribute and no `should_panic`.
fn ignore_rule(src: &Source, out: &mut Vec<String>) {
    for (n, line) in src.code.iter().enumerate() {
        let attr = line.contains("#[") || line.contains("#![");
        if attr && has_token(line, "ignore", None) {
            out.push(format!("{}:{}: #[ignore]: {}", src.path, n + 1, src.raw[n].trim()));
        }
        if has_token(line, "should_panic", None) {
            out.push(format!("{}:{}: should_panic: {}", src.path, n + 1, src.raw[n].trim()));
        }
    }
}

#[test]
fn no_ignored_or_should_panic_tests() {
    check_all("no #[ignore] or should_panic: a test runs, and checks a result", ignore_rule);
}

/// Where a print that mentions skipping is not a test skipping itself:
/// the skip helper itself, and xtask's reports of peers it cannot find
/// (`cargo xtask bench --vs-peers` is a tool run, not a test).
const MAY_PRINT_SKIPS: &[&str] = &["crates/testkit/src/", "xtask/src/peers.rs"];

/// Rule: no print whose text says "skip" (the macro's arguments up to the
/// end of the statement, over up to four lines) outside
/// [`MAY_PRINT_SKIPS`]: a test that cannot run calls
/// `prism_testkit::skip`, which fails under `CI=true`.
fn skip_rule(src: &Source, out: &mut Vec<String>) {
    if MAY_PRINT_SKIPS.iter().any(|p| src.path.starts_with(p)) {
        return;
    }
    for (n, line) in src.code.iter().enumerate() {
        if prints(line).is_none() {
            continue;
        }
        let statement_end = (n..src.code.len().min(n + 4)).find(|&k| src.code[k].contains(';')).unwrap_or(n);
        let says_skip = src.raw[n..=statement_end].iter().any(|l| l.to_lowercase().contains("skip"));
        if says_skip {
            out.push(format!(
                "{}:{}: a hand-written skip (call prism_testkit::skip, which fails under CI): {}",
                src.path,
                n + 1,
                src.raw[n].trim()
            ));
        }
    }
}

#[test]
fn no_hand_written_skips() {
    check_all("tests skip only through prism_testkit::skip", skip_rule);
}

/// The `mod NAME;` declarations under `#[cfg(test)]` in `src`, as path
/// prefixes of the files they hold (`NAME.rs`, and everything in `NAME/`).
fn test_module_files(src: &Source) -> Vec<String> {
    let dir = match src.path.rsplit_once('/') {
        Some((dir, "lib.rs" | "main.rs" | "mod.rs")) => dir.to_string(),
        _ => src.path.trim_end_matches(".rs").to_string(),
    };
    let mut files = Vec::new();
    for pair in src.code.windows(2) {
        let decl = pair[1].trim();
        if pair[0].trim() == "#[cfg(test)]"
            && let Some(name) = decl.strip_prefix("mod ").and_then(|d| d.strip_suffix(';'))
        {
            files.push(format!("{dir}/{name}.rs"));
            files.push(format!("{dir}/{name}/"));
        }
    }
    files
}

#[test]
fn only_the_cli_prints() {
    let sources: Vec<Source> = rust_files().iter().map(|p| read(p)).collect();
    let problems = print_rule(&sources);
    assert!(
        problems.is_empty(),
        "only crates/cli prints or exits; libraries return values and errors (or add a justified entry to MAY_PRINT in xtask/src/tidy.rs):\n{}",
        problems.join("\n")
    );
}

/// Rule: library code under `crates/*/src` (not `crates/cli`, test
/// modules or [`MAY_PRINT`]) neither prints nor exits. Other files in
/// `sources` are not checked.
fn print_rule(sources: &[Source]) -> Vec<String> {
    let library = |p: &str| {
        p.starts_with("crates/") && p.split('/').nth(2) == Some("src") && !p.starts_with("crates/cli/")
    };
    let sources: Vec<&Source> = sources.iter().filter(|s| library(&s.path)).collect();
    let test_files: BTreeSet<String> = sources.iter().flat_map(|s| test_module_files(s)).collect();
    let mut problems = Vec::new();
    for src in sources {
        if test_files.iter().any(|t| src.path.starts_with(t.as_str()))
            || MAY_PRINT
                .iter()
                .any(|(p, _)| if p.ends_with('/') { src.path.starts_with(p) } else { src.path == *p })
        {
            continue;
        }
        for (n, line) in src.code.iter().enumerate() {
            // An inline `#[cfg(test)] mod NAME {` runs to the end of its file
            // (here test modules close their files).
            if line.trim() == "#[cfg(test)]"
                && src
                    .code
                    .get(n + 1)
                    .is_some_and(|l| l.trim_start().starts_with("mod ") && l.trim_end().ends_with('{'))
            {
                break;
            }
            if let Some(what) = prints(line) {
                problems.push(format!("{}:{}: {what}: {}", src.path, n + 1, src.raw[n].trim()));
            }
        }
    }
    problems
}

/// Rule: `unsafe` only under [`MAY_USE_UNSAFE`], each with a `// SAFETY:`
/// comment (or an `unsafe fn`'s `# Safety` doc) right above it.
fn unsafe_rule(src: &Source, out: &mut Vec<String>) {
    for (n, line) in src.code.iter().enumerate() {
        if !has_token(line, "unsafe", None) {
            continue;
        }
        // The comment and attribute lines right above; `# Safety` is the
        // doc section of an `unsafe fn`.
        let explained = src.raw[..n]
            .iter()
            .rev()
            .map(|l| l.trim())
            .take_while(|l| l.starts_with("//") || l.starts_with("#["))
            .any(|l| l.contains("SAFETY:") || l.contains("# Safety"));
        if !explained {
            out.push(format!(
                "{}:{}: unsafe without a SAFETY comment: {}",
                src.path,
                n + 1,
                src.raw[n].trim()
            ));
        }
        if !MAY_USE_UNSAFE.iter().any(|p| src.path.starts_with(p)) {
            out.push(format!(
                "{}:{}: unsafe outside {MAY_USE_UNSAFE:?} (add the place there and to docs/fuzzing.md, with why): {}",
                src.path,
                n + 1,
                src.raw[n].trim()
            ));
        }
    }
}

#[test]
fn unsafe_is_rare_and_explained() {
    check_all(
        "`unsafe` only where MAY_USE_UNSAFE allows, each with a `// SAFETY:` comment just above it (attributes may sit between)",
        unsafe_rule,
    );
}

/// A workspace crate and its declared dependencies.
struct Manifest {
    name: String,
    /// The `Cargo.toml`, relative to the root.
    path: String,
    /// `(dependency, kind)`: kind is `normal`, `dev` or `build`.
    deps: Vec<(String, String)>,
}

impl Manifest {
    /// `path:line` of the line declaring `dep` (`dep = …` or `dep.workspace = …`).
    fn place(&self, dep: &str) -> String {
        let text = std::fs::read_to_string(root().join(&self.path)).unwrap_or_default();
        let line = text.lines().position(|l| {
            l.trim_start().strip_prefix(dep).is_some_and(|rest| rest.trim_start().starts_with(['=', '.']))
        });
        line.map_or_else(|| self.path.clone(), |n| format!("{}:{}", self.path, n + 1))
    }
}

/// Every workspace member, from `cargo metadata --no-deps` (the manifests
/// as written, no resolution).
fn workspace_manifests() -> Vec<Manifest> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let out = std::process::Command::new(cargo)
        .args(["metadata", "--format-version", "1", "--no-deps", "--offline"])
        .current_dir(root())
        .output()
        .expect("run cargo metadata");
    assert!(out.status.success(), "cargo metadata failed: {}", String::from_utf8_lossy(&out.stderr));
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).expect("cargo metadata prints JSON");
    let packages = meta["packages"].as_array().expect("metadata has packages");
    packages
        .iter()
        .map(|p| {
            let name = p["name"].as_str().expect("a package name").to_string();
            let manifest = Path::new(p["manifest_path"].as_str().expect("a manifest path"));
            let path = manifest.strip_prefix(root()).unwrap_or(manifest).to_string_lossy().replace('\\', "/");
            let deps = p["dependencies"]
                .as_array()
                .expect("dependencies")
                .iter()
                .map(|d| {
                    let dep = d["name"].as_str().expect("a dependency name").to_string();
                    (dep, d["kind"].as_str().unwrap_or("normal").to_string())
                })
                .collect();
            Manifest { name, path, deps }
        })
        .collect()
}

#[test]
fn crate_layering_holds() {
    let crates = workspace_manifests();
    let members: BTreeSet<&str> = crates.iter().map(|m| m.name.as_str()).collect();
    assert!(members.contains("prism-geometry") && members.contains("prism-cli"), "members: {members:?}");
    let problems = layering_problems(&crates);
    assert!(problems.is_empty(), "crate layering (xtask/src/tidy.rs LAYERS):\n{problems}");
    // The geometry kernel's one dependency is really there (the walk saw the manifests).
    let geometry = crates.iter().find(|m| m.name == "prism-geometry").map(|m| &m.deps);
    assert!(geometry.is_some_and(|d| d.iter().any(|(n, k)| n == "glam" && k == "normal")), "{geometry:?}");
}

/// Rule: each crate depends only on what [`LAYERS`] and [`EXTERNAL`]
/// allow it, and every row of `LAYERS` names a member.
fn layering_problems(crates: &[Manifest]) -> String {
    let members: BTreeSet<&str> = crates.iter().map(|m| m.name.as_str()).collect();
    let mut problems = String::new();
    for manifest in crates {
        let (name, deps) = (&manifest.name, &manifest.deps);
        let Some((_, allowed)) = LAYERS.iter().find(|(c, _)| c == name) else {
            let _ = writeln!(
                problems,
                "{}: crate {name} is not in LAYERS (xtask/src/tidy.rs); say which crates it may use",
                manifest.path
            );
            continue;
        };
        let external = EXTERNAL.iter().find(|(c, _)| c == name).map(|(_, e)| *e);
        for (dep, kind) in deps {
            let ok = if members.contains(dep.as_str()) {
                allowed.contains(&dep.as_str()) || (kind == "dev" && dep == "prism-testkit")
            } else {
                kind == "dev" || external.is_none_or(|e| e.contains(&dep.as_str()))
            };
            if !ok {
                let _ = writeln!(
                    problems,
                    "{}: {name}'s {kind} dependency `{dep}` breaks the layering (allowed: {allowed:?}{})",
                    manifest.place(dep),
                    external.map(|e| format!(", outside the workspace only {e:?}")).unwrap_or_default()
                );
            }
        }
    }
    for (name, _) in LAYERS {
        if !members.contains(name) {
            let _ = writeln!(problems, "LAYERS names `{name}`, which is not a workspace member");
        }
    }
    problems
}

#[test]
fn the_stripper_hides_comments_and_literals_only() {
    let src = "let a = \"unsafe { println!() }\"; // should_panic\n\
               let b = r#\"#[ignore] \"quoted\"\"#; let c = '\"'; let d: &'static str = x;\n\
               /* outer /* inner */ still comment */ unsafe { f() }\n\
               let s = \"two\nlines\"; dbg!(s);\n\
               let q = '\\''; let w = \"unsafe\"; let x = b'\"'; unsafe_fn();\n";
    let lines = strip(src);
    assert_eq!(lines.len(), 6, "{lines:?}");
    assert!(!lines[0].contains("unsafe") && !lines[0].contains("should_panic") && lines[0].contains("let a"));
    assert!(!lines[1].contains("ignore") && lines[1].contains("let c") && lines[1].contains("&'static str"));
    assert!(has_token(&lines[2], "unsafe", None) && !lines[2].contains("comment"));
    // A string over two lines stays blank on both.
    assert!(lines[3].contains("let s") && !lines[3].contains("two"));
    assert!(!lines[4].contains("lines") && has_token(&lines[4], "dbg", Some('!')));
    assert!(
        lines[5].contains("let w") && lines[5].contains("unsafe_fn") && !has_token(&lines[5], "unsafe", None)
    );
    // Whole identifiers only, and the `!` of a macro.
    assert!(!has_token("eprintln!(x)", "println", Some('!')));
    assert!(has_token("eprintln !(x)", "eprintln", Some('!')));
    assert!(!has_token("w.print(x)", "print", Some('!')));
    assert!(!has_token("#![forbid(unsafe_code)]", "unsafe", None));
    // What counts as printing.
    assert_eq!(prints("    eprintln!(\"{x}\");"), Some("eprintln"));
    assert_eq!(prints("let _ = writeln!(std::io::stderr(), \"x\");"), Some("stderr()"));
    assert_eq!(prints("std::process::exit(2);"), Some("process::exit"));
    assert_eq!(prints("let printed = self.exit(); fmt.print_stats(x);"), None);
}

#[test]
fn test_modules_are_found() {
    let lib = Source::new("crates/x/src/lib.rs".into(), "//! x\n#[cfg(test)]\nmod tests;\nmod real;\n");
    assert_eq!(test_module_files(&lib), ["crates/x/src/tests.rs", "crates/x/src/tests/"]);
    let walk =
        Source::new("crates/x/src/walk.rs".into(), "#[cfg(test)]\nmod checks;\n#[cfg(test)]\nmod t {}\n");
    assert_eq!(test_module_files(&walk), ["crates/x/src/walk/checks.rs", "crates/x/src/walk/checks/"]);
}

/// A rule checked one file at a time.
type FileRule = fn(&Source, &mut Vec<String>);

/// Runs a per-file rule on one made-up file.
fn complaints(rule: FileRule, path: &str, text: &str) -> Vec<String> {
    let mut out = Vec::new();
    rule(&Source::new(path.into(), text), &mut out);
    out
}

#[test]
fn each_rule_reports_what_breaks_it() {
    // Each rule against a file that breaks it (it must name the file and
    // line) and one that keeps it (it must say nothing).
    let cases: [(FileRule, &str, &str, &str, &str); 7] = [
        (doc_line_rule, "crates/x/src/a.rs", "use x;\n", "crates/x/src/a.rs:1:", "//! A.\nuse x;\n"),
        (
            ignore_rule,
            "crates/x/tests/t.rs",
            "//! T.\n#[test]\n#[ignore]\nfn t() {}\n",
            "crates/x/tests/t.rs:3:",
            "//! T.\n#[test]\nfn t() {} // #[ignore]\n",
        ),
        (
            ignore_rule,
            "crates/x/tests/t.rs",
            "//! T.\n#[test]\n#[should_panic]\nfn t() {}\n",
            "crates/x/tests/t.rs:3:",
            "//! T.\nlet s = \"should_panic\";\n",
        ),
        (
            unsafe_rule,
            "crates/bvh/src/w.rs",
            "//! W.\nfn f() {\n    unsafe { g() }\n}\n",
            "crates/bvh/src/w.rs:3:",
            "//! W.\n// SAFETY: g has no preconditions.\nunsafe { g() }\n",
        ),
        (
            unsafe_rule,
            "crates/shade/src/w.rs",
            "//! W.\n// SAFETY: no preconditions.\nunsafe { g() }\n",
            "crates/shade/src/w.rs:3: unsafe outside",
            "//! W.\nlet s = \"unsafe\";\n",
        ),
        (
            skip_rule,
            "crates/x/tests/t.rs",
            "//! T.\nif !found {\n    eprintln!(\"Skipping: no mesh\");\n    return;\n}\n",
            "crates/x/tests/t.rs:3:",
            "//! T.\nif !found {\n    prism_testkit::skip(\"no mesh\");\n    return;\n}\n",
        ),
        (
            skip_rule,
            "crates/x/src/lib.rs",
            "//! T.\nprintln!(\n    \"{} {}\",\n    \"skipped\", why\n);\n",
            "crates/x/src/lib.rs:2:",
            "//! T.\nprintln!(\"{}\", why);\nlet skip = 3;\n",
        ),
    ];
    for (rule, path, bad, expected, good) in cases {
        let found = complaints(rule, path, bad);
        assert!(found.len() == 1 && found[0].starts_with(expected), "{expected}: {found:?}");
        assert_eq!(complaints(rule, path, good), Vec::<String>::new(), "{path}: {good}");
    }
    // The skip helper itself may print its skips.
    assert!(
        complaints(skip_rule, "crates/testkit/src/lib.rs", "//! K.\neprintln!(\"skipped: {why}\");\n")
            .is_empty()
    );

    // Printing: a library file, its test module, the CLI.
    let sources = [
        Source::new("crates/shade/src/a.rs".into(), "//! A.\nfn f() {\n    println!(\"x\");\n}\n"),
        Source::new(
            "crates/shade/src/b.rs".into(),
            "//! B.\n#[cfg(test)]\nmod tests {\n    fn t() { dbg!(1); }\n}\n",
        ),
        Source::new("crates/cli/src/main.rs".into(), "//! M.\nfn main() { std::process::exit(2); }\n"),
        Source::new("crates/shade/tests/t.rs".into(), "//! T.\nfn t() { println!(\"x\"); }\n"),
    ];
    let found = print_rule(&sources);
    assert!(found.len() == 1 && found[0].starts_with("crates/shade/src/a.rs:3: println"), "{found:?}");

    // Layering: geometry may not use shade, nor any crate but glam.
    let manifest = |name: &str, deps: &[(&str, &str)]| Manifest {
        name: name.into(),
        path: format!("crates/{name}/Cargo.toml"),
        deps: deps.iter().map(|(d, k)| (d.to_string(), k.to_string())).collect(),
    };
    let mut crates: Vec<Manifest> = LAYERS.iter().map(|(name, _)| manifest(name, &[])).collect();
    assert_eq!(layering_problems(&crates), "");
    crates[0] =
        manifest("prism-geometry", &[("glam", "normal"), ("prism-shade", "normal"), ("rand", "normal")]);
    let found = layering_problems(&crates);
    assert!(
        found.lines().count() == 2
            && found.contains("`prism-shade` breaks")
            && found.contains("`rand` breaks"),
        "{found}"
    );
    crates[0] = manifest("prism-geometry", &[("glam", "normal"), ("proptest", "dev")]);
    crates.push(manifest("prism-extra", &[]));
    let found = layering_problems(&crates);
    assert!(found.lines().count() == 1 && found.contains("prism-extra is not in LAYERS"), "{found}");
}
