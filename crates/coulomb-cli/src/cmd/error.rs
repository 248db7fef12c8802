//! `coulomb error`.

/// Arguments of `coulomb error`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `coulomb error`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("coulomb error is not available yet")
}
