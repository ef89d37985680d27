//! `meid completions` and `meid man`: shell completion scripts (clap_complete) and manual pages
//! (clap_mangen), generated from the command-line definition itself so they cannot drift.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::CommandFactory;
use clap_complete::Shell;

#[derive(clap::Args)]
pub struct CompletionsArgs {
    /// The shell. Install e.g. with `meid completions bash > ~/.local/share/bash-completion/completions/meid`,
    /// `meid completions zsh > ~/.zfunc/_meid` or `meid completions fish > ~/.config/fish/completions/meid.fish`.
    #[arg(value_enum)]
    shell: Shell,
}

/// Prints the completion script of `a.shell` on stdout.
pub fn completions(a: CompletionsArgs) -> Result<()> {
    let mut cmd = crate::Cli::command();
    let mut buf = Vec::new();
    clap_complete::generate(a.shell, &mut cmd, "meid", &mut buf);
    crate::ui::write_stdout_bytes(&buf);
    Ok(())
}

#[derive(clap::Args)]
pub struct ManArgs {
    /// The page of one subcommand (e.g. `simulate`: meid-simulate(1)); default: meid(1).
    #[arg(value_name = "SUBCOMMAND")]
    subcommand: Option<String>,
    /// Write every page (meid.1, meid-simulate.1, ...) into DIR instead of printing one.
    #[arg(short, long, value_name = "DIR")]
    output: Option<PathBuf>,
    /// With -o: do not print what was written.
    #[arg(short, long)]
    quiet: bool,
}

/// The page of `cmd` as roff.
fn render(man: clap_mangen::Man) -> Result<Vec<u8>> {
    let man = man.source(format!(
        "meid {} (commit {})",
        env!("CARGO_PKG_VERSION"),
        env!("MEID_GIT_COMMIT")
    ));
    let mut buf = Vec::new();
    man.render(&mut buf)
        .context("cannot render the manual page")?;
    Ok(buf)
}

/// Prints one manual page, or writes them all with `-o DIR`.
pub fn man(a: ManArgs) -> Result<()> {
    let mut cmd = crate::Cli::command().disable_help_subcommand(true);
    // Built, the subcommands are displayed as `meid-NAME`: their pages' titles and files.
    cmd.build();
    if let Some(dir) = &a.output {
        let mut written = Vec::new();
        let pages = std::iter::once(cmd.clone()).chain(cmd.get_subcommands().cloned());
        for page in pages {
            let man = clap_mangen::Man::new(page);
            let file = dir.join(man.get_filename());
            meid::io::write_atomic(&file, &render(man)?)?;
            written.push(file.display().to_string());
        }
        if !a.quiet {
            println!("wrote {}", written.join(", "));
        }
        return Ok(());
    }
    let page = match &a.subcommand {
        None => cmd,
        Some(name) => match cmd.find_subcommand(name) {
            Some(s) => s.clone(),
            None => {
                let names: Vec<&str> = cmd.get_subcommands().map(|s| s.get_name()).collect();
                bail!(
                    "meid man: no subcommand `{name}`; valid: {}",
                    names.join(", ")
                )
            }
        },
    };
    crate::ui::write_stdout_bytes(&render(clap_mangen::Man::new(page))?);
    Ok(())
}
