//! `prism completions SHELL` (a completion script on standard output, by
//! clap_complete) and the hidden `prism man DIR` behind `cargo xtask man`
//! (one roff page per command, by clap_mangen).

use anyhow::{Context, Result};
use clap::Args;
use clap_complete::Shell;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct CompletionsArgs {
    /// The shell: bash, zsh, fish (also elvish, powershell).
    #[arg(value_enum)]
    shell: Shell,
}

#[derive(Args)]
pub struct ManArgs {
    /// The directory to write `prism.1`, `prism-render.1`, … into (created).
    dir: PathBuf,
}

/// The completion script of `cmd` for `shell`, without its hidden
/// subcommands (`man`; clap_complete would offer them).
pub fn script(cmd: &mut clap::Command, shell: Shell) -> Vec<u8> {
    let mut visible = clap::Command::new("prism")
        .version(env!("CARGO_PKG_VERSION"))
        .subcommands(cmd.get_subcommands().filter(|s| !s.is_hide_set()).cloned())
        .args(cmd.get_arguments().filter(|a| !a.is_hide_set()).cloned());
    let mut out = Vec::new();
    clap_complete::generate(shell, &mut visible, "prism", &mut out);
    out
}

/// Prints the completion script for `args.shell` to standard output.
pub fn completions_command(args: &CompletionsArgs, mut cmd: clap::Command) -> Result<()> {
    crate::write_stdout(&script(&mut cmd, args.shell), "the completion script")
}

/// Writes one man page per visible command of `cmd` into `args.dir`, and
/// prints the files written.
pub fn man_command(args: &ManArgs, cmd: clap::Command) -> Result<()> {
    std::fs::create_dir_all(&args.dir).with_context(|| format!("cannot create {}", args.dir.display()))?;
    clap_mangen::generate_to(cmd, &args.dir)
        .with_context(|| format!("cannot write man pages into {}", args.dir.display()))?;
    for page in pages(&args.dir)? {
        outln!("wrote {}", page.display());
    }
    Ok(())
}

/// The `*.1` files in `dir`, sorted.
fn pages(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut v = Vec::new();
    for e in std::fs::read_dir(dir).with_context(|| format!("cannot list {}", dir.display()))? {
        let p = e?.path();
        if p.extension().is_some_and(|x| x == "1") {
            v.push(p);
        }
    }
    v.sort();
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cmd() -> clap::Command {
        clap::Command::new("prism")
            .subcommand(clap::Command::new("render").arg(clap::Arg::new("spp").long("spp")))
            .subcommand(clap::Command::new("secret-pages").hide(true))
    }

    #[test]
    fn each_shell_gets_a_script_naming_the_subcommands() {
        for shell in [Shell::Bash, Shell::Zsh, Shell::Fish] {
            let s = String::from_utf8(script(&mut cmd(), shell)).unwrap();
            assert!(s.contains("render") && s.contains("spp"), "{shell}: {s}");
            // A hidden subcommand is not offered.
            assert!(!s.contains("secret"), "{shell}: {s}");
        }
    }
}
