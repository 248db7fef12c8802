//! `coulomb paper`.

/// Arguments of `coulomb paper`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `coulomb paper`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("coulomb paper is not available yet")
}
