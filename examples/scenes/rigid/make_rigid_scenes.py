"""Writes the rigid-body scene files of this folder (issue 41): a running-bond brick wall (with
1 mm joints, and touching), a cube pyramid, a Kapla tower, 500 random convex rocks poured into
a box, capsules in a hopper, a block on an incline, a wall hit by a steel ball. Deterministic
(numpy's default_rng with fixed seeds); run
`python3 make_rigid_scenes.py` here to rewrite them. Quaternions are (w, x, y, z), written
with 17 significant digits so that their norm is 1 to round-off (files refuse a quaternion
whose norm differs from 1 by more than 1e-9)."""

import json
import math
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def num(x: float) -> str:
    return repr(float(x))


def vec(v) -> str:
    return "[" + ", ".join(num(x) for x in v) + "]"


def rows(vs, indent="  ") -> str:
    return "[\n" + "".join(f"{indent}{vec(v)},\n" for v in vs) + "]"


def header(title: str, h: float, steps: int, mu: float, e: float = 0.0) -> str:
    return (f"# {title}\n# (written by make_rigid_scenes.py)\n\n"
            f"[step]\nh = {h}\nsteps = {steps}\ntol = 1e-8\n\n"
            f"[default_pair]\nmu = {mu}\nrestitution = {e}\n\n")


def floor() -> str:
    return ('[[obstacles]]\nname = "floor"\n'
            'shape = { kind = "plane", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }\n\n')


def group(shape: str, positions, orientations=None, extra: str = "") -> str:
    s = f"[[bodies]]\n{extra}shape = {shape}\npositions = {rows(positions)}\n"
    if orientations is not None:
        s += f"orientations = {rows(orientations)}\n"
    return s + "\n"


def quat_z(angle: float):
    return [math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2)]


def random_quaternion(rng):
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


def brick_wall(courses=10, bricks=6, joint=0.001, name="brick-wall.toml"):
    # brick 0.2 x 0.1 x 0.05 m (half 0.1, 0.05, 0.025), dry joints of `joint` (1 mm) between
    # the bricks of a course; odd courses start and end with a half brick: the running bond
    full, half = [], []
    p = 0.2 + joint
    for c in range(courses):
        z = 0.025 + 0.05 * c
        if c % 2 == 0:
            full += [[0.1 + p * i, 0.0, z] for i in range(bricks)]
        else:
            half += [[0.05, 0.0, z], [p * bricks - joint - 0.05, 0.0, z]]
            full += [[0.1 + joint + 0.1 + p * i, 0.0, z] for i in range(bricks - 1)]
    joints = f"dry joints of {joint * 1e3:g} mm" if joint > 0 else "touching, no joints"
    text = header(f"A running-bond brick wall: {courses} courses of {bricks} bricks "
                  f"(0.2 x 0.1 x 0.05 m, 1800 kg/m^3, {joints}) on the floor, mu = 0.7.", 1e-3, 1000, 0.7)
    text += "[materials.brick]\ndensity = 1800\n\n" + floor()
    text += group('{ kind = "cuboid", half_extents = [0.1, 0.05, 0.025] }', full,
                  extra='material = "brick"\n')
    text += group('{ kind = "cuboid", half_extents = [0.05, 0.05, 0.025] }', half,
                  extra='material = "brick"\n')
    (HERE / name).write_text(text)


def cube_pyramid(layers=5, a=0.1):
    pos = []
    for l in range(layers):
        n = layers - l
        off = 0.5 * a * l
        pos += [[off + a * (i + 0.5), off + a * (j + 0.5), a * (l + 0.5)]
                for i in range(n) for j in range(n)]
    text = header(f"A pyramid of cubes (side {a} m): {layers} layers, n x n cubes on layer "
                  "n, each layer on the one below offset by half a cube; mu = 0.7.",
                  1e-3, 1000, 0.7)
    text += floor() + group(f'{{ kind = "cuboid", half_extents = [{a / 2}, {a / 2}, {a / 2}] }}',
                            pos, extra="density = 1000\n")
    (HERE / "cube-pyramid.toml").write_text(text)


def kapla_tower(levels=12):
    # Kapla plank 117 x 23.4 x 7.8 mm: two planks per level, levels crossed at 90 degrees
    hx, hy, hz = 0.0585, 0.0117, 0.0039
    pos, ori = [], []
    for l in range(levels):
        z = hz * (2 * l + 1)
        for side in (-1, 1):
            d = side * (hx - hy)
            if l % 2 == 0:
                pos.append([0.0, d, z]); ori.append([1.0, 0.0, 0.0, 0.0])
            else:
                pos.append([d, 0.0, z]); ori.append(quat_z(math.pi / 2))
    text = header(f"A Kapla tower: {levels} levels of two planks (117 x 23.4 x 7.8 mm, pine "
                  "450 kg/m^3), each level crossed at 90 degrees; mu = 0.5.", 5e-4, 2000, 0.5)
    text += floor() + group(f'{{ kind = "cuboid", half_extents = [{hx}, {hy}, {hz}] }}', pos, ori,
                            extra="density = 450\n")
    (HERE / "kapla-tower.toml").write_text(text)


def rock_pile(count=500, seed=41):
    # random convex rocks: hulls of 10 points on an ellipsoid of semi-axes 15-30 mm, on a
    # 10 x 10 lattice of pitch 0.08 m, 5 layers, randomly turned, dropped into a box
    rng = np.random.default_rng(seed)
    bodies = []
    for k in range(count):
        axes = rng.uniform(0.015, 0.03, size=3)
        d = rng.normal(size=(10, 3))
        d /= np.linalg.norm(d, axis=1)[:, None]
        pts = np.round(d * axes, 5).tolist()
        i, j, l = k % 10, (k // 10) % 10, k // 100
        pos = [0.06 + 0.08 * i, 0.06 + 0.08 * j, 0.06 + 0.08 * l]
        bodies.append({"shape": {"kind": "convex_hull", "points": pts},
                       "positions": [pos],
                       "orientations": [[float(x) for x in random_quaternion(rng)]],
                       "material": "rock"})
    scene = {
        "name": "rock-pile",
        "step": {"h": 1e-3, "steps": 1000, "tol": 1e-6},
        "materials": {"rock": {"density": 2600}},
        "default_pair": {"mu": 0.6, "restitution": 0.0},
        "obstacles": [{"name": "bin", "shape": {"kind": "box", "lo": [0, 0, 0],
                                                 "hi": [0.86, 0.86, 1.0], "open_top": True}}],
        "bodies": bodies,
    }
    (HERE / "rock-pile.json").write_text(json.dumps(scene, indent=None, separators=(",", ":"))
                                          + "\n")


def capsule_hopper(count=96, seed=7):
    # a hopper of two plates at 60 degrees from the horizontal (a V slot of 0.08 m at
    # z = 0.3 m) between two side walls (a box container), capsules above it
    rng = np.random.default_rng(seed)
    s, c = math.sin(math.radians(60)), math.cos(math.radians(60))
    half_u, half_v = 0.2, 0.15
    text = header("Capsules (radius 15 mm, segment 50 mm) poured into a hopper: two plates at "
                  "60 degrees forming a V with a slot of 0.08 m, inside a box; mu = 0.4.",
                  1e-3, 1500, 0.4)
    text += ('[[obstacles]]\nname = "bin"\nshape = { kind = "box", lo = [-0.4, -0.15, -0.2], '
             'hi = [0.4, 0.15, 2.0], open_top = true }\n\n')
    for side in (-1, 1):
        cx = side * (0.04 + half_u * c)
        cz = 0.3 + half_u * s
        normal = [-side * s, 0.0, c]
        u = [side * c, 0.0, s]
        text += (f'[[obstacles]]\nname = "plate-{"left" if side < 0 else "right"}"\n'
                 f'[obstacles.shape]\nkind = "rectangle"\ncenter = {vec([cx, 0.0, cz])}\n'
                 f'normal = {vec(normal)}\nu = {vec(u)}\nhalf_u = {half_u}\nhalf_v = {half_v}\n\n')
    pos, ori = [], []
    for k in range(count):
        i, j, l = k % 8, (k // 8) % 3, k // 24
        pos.append([-0.28 + 0.08 * i, -0.08 + 0.08 * j, 0.75 + 0.1 * l])
        ori.append([float(x) for x in random_quaternion(rng)])
    text += group('{ kind = "capsule", radius = 0.015, half_height = 0.025 }', pos, ori,
                  extra="density = 1200\n")
    (HERE / "capsule-hopper.toml").write_text(text)


def incline(theta_deg=30.0, mu=0.3):
    th = math.radians(theta_deg)
    n = [math.sin(th), 0.0, math.cos(th)]
    q = [math.cos(th / 2), 0.0, math.sin(th / 2), 0.0]  # z axis onto the normal
    hz = 0.05
    pos = [n[k] * hz for k in range(3)]
    text = header(f"A block (0.2 x 0.2 x 0.1 m) on an incline of {theta_deg} degrees with "
                  f"mu = {mu}: tan(theta) = {math.tan(th):.3f} > mu, it slides with "
                  f"a = g (sin - mu cos) = {9.81 * (math.sin(th) - mu * math.cos(th)):.4f} m/s^2 "
                  "(h/w = 0.5 < 1/tan(theta): it does not topple).", 1e-3, 500, mu)
    text += ('[[obstacles]]\nname = "incline"\n'
             f'shape = {{ kind = "plane", point = [0.0, 0.0, 0.0], normal = {vec(n)} }}\n\n')
    text += group(f'{{ kind = "cuboid", half_extents = [0.1, 0.1, {hz}] }}', [pos], [q],
                  extra="density = 1000\n")
    (HERE / "incline.toml").write_text(text)


def wall_impact(courses=5, bricks=4, speed=6.0):
    # the geometry of `coulomb validate`'s wall-impact check (rigid/validation.rs,
    # brick_wall + impact_sphere): bricks 0.2 x 0.1 x 0.05 m (2000 kg/m^3) side by side
    # without joints, odd courses shifted by half a brick with one brick less; a steel ball
    # (r = 0.08 m, 7800 kg/m^3) 2 cm in front of the wall at mid-length, thrown at it
    full = []
    for c in range(courses):
        n = bricks - 1 if c % 2 else bricks
        full += [[0.2 * i + (0.1 if c % 2 else 0.0), 0.0, 0.025 + 0.05 * c] for i in range(n)]
    xs = [p[0] for p in full]
    r = 0.08
    ball = [0.5 * (min(xs) + max(xs)), -0.05 - r - 0.02, 0.125]
    text = header(f"A running-bond wall of {courses} courses ({len(full)} bricks 0.2 x 0.1 x 0.05 m, "
                  f"2000 kg/m^3) hit by a steel ball (r = 8 cm, 7800 kg/m^3) at {speed} m/s; "
                  "mu = 0.7. The wall collapses.", 1e-3, 400, 0.7)
    text += floor()
    text += group('{ kind = "cuboid", half_extents = [0.1, 0.05, 0.025] }', full,
                  extra="density = 2000\n")
    text += group(f'{{ kind = "sphere", radius = {r} }}', [ball],
                  extra=f"density = 7800\nvelocity = {vec([0.0, speed, 0.0])}\n")
    (HERE / "wall-impact.toml").write_text(text)


if __name__ == "__main__":
    brick_wall()
    brick_wall(joint=0.0, name="brick-wall-touching.toml")
    cube_pyramid()
    kapla_tower()
    rock_pile()
    capsule_hopper()
    incline()
    wall_impact()
