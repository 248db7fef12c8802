//! `coulomb example {painleve, rectangle, crushed-ball, moving-obstacle}`: writes one of the
//! paper's examples as an FCLIB global problem and prints what the existence check says.

use coulomb::examples;
use coulomb::existence::{self, CheckSettings};
use coulomb::fclib::FclibFile;
use coulomb::{GlobalProblem, Problem};
use std::path::{Path, PathBuf};

/// Arguments of `coulomb example`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub which: Which,
}

/// The examples.
#[derive(clap::Subcommand, Debug)]
pub enum Which {
    /// Painlevé's rod (2.12), §2.2 and §5.2–§5.4 (m = l = h = 1, v0 = 0)
    Painleve {
        /// rod angle θ in degrees, in ]0, 90[
        #[arg(long, value_parser = crate::values::finite)]
        theta: f64,
        /// friction coefficient μ
        #[arg(long, value_parser = crate::values::nonnegative)]
        mu: f64,
        /// velocity u0 of the pivot A along Ox
        #[arg(long, allow_hyphen_values = true, value_parser = crate::values::finite)]
        u0: f64,
        /// gravity along Oy (g > 0: upwards; Example 2.1 has g = −1)
        #[arg(long, default_value_t = -1.0, allow_hyphen_values = true, value_parser = crate::values::finite)]
        g: f64,
        /// output FCLIB file
        #[arg(long)]
        output: PathBuf,
    },
    /// Fig. 7: a rigid rectangle on two circular supports, the right one moving; (5.1) holds
    Rectangle {
        /// friction coefficient μ
        #[arg(long, default_value_t = 0.3, value_parser = crate::values::nonnegative)]
        mu: f64,
        /// velocity of the right support along x
        #[arg(long, default_value_t = 0.0, allow_hyphen_values = true, value_parser = crate::values::finite)]
        sx: f64,
        /// velocity of the right support along y
        #[arg(long, default_value_t = -0.1, allow_hyphen_values = true, value_parser = crate::values::finite)]
        sy: f64,
        /// output FCLIB file
        #[arg(long)]
        output: PathBuf,
    },
    /// Fig. 3: a ball crushed between the ground and a plane moving towards it; no solution
    CrushedBall {
        /// friction coefficient μ
        #[arg(long, default_value_t = 0.3, value_parser = crate::values::nonnegative)]
        mu: f64,
        /// speed of the plane towards the ground
        #[arg(long, default_value_t = 1.0, allow_hyphen_values = true, value_parser = crate::values::finite)]
        u0: f64,
        /// output FCLIB file
        #[arg(long)]
        output: PathBuf,
    },
    /// §5.6: three discs in a box moving as a rigid body; (4.4) holds
    MovingObstacle {
        /// friction coefficient μ
        #[arg(long, default_value_t = 0.3, value_parser = crate::values::nonnegative)]
        mu: f64,
        /// box velocity along x
        #[arg(long, default_value_t = 0.0, allow_hyphen_values = true, value_parser = crate::values::finite)]
        vx: f64,
        /// box velocity along y
        #[arg(long, default_value_t = 0.0, allow_hyphen_values = true, value_parser = crate::values::finite)]
        vy: f64,
        /// box angular velocity about its centre
        #[arg(long, default_value_t = 0.0, allow_hyphen_values = true, value_parser = crate::values::finite)]
        omega: f64,
        /// output FCLIB file
        #[arg(long)]
        output: PathBuf,
    },
}

/// Runs `coulomb example`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let (name, problem, output) = build(args.which)?;
    crate::outputs::check("--output", &output, &[])?;
    write_global(&output, &problem)?;
    let report = existence::check(&Problem::Global(problem.clone()), &CheckSettings::default())?;
    let by = match &report.conclusion {
        existence::Conclusion::Exists { by, theorem }
        | existence::Conclusion::None { by, theorem } => {
            format!(" by {by} ({theorem})")
        }
        existence::Conclusion::Unknown => String::new(),
    };
    println!(
        "wrote {name} to {} ({} dofs, {} contacts); existence: {}{by}",
        output.display(),
        problem.dofs(),
        problem.contacts(),
        report.conclusion.label(),
    );
    Ok(())
}

/// Builds the requested example.
pub fn build(which: Which) -> anyhow::Result<(&'static str, GlobalProblem, PathBuf)> {
    Ok(match which {
        Which::Painleve {
            theta,
            mu,
            u0,
            g,
            output,
        } => {
            if !(theta > 0.0 && theta < 90.0) {
                anyhow::bail!("--theta {theta}: the rod angle must be in ]0, 90[ degrees");
            }
            (
                "painleve",
                examples::painleve(theta.to_radians(), mu, u0, g)?,
                output,
            )
        }
        Which::Rectangle { mu, sx, sy, output } => {
            ("rectangle", examples::rectangle(mu, [sx, sy])?, output)
        }
        Which::CrushedBall { mu, u0, output } => {
            ("crushed-ball", examples::crushed_ball(mu, u0)?, output)
        }
        Which::MovingObstacle {
            mu,
            vx,
            vy,
            omega,
            output,
        } => (
            "moving-obstacle",
            examples::moving_obstacle(mu, [vx, vy], omega)?,
            output,
        ),
    })
}

/// Writes a global problem as FCLIB.
fn write_global(path: &Path, problem: &GlobalProblem) -> anyhow::Result<()> {
    let file = FclibFile::new(Problem::Global(problem.clone()));
    crate::outputs::write_fclib(path, &file)?;
    Ok(())
}
