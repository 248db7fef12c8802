//! Issue 52, bug (4): in a packed column of beads at rest, the contact impulses the step
//! exports (those of `Simulation::contacts`, written as forces to the contact frames) carry the
//! whole weight: Σ over the floor and wall contacts of the impulses' vertical component equals
//! M |g| h. The position correction moves centres only and must not carry weight.

use coulomb::{InnerKind, Method, MethodParams, OuterKind, Settings};
use coulomb_granular::contact::Partner;
use coulomb_granular::math::Vec3;
use coulomb_granular::projection::Velocities;
use coulomb_granular::world::{Obstacle, Shape, Sphere, World};
use coulomb_granular::{Activation, NsgsSettings, Params, Projection, Simulation, StepMethod};

fn params(projection: Option<Projection>, tol: f64) -> Params {
    let d = Settings::time_stepping(Method::new(InnerKind::Pgs, Settings::default().outer));
    let solver = Settings {
        tol,
        max_outer: 20,
        params: MethodParams {
            fixed_point_tol: None,
            ..d.params
        },
        outer: OuterKind::Fused,
        fallback: Some((InnerKind::Apgd, OuterKind::Anderson)),
        ..d
    };
    Params {
        h: 0.02,
        theta: 0.5,
        restitution: 0.2,
        mu: 0.3,
        activation: Activation {
            gamma: 1.0,
            close_gaps: true,
            ..Activation::accurate()
        },
        solver,
        warm_start: true,
        projection,
        method: StepMethod::Nsgs(NsgsSettings {
            tol,
            max_sweeps: 20_000,
            relaxation: 1.5,
            ..NsgsSettings::default()
        }),
        rolling_friction: 0.0,
    }
}

/// A square tube 3 diameters wide (a floor and four walls) holding `layers` layers of beads
/// (R = 5 cm, 1.3 kg), alternately 3 × 3 beads touching each other and the walls and 2 × 2
/// beads in their hollows, √2 R apart vertically: every bead touches its neighbours (gap 0),
/// a stable packing.
fn packed_column(layers: usize) -> World {
    let r = 0.05;
    let side = 6.0 * r;
    let mut w = World::new();
    let plane = |p: Vec3, n: Vec3| Shape::Plane {
        point: p,
        normal: n,
    };
    w.obstacles
        .push(Obstacle::fixed("floor", plane(Vec3::ZERO, Vec3::Z)));
    w.obstacles
        .push(Obstacle::fixed("x0", plane(Vec3::ZERO, Vec3::X)));
    w.obstacles.push(Obstacle::fixed(
        "x1",
        plane(Vec3::new(side, 0.0, 0.0), -Vec3::X),
    ));
    w.obstacles
        .push(Obstacle::fixed("y0", plane(Vec3::ZERO, Vec3::Y)));
    w.obstacles.push(Obstacle::fixed(
        "y1",
        plane(Vec3::new(0.0, side, 0.0), -Vec3::Y),
    ));
    for layer in 0..layers {
        let z = r + layer as f64 * 2f64.sqrt() * r;
        let (n, first) = if layer % 2 == 0 { (3, r) } else { (2, 2.0 * r) };
        for i in 0..n {
            for j in 0..n {
                let p = Vec3::new(first + 2.0 * r * i as f64, first + 2.0 * r * j as f64, z);
                w.bodies.push(Sphere::new(p, r, 1.3));
            }
        }
    }
    w
}

/// What a run measured over its last `last` steps.
struct Balance {
    /// mean over the steps of (Σ obstacle impulses' z) / (M |g| h)
    mean: f64,
    /// largest |(Σ obstacle impulses' z) − (M |g| h + ΔP_z)| / (M |g| h) of one step
    momentum_residual: f64,
    /// position-correction sweeps done
    sweeps: usize,
}

fn balance(
    world: World,
    projection: Option<Projection>,
    tol: f64,
    steps: usize,
    last: usize,
) -> Balance {
    let mut sim = Simulation::new(world, params(projection, tol)).unwrap();
    let h = sim.params.h;
    let weight: f64 =
        sim.world.bodies.iter().map(|b| b.mass).sum::<f64>() * sim.world.gravity.norm();
    let momentum = |sim: &Simulation| -> f64 {
        sim.world
            .bodies
            .iter()
            .map(|b| b.mass * b.velocity.z)
            .sum::<f64>()
    };
    let mut out = Balance {
        mean: 0.0,
        momentum_residual: 0.0,
        sweeps: 0,
    };
    for k in 0..steps {
        let p0 = momentum(&sim);
        let s = sim.step().unwrap();
        if k + last < steps {
            continue;
        }
        let dp = momentum(&sim) - p0;
        let up: f64 = sim
            .contacts
            .iter()
            .filter(|c| matches!(c.partner, Partner::Obstacle(..)))
            .map(|c| c.world_impulse().z)
            .sum();
        out.mean += up / (weight * h) / last as f64;
        out.momentum_residual = out
            .momentum_residual
            .max((up - weight * h - dp).abs() / (weight * h));
        out.sweeps += s.projection_sweeps;
    }
    out
}

/// The packed column of 20 layers with the correction `projection` solved to `tol`, 150
/// steps: the correction acts, the floor and walls carry the weight over the last 100 to `mean`
/// (|mean Σ r_z / (M g h) − 1|) and every one of those steps balances to `step` (the largest
/// momentum residual, / (M g h)).
fn check_balance(projection: Projection, tol: f64, mean: f64, step: f64) {
    let b = balance(packed_column(20), Some(projection), tol, 150, 100);
    eprintln!(
        "tol {tol:e}: mean Σ r_z / (M g h) = {:.6}, largest momentum residual {:.2e}, {} correction sweeps",
        b.mean, b.momentum_residual, b.sweeps
    );
    assert!(
        b.sweeps > 0,
        "the correction never acted: the test tests nothing"
    );
    assert!((b.mean - 1.0).abs() <= mean, "tol {tol:e}: {:.6}", b.mean);
    assert!(
        b.momentum_residual <= step,
        "tol {tol:e}: {:e}",
        b.momentum_residual
    );
}

/// Runs the packed column of 130 beads at rest with the correction `projection`, solved to
/// 10⁻² and 10⁻³ (the solver's residual lets it sink, so that the correction acts every few
/// steps), and checks that over the last 100 of 150 steps the floor and walls carry the weight,
/// Σ_steps Σ_obstacles r_z = 100 M |g| h, to 0.1 % (the mean differs from 1 by the column's
/// change of momentum over the 100 steps divided by 100 M |g| h, a few 10⁻⁵ here: the column is
/// at rest), and that every step obeys the momentum balance Σ r_z = M |g| h + ΔP_z exactly (to
/// round-off): the correction changes no velocity.
fn check_the_column_balances(projection: Projection) {
    for tol in [1e-2, 1e-3] {
        check_balance(projection, tol, 1e-3, 1e-9);
    }
    // without the correction, the same balance
    let b = balance(packed_column(20), None, 1e-2, 150, 100);
    assert!((b.mean - 1.0).abs() <= 1e-3, "no correction: {:.6}", b.mean);
}

/// The default correction (`Projection::default()`, which rescales the velocities of the
/// beads it moves to balance their potential energy) must carry no weight. Measured: mean
/// 0.982 at 10⁻² (docs/granular.md, "Position correction"). Ignored while the default keeps the
/// rescaling: the positions-only correction and the inelastic velocity projection (next tests)
/// balance, but `coulomb validate` then fails Beverloo's check (and with positions only the
/// column collapse too; measured, docs/granular.md, "Issue 52, bug 4").
#[test]
#[ignore = "issue 52 bug 4, open at loose tolerances: the default correction's velocity rescaling carries the residual the tolerance leaves, 1.8 % of the weight at 1e-2, 0.15 % at 1e-3 (0.001 % at the default 1e-4: the test above); the positions-only and inelastic variants balance (tests below) but positions-only fails validate's column collapse (runout 2.877 > 2.826) and Beverloo (C = 1.47), the inelastic one Beverloo (C = 0.774 > 0.7): docs/granular.md, \"Issue 52, bug 4\""]
fn a_packed_column_at_rest_puts_its_whole_weight_on_the_floor_and_walls() {
    check_the_column_balances(Projection::default());
}

/// At the default tolerance the default correction carries the weight to the solver's
/// residual: what the rescaling takes is the sinking velocity the solve leaves (its error, at
/// most the tolerance), so the weight it carries falls with the tolerance (mean Σ r_z / (M g h)
/// 0.982 at 10⁻², 0.9985 at 10⁻³, 0.99999 at 10⁻⁴ on this column; 0.99998 and 0.99995 on 40 and
/// 80 layers at 10⁻⁴: docs/granular.md, "Issue 52, bug 4"). The column of 20 layers, solved to
/// the step's default tolerance (`NsgsSettings::default().tol`): over the last 100 of 150 steps
/// the floor and walls carry the weight to 10⁻⁴, and no single step's balance is off by more
/// than 10⁻³ of the weight (measured 4.0·10⁻⁴), with the correction acting.
#[test]
fn at_the_default_tolerance_the_default_correction_leaves_the_weight_on_the_floor_and_walls() {
    check_balance(
        Projection::default(),
        NsgsSettings::default().tol,
        1e-4,
        1e-3,
    );
}

/// The positions-only correction (`Velocities::PositionsOnly`: centres moved, velocities
/// untouched) carries no weight. Measured: mean 1.000093 at 10⁻², 0.999994 at 10⁻³, momentum
/// residual ≤ 2.2·10⁻¹⁵.
#[test]
fn the_positions_only_correction_puts_the_whole_weight_on_the_floor_and_walls() {
    check_the_column_balances(Projection {
        velocities: Velocities::PositionsOnly,
        ..Projection::default()
    });
}

/// The same property on the rigid-body engine, whose position correction moves positions only
/// (`RigidSettings::position_correction`): a pyramid of 14 cubes (3 layers, each cube on four)
/// on the floor, each step solved to 10⁻⁴ or to the default 10⁻⁸: every step Σ floor r_z =
/// M |g| h + ΔP_z to round-off, and over the last 100 of 150 steps the floor carries the
/// weight, mean Σ r_z / (M |g| h) = 1 to 10⁻³. The correction does not act here: the rigid
/// activation keeps penetrations at 2·10⁻⁸ m (10⁻⁴) and 3·10⁻¹² m (10⁻⁸), far below its trigger
/// (10⁻³ of the half width, 5·10⁻⁵ m; a drop from 15 cm ends 5.5·10⁻⁶ m deep), so this checks
/// the exported impulses, not the correction.
#[test]
fn a_pyramid_of_boxes_puts_its_whole_weight_on_the_floor() {
    use coulomb_granular::rigid::validation::{cube_pyramid, floor, one_material};
    use coulomb_granular::rigid::{RigidSettings, RigidWorld};
    for tol in [1e-4, 1e-8] {
        let settings = RigidSettings {
            tolerance: tol,
            ..RigidSettings::default()
        };
        let (h, g) = (settings.h, settings.gravity[2].abs());
        let mut w = RigidWorld::new(
            cube_pyramid(3).unwrap(),
            vec![floor()],
            one_material(0.5),
            settings,
        )
        .unwrap();
        let weight = w.masses().iter().sum::<f64>() * g;
        let momentum = |w: &RigidWorld| -> f64 {
            w.masses()
                .iter()
                .zip(w.velocities())
                .map(|(m, v)| m * v[2])
                .sum()
        };
        let (steps, last) = (150, 100);
        let (mut mean, mut worst, mut deepest) = (0.0, 0.0f64, 0.0f64);
        for k in 0..steps {
            let p0 = momentum(&w);
            let r = w.step().unwrap();
            deepest = deepest.max(r.max_penetration);
            if k + last < steps {
                continue;
            }
            let up: f64 = w
                .contacts()
                .iter()
                .filter(|c| matches!(c.partner, Partner::Obstacle(_, _)))
                .map(|c| c.world_impulse().z)
                .sum();
            let dp = momentum(&w) - p0;
            mean += up / (weight * h) / last as f64;
            worst = worst.max((up - weight * h - dp).abs() / (weight * h));
        }
        eprintln!(
            "rigid, tol {tol:e}: mean Σ r_z / (M g h) = {mean:.6}, largest momentum residual {worst:.2e}, deepest penetration at a step start {deepest:.2e} m"
        );
        assert!((mean - 1.0).abs() <= 1e-3, "tol {tol:e}: {mean:.6}");
        assert!(worst <= 1e-9, "tol {tol:e}: {worst:e}");
    }
}

/// Moreau's inelastic velocity projection on the corrected contacts
/// (`Velocities::Inelastic`), its impulses added to the exported ones, carries no weight:
/// the momentum balance holds to round-off at every step. Measured: mean 1.000019 at 10⁻²,
/// 0.999997 at 10⁻³ (docs/granular.md, "Issue 52, bug 4").
#[test]
fn the_inelastic_velocity_projection_puts_the_whole_weight_on_the_floor_and_walls() {
    check_the_column_balances(Projection {
        velocities: Velocities::Inelastic,
        ..Projection::default()
    });
}

/// The setting reaches the step from a scene file (`[step] projection_velocities`, the same
/// `Velocities` as the CLI's `--projection-velocities` and Python's `projection_velocities=`),
/// and is refused, naming the key, when the file turns the correction off.
#[test]
fn a_scene_file_chooses_what_the_correction_does_to_velocities() {
    use coulomb_granular::scene_file::{BuildOptions, LoadedScene};
    let params = |step: &str| {
        let text = format!(
            "[step]\nsteps = 1\n{step}\n\
             [[obstacles]]\nname = \"floor\"\nshape = {{ kind = \"plane\", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}\n\
             [[bodies]]\nspheres = [[0.0, 0.0, 0.1, 0.1]]\n"
        );
        LoadedScene::parse(std::path::Path::new("s.toml"), text, true)
            .and_then(|s| s.build(&BuildOptions::default()))
            .and_then(|b| b.build(&Default::default()))
            .map(|(_, p)| p.projection)
            .map_err(|e| e.to_string())
    };
    let velocities = |step: &str| params(step).unwrap().map(|p| p.velocities);
    assert_eq!(velocities(""), Some(Velocities::Rescale));
    for (name, v) in [
        ("rescale", Velocities::Rescale),
        ("positions_only", Velocities::PositionsOnly),
        ("inelastic", Velocities::Inelastic),
    ] {
        let line = format!("projection_velocities = \"{name}\"");
        assert_eq!(velocities(&line), Some(v));
    }
    let e = params("projection = false\nprojection_velocities = \"inelastic\"").unwrap_err();
    assert!(e.contains("projection_velocities"), "{e}");
    // an unknown variant: refused at the value's line and column, naming the variants
    let e = params("projection_velocities = \"elastic\"").unwrap_err();
    assert!(
        e.contains("s.toml:3:25") && e.contains("positions_only"),
        "{e}"
    );
}
