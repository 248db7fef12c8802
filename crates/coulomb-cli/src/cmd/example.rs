//! `coulomb example`.

/// Arguments of `coulomb example`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `coulomb example`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("coulomb example is not available yet")
}
