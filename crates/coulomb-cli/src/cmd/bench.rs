//! `coulomb bench`.

/// Arguments of `coulomb bench`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `coulomb bench`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("coulomb bench is not available yet")
}
