"""Writes the mechanism scenes of this folder that are built from many parts (issue 53): the ball
mill (ball-mill.toml) and the vehicle on granular ground (vehicle-on-spheres.toml).
Run `python3 make_joint_scenes.py` here to rewrite them (deterministic: no random numbers; the
spheres come from the files' `fill` groups, seeded by the scene's seed).

The rigid-body engine has no concave shape but triangle meshes, which are obstacles, not
bodies: a hollow body is a `compound` of convex parts. The mill's drum is one compound body
(a ring of convex-hull staves, two end plates, lifters), the vehicle's chassis a cuboid and its
wheels cylinders."""

import math
from pathlib import Path

HERE = Path(__file__).resolve().parent


def num(x: float) -> str:
    # 17 significant digits: quaternions keep their unit norm to round-off
    return repr(float(round(x, 15))) if abs(x) > 1e-15 else "0.0"


def vec(v) -> str:
    return "[" + ", ".join(num(x) for x in v) + "]"


def quat_y(angle: float):
    """The rotation by `angle` about the y axis, (w, x, y, z)."""
    return [math.cos(angle / 2), 0.0, math.sin(angle / 2), 0.0]


def rot_y(angle: float, p):
    """p turned by `angle` about the y axis: x' = x cos + z sin, z' = -x sin + z cos."""
    c, s = math.cos(angle), math.sin(angle)
    return [p[0] * c + p[2] * s, p[1], -p[0] * s + p[2] * c]


def ball_mill(staves=16, radius=0.3, wall=0.02, length=0.3, plate=0.01, lifters=8,
              lifter_height=0.03, lifter_width=0.02, omega=3.0, torque=300.0, count=600,
              ball=0.015, centre_z=0.5):
    """A drum of inner radius `radius` (the apothem of a `staves`-gon), axis y, turning at
    `omega` rad/s on a motorised revolute joint to the world, `count` steel balls inside."""
    half = length / 2
    parts = []
    step = 2 * math.pi / staves
    ri = radius / math.cos(step / 2)  # polygon vertices: inner and outer
    ro = (radius + wall) / math.cos(step / 2)
    for k in range(staves):
        a0, a1 = (k - 0.5) * step, (k + 0.5) * step
        pts = []
        for r in (ri, ro):
            for a in (a0, a1):
                for y in (-half, half):
                    pts.append(rot_y(a, [r, y, 0.0]))
        parts.append('{ shape = { kind = "convex_hull", points = ['
                     + ", ".join(vec(p) for p in pts) + '] }, position = [0.0, 0.0, 0.0] }')
    # the end plates close the drum (square plates across the whole ring)
    for side in (-1, 1):
        parts.append(f'{{ shape = {{ kind = "cuboid", half_extents = {vec([ro, plate / 2, ro])} }}, '
                     f'position = {vec([0.0, side * (half + plate / 2), 0.0])} }}')
    # lifters: bars along the axis on the inner wall, at the middle of every other stave
    for k in range(lifters):
        a = k * 2 * math.pi / lifters
        c = rot_y(a, [radius - lifter_height / 2, 0.0, 0.0])
        parts.append(f'{{ shape = {{ kind = "cuboid", half_extents = '
                     f'{vec([lifter_height / 2, half, lifter_width / 2])} }}, position = {vec(c)}, '
                     f'orientation = {vec(quat_y(a))} }}')
    crit = math.sqrt(9.81 / radius)
    text = (
        f"# A ball mill (issue 53): a steel drum (inner radius {radius} m: a {staves}-gon of "
        f"{wall * 1e3:g} mm staves, {length} m long,\n"
        f"# closed by two end plates, {lifters} lifters of {lifter_height * 1e3:g} x "
        f"{lifter_width * 1e3:g} mm) on a motorised revolute joint to the\n"
        f"# world (axis y through its centre, motor {omega} rad/s = "
        f"{100 * omega / crit:.0f} % of the critical speed sqrt(g/R), at most {torque} N m),\n"
        f"# {count} steel balls (r = {ball * 1e3:g} mm) inside, filled on a lattice from the "
        "bottom. The engine has no concave\n"
        "# body: the drum is one compound of convex parts (make_joint_scenes.py writes it).\n"
        "# Body 0 is the drum, the balls follow.\n"
        "# (written by make_joint_scenes.py)\n\n"
        f"[step]\nh = 0.001\nsteps = 3000\ntol = 1e-6\n\n"
        "[default_pair]\nmu = 0.5\nrestitution = 0.0\n\n"
        "[materials.steel]\ndensity = 7800\n\n"
        "[[bodies]]\nmaterial = \"steel\"\n"
        f"positions = [{vec([0.0, 0.0, centre_z])}]\n"
        "[bodies.shape]\nkind = \"compound\"\nparts = [\n"
        + "".join(f"  {p},\n" for p in parts) + "]\n\n"
        "[[bodies]]\nmaterial = \"steel\"\n[bodies.fill]\n"
        f"count = {count}\n"
        f"region = {{ kind = \"cylinder\", base = {vec([0.0, -half + 0.005, centre_z])}, "
        f"axis = [0.0, 1.0, 0.0], radius = {radius - lifter_height - 0.01}, "
        f"height = {length - 0.01} }}\n"
        f"sizes = {{ kind = \"mono\", radius = {ball} }}\n"
        f"packing = {{ method = \"lattice\", pitch = {2.2 * ball}, jitter = 0.05 }}\n\n"
        "[[joints]]\nkind = \"revolute\"\nbody_a = 0\n"
        f"anchor = {vec([0.0, 0.0, centre_z])}\naxis = [0.0, 1.0, 0.0]\n"
        f"motor = {{ velocity = {omega}, max_force = {torque} }}\n"
    )
    (HERE / "ball-mill.toml").write_text(text)


def vehicle(nx=100, ny=25, layers=4, ball=0.01, pitch=0.022,
            wheel=0.1, wheel_half_width=0.03, omega=5.0, torque=20.0):
    """A four-wheel vehicle (a cuboid chassis, four cylinder wheels on motorised revolute
    joints, axis y) driving along +x over a bed of `count` spheres in an open box."""
    # the lattice's sites fill the box exactly: nx x ny x layers spheres (10^4)
    length, width, bed = nx * pitch, ny * pitch, layers * pitch + 0.0005
    count = nx * ny * layers
    gap = 0.001
    axle_z = bed + wheel + gap
    chassis = [0.25, 0.12, 0.04]
    wy = chassis[1] + 0.005 + wheel_half_width
    start_x = 0.35
    wheels = [[start_x + sx * 0.2, sy * wy, axle_z] for sx in (1, -1) for sy in (1, -1)]
    text = (
        f"# A four-wheel vehicle on granular ground (issue 53): a chassis (0.5 x 0.24 x 0.08 m, "
        f"2000 kg/m^3) and four wheels\n"
        f"# (cylinders r = {wheel} m, {2 * wheel_half_width} m wide, 1000 kg/m^3) on motorised "
        f"revolute joints (axis y, {omega} rad/s,\n"
        f"# at most {torque} N m each: {omega * wheel} m/s without slip) driving along +x over a "
        f"bed of {count} steel spheres\n"
        f"# (r = {ball * 1e3:g} mm, a lattice of pitch {pitch} m, {layers} layers, in an "
        f"open box {length:.3f} x {width:.3f} m). Bodies: 0 the\n"
        "# chassis, 1-4 the wheels, then the spheres. (written by make_joint_scenes.py)\n\n"
        "[step]\nh = 0.001\nsteps = 2000\ntol = 1e-6\n\n"
        "[default_pair]\nmu = 0.6\nrestitution = 0.0\n\n"
        "[materials.steel]\ndensity = 7800\n\n"
        "[[obstacles]]\nname = \"bin\"\nmaterial = \"steel\"\n"
        f"shape = {{ kind = \"box\", lo = {vec([0.0, -width / 2, 0.0])}, "
        f"hi = {vec([length, width / 2, 1.0])}, open_top = true }}\n\n"
        "[[bodies]]\ndensity = 2000\n"
        f"shape = {{ kind = \"cuboid\", half_extents = {vec(chassis)} }}\n"
        f"positions = [{vec([start_x, 0.0, axle_z])}]\n\n"
        "[[bodies]]\ndensity = 1000\n"
        f"shape = {{ kind = \"cylinder\", radius = {wheel}, half_height = {wheel_half_width} }}\n"
        "positions = [" + ", ".join(vec(p) for p in wheels) + "]\n\n"
        "[[bodies]]\nmaterial = \"steel\"\n[bodies.fill]\n"
        f"count = {count}\n"
        f"region = {{ kind = \"box\", lo = {vec([0.0, -width / 2, 0.0])}, "
        f"hi = {vec([length, width / 2, bed])} }}\n"
        f"sizes = {{ kind = \"mono\", radius = {ball} }}\n"
        f"packing = {{ method = \"lattice\", pitch = {pitch}, jitter = 0.05 }}\n"
    )
    for k, p in enumerate(wheels):
        text += ("\n[[joints]]\nkind = \"revolute\"\n"
                 f"body_a = {k + 1}\nbody_b = 0\nanchor = {vec(p)}\naxis = [0.0, 1.0, 0.0]\n"
                 f"motor = {{ velocity = {omega}, max_force = {torque} }}\n")
    (HERE / "vehicle-on-spheres.toml").write_text(text)


def chain(links=1000, path=None, steps=500, height=0.05):
    """The benchmark chain (scripts/bench_chain.sh; not shipped): `links` bars 0.1 x 0.02 x
    0.02 m (1000 kg/m^3) end to end on revolute joints (axis y), laid along a wave in the x-z
    plane (link i at the angle 0.3 sin(2 pi i / 50) from the horizontal, the lowest point
    `height` above the floor), released at rest: it falls onto the floor, where its links land at
    different times and the chain folds."""
    pts = [[0.0, 0.0, 0.0]]
    for i in range(links):
        phi = 0.3 * math.sin(2 * math.pi * i / 50)
        p = pts[-1]
        pts.append([p[0] + 0.1 * math.cos(phi), 0.0, p[2] + 0.1 * math.sin(phi)])
    lift = height + 0.01 - min(p[2] for p in pts)
    pts = [[p[0], 0.0, p[2] + lift] for p in pts]
    pos, ori = [], []
    for i in range(links):
        a, b = pts[i], pts[i + 1]
        phi = math.atan2(b[2] - a[2], b[0] - a[0])
        pos.append([(a[0] + b[0]) / 2, 0.0, (a[2] + b[2]) / 2])
        ori.append(quat_y(-phi))
    text = (
        f"# A chain of {links} links (0.1 x 0.02 x 0.02 m bars, 1000 kg/m^3) on revolute joints "
        "(axis y) falling onto the\n# floor from a wave (make_joint_scenes.py chain; "
        "scripts/bench_chain.sh).\n\n"
        f"[step]\nh = 0.001\nsteps = {steps}\ntol = 1e-6\n\n"
        "[default_pair]\nmu = 0.5\nrestitution = 0.0\n\n"
        '[[obstacles]]\nname = "floor"\n'
        'shape = { kind = "plane", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }\n\n'
        '[[bodies]]\ndensity = 1000\n'
        'shape = { kind = "cuboid", half_extents = [0.05, 0.01, 0.01] }\n'
        "positions = [\n" + "".join(f"  {vec(p)},\n" for p in pos) + "]\n"
        "orientations = [\n" + "".join(f"  {vec(q)},\n" for q in ori) + "]\n"
    )
    for i in range(1, links):
        text += (f'\n[[joints]]\nkind = "revolute"\nbody_a = {i}\nbody_b = {i - 1}\n'
                 f"anchor = {vec(pts[i])}\naxis = [0.0, 1.0, 0.0]\n")
    Path(path).write_text(text)


if __name__ == "__main__":
    import sys
    if len(sys.argv) > 1 and sys.argv[1] == "chain":
        # python3 make_joint_scenes.py chain LINKS OUT.toml [STEPS]
        chain(int(sys.argv[2]), sys.argv[3], int(sys.argv[4]) if len(sys.argv) > 4 else 500)
    else:
        ball_mill()
        vehicle()
