//! `coulomb check`.

/// Arguments of `coulomb check`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `coulomb check`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("coulomb check is not available yet")
}
