//! Scenes of §6 and beyond: beads in a box (Table 1, Fig. 8, Fig. 9), a funnel over a floor,
//! a vertically vibrating plate, a rotating drum. Every scene is deterministic for a seed
//! (ChaCha8).

use crate::math::Vec3;
use crate::model::{ObstacleSpec, SceneModel, SphereBatch, DEFAULT_MATERIAL};
use crate::world::{Motion, Shape, Sphere, World};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

/// Bead radius of every scene (m).
pub const BEAD_RADIUS: f64 = 0.05;
/// Bead density (kg/m³, glass).
pub const BEAD_DENSITY: f64 = 2500.0;
/// Side of the square floor of the other scenes' bins (m): 8 bead diameters.
pub const BOX_SIDE: f64 = 0.8;

/// Initial layers of the calibrated `box` scene: beads per lattice layer = N / BOX_LAYERS
/// (docs/granular.md, "Box calibration").
pub const BOX_LAYERS: f64 = 1.18;

/// Geometry of the `box` scene and of its initial loose arrangement (docs/granular.md,
/// "Box calibration"): an open box with a `side_x` × `side_y` floor, the beads on a lattice of
/// `pitch` horizontally and `layer_pitch` vertically, the lowest layer's centres `base` above
/// the floor, each site jittered by ±0.2 R, initial velocities ±0.1 m/s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BoxLayout {
    /// side of the floor along x (m)
    pub side_x: f64,
    /// side of the floor along y (m)
    pub side_y: f64,
    /// horizontal lattice pitch (m)
    pub pitch: f64,
    /// vertical pitch between layers (m)
    pub layer_pitch: f64,
    /// height of the lowest layer's centres above the floor (m)
    pub base: f64,
}

impl BoxLayout {
    /// The calibrated layout for `beads` beads: pitch 2.5 R in all directions, the first layer
    /// 1.25 R above the floor (a gap of R/4), and a floor of nx × ny lattice sites with
    /// nx = ⌈√(N / [`BOX_LAYERS`])⌉, ny = ⌈N / (BOX_LAYERS nx)⌉, so that the beads start in
    /// about [`BOX_LAYERS`] layers and the footprint grows with N (the pile's height does not).
    pub fn for_beads(beads: usize) -> Self {
        let r = BEAD_RADIUS;
        let pitch = 2.5 * r;
        let sites = (beads.max(1) as f64 / BOX_LAYERS).ceil();
        let nx = sites.sqrt().ceil().max(1.0);
        let ny = (sites / nx).ceil().max(1.0);
        let side = |n: f64| (n - 1.0) * pitch + 2.5 * r;
        Self {
            side_x: side(nx),
            side_y: side(ny),
            pitch,
            layer_pitch: pitch,
            base: 1.25 * r,
        }
    }
}

/// Which scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Scene {
    /// beads dropped from a loose random arrangement into a square box (§6)
    Box,
    /// beads flowing through a V-shaped funnel onto a floor
    Funnel,
    /// beads on a vertically vibrating plate, inside fixed walls
    VibratingPlate,
    /// beads in a drum rotating about a horizontal axis
    RotatingDrum,
}

impl Scene {
    /// All scenes.
    pub const ALL: [Scene; 4] = [
        Scene::Box,
        Scene::Funnel,
        Scene::VibratingPlate,
        Scene::RotatingDrum,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Scene::Box => "box",
            Scene::Funnel => "funnel",
            Scene::VibratingPlate => "vibrating-plate",
            Scene::RotatingDrum => "rotating-drum",
        }
    }

    /// Parses a command-line name.
    pub fn from_name(s: &str) -> Option<Scene> {
        Scene::ALL.into_iter().find(|x| x.name() == s)
    }

    /// Builds the world of this scene with `beads` spheres, deterministically from `seed`
    /// (the `box` scene with [`BoxLayout::for_beads`]).
    pub fn build(self, beads: usize, seed: u64) -> World {
        self.build_with(beads, seed, &BoxLayout::for_beads(beads))
    }

    /// The `box` scene with the calibrated layout of [`BoxLayout::for_beads`], except that
    /// the beads of the partial top layer sit at random sites spread over the whole floor
    /// (chosen by `seed`) instead of filling its first rows: the heap then has the same
    /// structure at every N (docs/scaling.md, "Scene sizing"), while the calibrated layout's
    /// two-layer strip grows as √N.
    pub fn box_spread(beads: usize, seed: u64) -> World {
        let layout = BoxLayout::for_beads(beads);
        let plain = Scene::Box.build_with(beads, seed, &layout);
        let layer = |z: f64| ((z - layout.base) / layout.layer_pitch).round().max(0.0) as usize;
        let per_layer = plain
            .bodies
            .iter()
            .filter(|b| layer(b.position.z) == 0)
            .count()
            .max(1);
        let full = beads / per_layer;
        let partial = beads - full * per_layer;
        if partial == 0 {
            return plain;
        }
        let mut world = Scene::Box.build_with((full + 1) * per_layer, seed, &layout);
        // keep `partial` of the top layer's beads, chosen by a seeded shuffle
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_5eed);
        let top: Vec<usize> = (0..world.bodies.len())
            .filter(|&i| layer(world.bodies[i].position.z) == full)
            .collect();
        let mut pick = top.clone();
        for k in 0..pick.len() {
            let j = rng.random_range(k..pick.len());
            pick.swap(k, j);
        }
        let mut drop = vec![false; world.bodies.len()];
        for &i in pick.iter().skip(partial) {
            drop[i] = true;
        }
        let mut k = 0;
        world.bodies.retain(|_| {
            let keep = !drop[k];
            k += 1;
            keep
        });
        world
    }

    /// Builds the world of this scene; `layout` is used by the `box` scene only: the world
    /// of [`Scene::model`] (built without the model's start checks: the built-in
    /// arrangements are loose by construction, `scenes_are_deterministic_and_start_without_overlap`).
    pub fn build_with(self, beads: usize, seed: u64, layout: &BoxLayout) -> World {
        // the model of a built-in scene is valid by construction (tested below); an empty
        // world would only come from a broken built-in
        self.model(beads, seed, layout).world().unwrap_or_default()
    }

    /// The scene description of this scene with `beads` spheres, deterministic from `seed`
    /// (ChaCha8): its obstacles, one material (`default`, the law of `Params::default()`),
    /// the beads as one [`SphereBatch`] (radius [`BEAD_RADIUS`], density [`BEAD_DENSITY`]),
    /// gravity −9.81 e_z, the step settings of `coulomb simulate`. `layout` is used by the
    /// `box` scene only.
    pub fn model(self, beads: usize, seed: u64, layout: &BoxLayout) -> SceneModel {
        let mut model = SceneModel::default();
        let mut spheres = Vec::with_capacity(beads);
        let region = self.geometry(layout, &mut model.obstacles);
        region.fill(beads, seed, &mut |b| spheres.push(b));
        model.sphere_batches.push(SphereBatch {
            positions: spheres.iter().map(|b| b.position).collect(),
            radii: vec![BEAD_RADIUS],
            velocities: spheres.iter().map(|b| b.velocity).collect(),
            density: Some(BEAD_DENSITY),
            ..SphereBatch::default()
        });
        model
    }

    /// The world of [`Scene::build_with`] without its beads: obstacles and gravity.
    pub fn skeleton(self, seed: u64, layout: &BoxLayout) -> World {
        self.build_with(0, seed, layout)
    }

    /// Hands the beads of [`Scene::build_with`] (`beads`, `seed`, `layout`) to `emit` one at
    /// a time in their order (global id 0, 1, …), each exactly the sphere of the built world,
    /// without holding them: a rank of a distributed run keeps its part only
    /// (module `distributed`, feature `mpi`). The lattice is drawn again on every call (O(N) time, O(1)
    /// memory).
    pub fn for_each_bead(
        self,
        beads: usize,
        seed: u64,
        layout: &BoxLayout,
        emit: &mut dyn FnMut(Sphere),
    ) {
        let mut obstacles = Vec::new();
        self.geometry(layout, &mut obstacles)
            .fill(beads, seed, emit);
    }

    /// The obstacles of this scene (appended to `obstacles`) and the region its beads fill.
    fn geometry(self, layout: &BoxLayout, obstacles: &mut Vec<ObstacleSpec>) -> Region {
        let r = BEAD_RADIUS;
        // the loose lattice of every scene but the box: spacing 2.5 R, first layer 1.25 R up
        let loose = |lo: Vec3, hi: Vec3| Lattice {
            lo,
            hi,
            pitch: 2.5 * r,
            layer_pitch: 2.5 * r,
            base: 1.25 * r,
        };
        match self {
            Scene::Box => {
                let l = layout;
                add_box(obstacles, l.side_x, l.side_y);
                Region {
                    lattice: Lattice {
                        lo: Vec3::new(0.0, 0.0, 0.0),
                        hi: Vec3::new(l.side_x, l.side_y, f64::INFINITY),
                        pitch: l.pitch,
                        layer_pitch: l.layer_pitch,
                        base: l.base,
                    },
                    keep: Keep::All,
                }
            }
            Scene::VibratingPlate => {
                add_box(obstacles, BOX_SIDE, BOX_SIDE);
                if let Some(ground) = obstacles.first_mut() {
                    ground.name = "plate".into();
                    ground.motion = Motion::Oscillate {
                        direction: Vec3::Z,
                        amplitude: 0.03,
                        frequency: 3.0,
                    };
                }
                Region {
                    lattice: loose(
                        Vec3::new(0.0, 0.0, 0.03),
                        Vec3::new(BOX_SIDE, BOX_SIDE, f64::INFINITY),
                    ),
                    keep: Keep::All,
                }
            }
            Scene::Funnel => {
                // floor and walls of a large bin; two inclined plates (45°) forming a V with a
                // slot of 3 diameters at height 1 m, the beads above them
                let (lx, ly) = (2.0, BOX_SIDE);
                add_box(obstacles, lx, ly);
                let slot = 6.0 * r;
                let zb = 1.0;
                let half = 0.5;
                let a = std::f64::consts::FRAC_PI_4;
                for side in [-1.0, 1.0] {
                    let dir = Vec3::new(side * a.cos(), 0.0, a.sin());
                    let center = Vec3::new(0.5 * lx + side * 0.5 * slot, 0.5 * ly, zb) + dir * half;
                    obstacles.push(ObstacleSpec::fixed(
                        if side < 0.0 {
                            "funnel-left"
                        } else {
                            "funnel-right"
                        },
                        Shape::Rectangle {
                            center,
                            normal: Vec3::new(-side * a.sin(), 0.0, a.cos()),
                            u: dir,
                            half_u: half,
                            half_v: 0.5 * ly,
                        },
                    ));
                }
                let x0 = 0.5 * lx - 0.5 * slot - 2.0 * half * a.cos();
                let x1 = 0.5 * lx + 0.5 * slot + 2.0 * half * a.cos();
                Region {
                    lattice: loose(
                        Vec3::new(x0, 0.0, zb + 2.0 * r),
                        Vec3::new(x1, ly, f64::INFINITY),
                    ),
                    keep: Keep::AboveV {
                        z: zb,
                        lift: 2.0 * r,
                        x: 0.5 * lx,
                        half_slot: 0.5 * slot,
                    },
                }
            }
            Scene::RotatingDrum => {
                let (rd, len) = (0.6, 0.5);
                let axis_point = Vec3::new(0.0, 0.0, rd);
                let motion = Motion::Rotate {
                    center: axis_point,
                    axis: Vec3::Y,
                    omega: 1.0,
                };
                obstacles.push(ObstacleSpec {
                    name: "drum".into(),
                    shape: Shape::CylinderInside {
                        point: axis_point,
                        axis: Vec3::Y,
                        radius: rd,
                    },
                    motion: motion.clone(),
                    material: DEFAULT_MATERIAL.into(),
                });
                for (name, y, n) in [("cap-front", 0.0, Vec3::Y), ("cap-back", len, -Vec3::Y)] {
                    obstacles.push(ObstacleSpec {
                        name: name.into(),
                        shape: Shape::Plane {
                            point: Vec3::new(0.0, y, 0.0),
                            normal: n,
                        },
                        motion: motion.clone(),
                        material: DEFAULT_MATERIAL.into(),
                    });
                }
                Region {
                    lattice: loose(Vec3::new(-rd, 0.0, 0.0), Vec3::new(rd, len, 2.0 * rd)),
                    keep: Keep::InsideDrum {
                        axis_z: rd,
                        radius: rd - 1.2 * r,
                    },
                }
            }
        }
    }
}

/// Where the beads of a built-in scene go: the sites of `lattice` where `keep` holds.
struct Region {
    lattice: Lattice,
    keep: Keep,
}

/// Which lattice sites a built-in scene keeps.
enum Keep {
    /// every site
    All,
    /// above the V of the funnel: site z − `z` − `lift` > |site x − `x`| − `half_slot`
    AboveV {
        z: f64,
        lift: f64,
        x: f64,
        half_slot: f64,
    },
    /// within `radius` of the drum's axis (parallel to y through (0, ·, `axis_z`))
    InsideDrum { axis_z: f64, radius: f64 },
}

impl Keep {
    /// Whether the site p is kept.
    fn holds(&self, p: Vec3) -> bool {
        match *self {
            Keep::All => true,
            Keep::AboveV {
                z,
                lift,
                x,
                half_slot,
            } => p.z - z - lift > (p.x - x).abs() - half_slot,
            Keep::InsideDrum { axis_z, radius } => {
                (Vec3::new(p.x, 0.0, p.z) - Vec3::new(0.0, 0.0, axis_z)).norm() < radius
            }
        }
    }
}

impl Region {
    /// The `beads` beads of the region, drawn from `seed` (ChaCha8), handed to `emit` in order.
    fn fill(&self, beads: usize, seed: u64, emit: &mut dyn FnMut(Sphere)) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        fill_lattice(&mut rng, beads, &self.lattice, |p| self.keep.holds(p), emit);
    }
}

/// Ground z = 0 and four vertical walls around [0, lx] × [0, ly].
fn add_box(obstacles: &mut Vec<ObstacleSpec>, lx: f64, ly: f64) {
    let planes = [
        ("ground", Vec3::ZERO, Vec3::Z),
        ("wall-x0", Vec3::ZERO, Vec3::X),
        ("wall-x1", Vec3::new(lx, 0.0, 0.0), -Vec3::X),
        ("wall-y0", Vec3::ZERO, Vec3::Y),
        ("wall-y1", Vec3::new(0.0, ly, 0.0), -Vec3::Y),
    ];
    for (name, point, normal) in planes {
        obstacles.push(ObstacleSpec::fixed(name, Shape::Plane { point, normal }));
    }
}

/// Sites of a loose initial arrangement in the box [lo, hi].
pub(crate) struct Lattice {
    pub(crate) lo: Vec3,
    pub(crate) hi: Vec3,
    pub(crate) pitch: f64,
    pub(crate) layer_pitch: f64,
    /// height of the first layer's centres above lo.z
    pub(crate) base: f64,
}

/// Places `n` beads on the sites of `lattice` (jitter ±0.2 R, random initial velocities of
/// ±0.1 m/s, mass of a glass ball of [`BEAD_DENSITY`]), layer by layer bottom up, keeping the
/// sites where `inside` holds; each bead is handed to `emit` as it is placed.
pub(crate) fn fill_lattice(
    rng: &mut ChaCha8Rng,
    n: usize,
    lattice: &Lattice,
    inside: impl Fn(Vec3) -> bool,
    emit: &mut dyn FnMut(Sphere),
) {
    let &Lattice {
        lo,
        hi,
        pitch: s,
        layer_pitch: sz,
        base,
    } = lattice;
    let r = BEAD_RADIUS;
    // the mass of `SceneModel::world` for a batch of this density
    let mass = crate::model::ball_mass(BEAD_DENSITY, r);
    let nx = (((hi.x - lo.x) - 2.5 * r) / s).floor().max(0.0) as usize + 1;
    let ny = (((hi.y - lo.y) - 2.5 * r) / s).floor().max(0.0) as usize + 1;
    let nz_max = if hi.z.is_finite() {
        (((hi.z - lo.z) - base - 1.25 * r) / sz).floor().max(0.0) as usize + 1
    } else {
        usize::MAX
    };
    let mut placed = 0;
    let mut iz = 0;
    while placed < n && iz < nz_max && iz < 100_000 {
        for iy in 0..ny {
            for ix in 0..nx {
                if placed >= n {
                    return;
                }
                let mut j = || rng.random_range(-0.2 * r..0.2 * r);
                let site = Vec3::new(
                    lo.x + 1.25 * r + ix as f64 * s,
                    lo.y + 1.25 * r + iy as f64 * s,
                    lo.z + base + iz as f64 * sz,
                );
                let p = site + Vec3::new(j(), j(), j());
                if !inside(site) {
                    continue;
                }
                let mut b = Sphere::new(p, r, mass);
                let mut v = || rng.random_range(-0.1..0.1);
                b.velocity = Vec3::new(v(), v(), v());
                emit(b);
                placed += 1;
            }
        }
        iz += 1;
    }
}

#[cfg(feature = "unit-tests")]
pub mod tests {
    use super::*;
    use crate::contact::{detect, Activation};

    pub fn scenes_are_deterministic_and_start_without_overlap() {
        for scene in Scene::ALL {
            let a = scene.build(150, 3);
            let b = scene.build(150, 3);
            let c = scene.build(150, 4);
            assert_eq!(a, b, "{scene:?}");
            assert_ne!(a, c, "{scene:?}");
            assert_eq!(a.bodies.len(), 150, "{scene:?}");
            let contacts = detect(
                &a,
                0.0,
                0.0,
                &Activation {
                    gamma: 0.0,
                    delta: 0.0,
                    keep_separating: false,
                    delta_from_tolerance: false,
                    close_gaps: false,
                },
            );
            assert!(
                contacts.is_empty(),
                "{scene:?}: {} overlaps",
                contacts.len()
            );
            assert_eq!(Scene::from_name(scene.name()), Some(scene));
        }
    }

    /// The streamed beads are those of the built world, in order, bit for bit; the skeleton
    /// has its obstacles and no bead.
    pub fn streamed_beads_are_the_built_ones() {
        for scene in Scene::ALL {
            for (n, seed) in [(0usize, 1u64), (1, 2), (257, 7)] {
                let layout = BoxLayout::for_beads(n);
                let world = scene.build_with(n, seed, &layout);
                let mut streamed = Vec::new();
                scene.for_each_bead(n, seed, &layout, &mut |b| streamed.push(b));
                assert_eq!(streamed, world.bodies, "{scene:?} {n}");
                let skeleton = scene.skeleton(seed, &layout);
                assert!(skeleton.bodies.is_empty());
                assert_eq!(skeleton.obstacles, world.obstacles, "{scene:?} {n}");
                assert_eq!(skeleton.gravity, world.gravity);
            }
        }
    }

    pub fn builtin_models_are_valid_scenes() {
        for scene in Scene::ALL {
            let model = scene.model(200, 5, &BoxLayout::for_beads(200));
            let (world, params) = model.build().unwrap_or_else(|e| panic!("{scene:?}: {e}"));
            assert_eq!(world, scene.build(200, 5), "{scene:?}");
            assert!(world.materials.is_none());
            assert_eq!((params.mu, params.restitution), (0.3, 0.2));
        }
    }

    pub fn calibrated_box_grows_with_the_beads_and_holds_them() {
        let r = BEAD_RADIUS;
        let mut last_area = 0.0;
        for n in [1usize, 150, 300, 600, 10_000] {
            let l = BoxLayout::for_beads(n);
            let area = l.side_x * l.side_y;
            assert!(area >= last_area, "{n}: {l:?}");
            last_area = area;
            // enough lattice sites per layer for n / BOX_LAYERS beads
            let sites = |side: f64| ((side - 2.5 * r) / l.pitch).floor() + 1.0;
            assert!(sites(l.side_x) * sites(l.side_y) >= n as f64 / BOX_LAYERS - 1e-9);
            let world = Scene::Box.build(n, 1);
            assert_eq!(world.bodies.len(), n);
            let layers = (n as f64 / (sites(l.side_x) * sites(l.side_y))).ceil();
            for b in &world.bodies {
                let p = b.position;
                assert!(p.x >= r && p.x <= l.side_x - r, "{n}: {p:?}");
                assert!(p.y >= r && p.y <= l.side_y - r, "{n}: {p:?}");
                assert!(p.z >= l.base - 0.2 * r - 1e-12, "{n}: {p:?}");
                assert!(p.z <= l.base + (layers - 1.0) * l.layer_pitch + 0.2 * r + 1e-12);
            }
        }
        // an explicit layout is used as given
        let l = BoxLayout {
            side_x: 0.5,
            side_y: 0.5,
            pitch: 2.5 * r,
            layer_pitch: 0.3,
            base: 0.2,
        };
        let world = Scene::Box.build_with(20, 2, &l);
        assert_eq!(world.bodies.len(), 20);
        // 4 × 4 sites per layer: 16 beads at z ≈ 0.2, 4 at z ≈ 0.5
        let high = world.bodies.iter().filter(|b| b.position.z > 0.4).count();
        assert_eq!(high, 4);
    }
}
