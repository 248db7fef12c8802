//! `coulomb info`.

/// Arguments of `coulomb info`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `coulomb info`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("coulomb info is not available yet")
}
