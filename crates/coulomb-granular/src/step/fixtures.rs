//! Step problems shared by the unit tests of the step's phases (compiled for tests only).

use crate::assembly::StepData;
use crate::contact::{detect, Activation};
use crate::math::Vec3;
use crate::nsgs::StepProblem;
use crate::world::{Obstacle, Shape, Sphere, World};

/// A `nx × ny × layers` simple-cubic stack of touching spheres at rest on a floor, and its
/// step problem (h = 0.02, μ = 0.5, e = 0) with the spheres' centres (for the grid coarse
/// space): gravity's load goes straight down through every column.
pub(crate) fn stack(nx: usize, ny: usize, layers: usize) -> StepProblem {
    let mut w = World::new();
    w.obstacles.push(Obstacle::fixed(
        "ground",
        Shape::Plane {
            point: Vec3::ZERO,
            normal: Vec3::Z,
        },
    ));
    let r = 0.05;
    for k in 0..layers {
        for j in 0..ny {
            for i in 0..nx {
                let p = Vec3::new(
                    2.0 * r * i as f64,
                    2.0 * r * j as f64,
                    r + 2.0 * r * k as f64,
                );
                w.bodies.push(Sphere::new(p, r, 1.0));
            }
        }
    }
    let contacts = detect(&w, 0.0, 0.02, &Activation::accurate());
    let data = StepData {
        h: 0.02,
        t_end: 0.02,
        restitution: 0.0,
        mu: 0.5,
        close_gaps: true,
    };
    StepProblem::new(&w, &contacts, &data)
        .unwrap()
        .with_positions(&w)
}
