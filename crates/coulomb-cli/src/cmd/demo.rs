//! `coulomb demo`.

/// Arguments of `coulomb demo`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `coulomb demo`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("coulomb demo is not available yet")
}
