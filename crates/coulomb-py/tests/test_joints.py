"""Joints between bodies from Python (issue 53): Scene.add_joint, Scene.body_count in
insertion order across add_spheres and add_body, Simulation.joint_forces, and bad input
raising ValueError (coulomb.SceneError) naming the joint and the field."""

import math

import numpy as np
import pytest

from coulomb import SceneError
from coulomb.granular import Cuboid, Scene, Simulation

G = 9.81


def pendulum(amplitude=0.01):
    """A bar hanging from a hinge at the origin (axis y), given a small swing."""
    a, c = 0.02, 0.25
    m = 1000.0 * (2 * a) ** 2 * (2 * c)
    i = m * (a * a + c * c) / 3.0 + m * c * c
    w0 = amplitude * math.sqrt(m * G * c / i)
    s = Scene().set_gravity([0, 0, -G])
    s.add_body(Cuboid([a, a, c]), [0, 0, -c], density=1000.0,
               angular_velocity=[0, w0, 0], velocity=[-w0 * c, 0, 0])
    s.add_joint("revolute", 0, None, anchor=[0, 0, 0], axis=[0, 1, 0])
    return s, 2 * math.pi * math.sqrt(i / (m * G * c))


def test_pendulum_period_within_half_a_percent():
    s, period = pendulum()
    sim = Simulation(s)
    h = sim.params["h"]
    crossings, prev = [], 0.0
    for _ in range(int(2.2 * period / h)):
        sim.step()
        x = sim.body_positions[0][0]  # the bar's centre swings through x = 0
        if prev < 0.0 <= x:
            crossings.append(sim.time - h * x / (x - prev))
        prev = x
    assert len(crossings) >= 2
    measured = (crossings[-1] - crossings[0]) / (len(crossings) - 1)
    assert abs(measured - period) / period < 5e-3
    assert sim.joint_drift < 1e-9
    f = sim.joint_forces
    assert f.shape == (1, 6)


def test_body_count_in_insertion_order_and_joint_forces_of_a_chain():
    # a fixed ball first, then links: the joints name bodies in insertion order
    s = Scene()
    s.add_spheres([[1.0, 0.0, 0.0]], 0.05, fixed=True)
    assert s.body_count == 1
    n = 5
    for k in range(n):
        s.add_body(Cuboid([0.01, 0.01, 0.05]), [0, 0, -0.05 - 0.1 * k], density=1000.0)
    assert s.body_count == n + 1
    s.add_joint("spherical", 1, None, anchor=[0, 0, 0])
    for k in range(1, n):
        s.add_joint("spherical", k + 1, k, anchor=[0, 0, -0.1 * k])
    sim = Simulation(s, tol=1e-12, max_sweeps=20000)
    for _ in range(3):
        sim.step()
    f = sim.joint_forces
    assert f.shape == (n, 6)
    m = 1000.0 * 0.02 * 0.02 * 0.1
    weight = n * m * G
    assert abs(f[0, 2] - weight) <= 1e-8 * weight
    assert abs(f[-1, 2] - m * G) <= 1e-8 * weight
    # the links hang still
    assert np.abs(sim.velocities).max() < 1e-9


def test_a_scene_of_spheres_with_joints_runs_in_the_rigid_simulator():
    s = Scene()
    s.add_spheres([[0.0, 0.0, -0.5]], 0.05, density=1000.0)
    s.add_joint("spherical", 0, None, anchor=[0, 0, 0])
    assert s.has_shapes
    sim = Simulation(s)
    assert sim.is_rigid
    sim.run(10)
    # a ball on a rigid string: it stays at its distance
    assert abs(np.linalg.norm(sim.body_positions[0]) - 0.5) < 1e-9


@pytest.mark.parametrize("kwargs, field", [
    (dict(kind="revolute", body_a=5, body_b=None, anchor=[0, 0, 0], axis=[0, 0, 1]), "body_a"),
    (dict(kind="revolute", body_a=0, body_b=0, anchor=[0, 0, 0], axis=[0, 0, 1]), "body_b"),
    (dict(kind="revolute", body_a=0, body_b=7, anchor=[0, 0, 0], axis=[0, 0, 1]), "body_b"),
    (dict(kind="revolute", body_a=0, body_b=None, anchor=[0, math.nan, 0], axis=[0, 0, 1]),
     "anchor"),
    (dict(kind="revolute", body_a=0, body_b=None, anchor=[0, 0, 0], axis=[math.inf, 0, 1]),
     "axis"),
    (dict(kind="revolute", body_a=0, body_b=None, anchor=[0, 0], axis=[0, 0, 1]), "anchor"),
    (dict(kind="revolute", body_a="0", body_b=None, anchor=[0, 0, 0], axis=[0, 0, 1]), "body_a"),
])
def test_bad_joint_arguments_are_refused_at_once(kwargs, field):
    s = Scene()
    s.add_body(Cuboid([0.1, 0.1, 0.1]), [0, 0, 1])
    with pytest.raises(ValueError) as e:
        s.add_joint(**kwargs)
    assert isinstance(e.value, SceneError)
    assert e.value.field == field
    assert "joint 0" in str(e.value)


@pytest.mark.parametrize("kwargs, field", [
    (dict(kind="revolute", anchor=[0, 0, 0], axis=[0, 0, 0]), "axis"),
    (dict(kind="revolute", anchor=[0, 0, 0]), "axis"),
    (dict(kind="spherical", anchor=[0, 0, 0], axis=[0, 0, 1]), "axis"),
    (dict(kind="revolute", anchor=[0, 0, 0], axis=[0, 0, 1], limits=(1.0, -1.0)), "limits"),
    (dict(kind="revolute", anchor=[0, 0, 0], axis=[0, 0, 1],
          motor=dict(velocity=1.0, max_force=-2.0)), "motor.max_force"),
    (dict(kind="revolute", anchor=[0, 0, 0], axis=[0, 0, 1],
          motor=dict(velocity=1.0, position=0.5, max_force=2.0)), "motor: velocity and position"),
    (dict(kind="revolute", anchor=[0, 0, 0], axis=[0, 0, 1],
          motor=dict(position=0.5, max_force=-2.0)), "motor.max_force"),
    (dict(kind="revolute", anchor=[0, 0, 0], axis=[0, 0, 1],
          motor=dict(position=0.5, max_force=2.0, gain=0.0)), "motor.gain"),
    (dict(kind="revolute", anchor=[0, 0, 0], axis=[0, 0, 1], limit_restitution=0.5),
     "limit_restitution"),
    (dict(kind="revolute", anchor=[0, 0, 0], axis=[0, 0, 1], limits=(-1, 1),
          limit_restitution=2.0), "limit_restitution"),
    (dict(kind="revolute", anchor=[0, 0, 0], axis=[0, 0, 1], friction=-1.0), "friction"),
    (dict(kind="spherical", anchor=[0, 0, 0], friction=1.0), "friction"),
])
def test_bad_joints_are_refused_at_build(kwargs, field):
    s = Scene()
    s.add_body(Cuboid([0.1, 0.1, 0.1]), [0, 0, 1])
    s.add_joint(body_a=0, body_b=None, **kwargs)
    with pytest.raises(ValueError) as e:
        Simulation(s)
    assert "joint 0" in str(e.value) and field in str(e.value)


def test_both_bodies_fixed_and_an_unknown_kind_are_refused():
    s = Scene()
    s.add_body(Cuboid([0.1, 0.1, 0.1]), [0, 0, 1], fixed=True)
    s.add_joint("fixed", 0, None, anchor=[0, 0, 1])
    with pytest.raises(ValueError, match="joint 0: body_a: both parties are fixed"):
        Simulation(s)
    s = Scene()
    s.add_body(Cuboid([0.1, 0.1, 0.1]), [0, 0, 1])
    s.add_joint("hinge", 0, None, anchor=[0, 0, 1])
    with pytest.raises(ValueError, match="hinge"):
        Simulation(s)


def test_readme_pendulum_chain_runs_as_written(capsys):
    from conftest import REPO
    text = (REPO / "README.md").read_text(encoding="utf-8")
    start = text.index("```python\n", text.index("### Joints")) + len("```python\n")
    exec(compile(text[start:text.index("```", start)], "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert out.strip()


def test_a_position_servo_settles_and_a_limit_with_restitution_rebounds():
    # a bar hanging from a hinge, servoed to 0.8 rad (gain 10 / s by default)
    a, c = 0.02, 0.25
    s = Scene().set_gravity([0, 0, -G])
    s.add_body(Cuboid([a, a, c]), [0, 0, -c], density=1000.0)
    s.add_joint("revolute", 0, None, anchor=[0, 0, 0], axis=[0, 1, 0],
                motor=dict(position=0.8, max_force=5.0))
    sim = Simulation(s)
    sim.run(3000)
    # the bar's centre is at 0.8 rad from the vertical
    x, _, z = sim.body_positions[0]
    assert abs(math.atan2(abs(x), -z) - 0.8) < 1e-6
    assert np.abs(sim.angular_velocities).max() < 1e-6
    # a plate turning at 2 rad/s on a vertical hinge into its limit at 0.5 rad, e = 1
    s = Scene().set_gravity([0, 0, -G])
    s.add_body(Cuboid([0.1, 0.1, 0.02]), [0, 0, 1], density=1000.0,
               angular_velocity=[0, 0, 2.0])
    s.add_joint("revolute", 0, None, anchor=[0, 0, 1], axis=[0, 0, 1], limits=(-0.5, 0.5),
                limit_restitution=1.0)
    sim = Simulation(s)
    sim.run(350)
    assert abs(sim.angular_velocities[0][2] + 2.0) < 1e-8


def test_joint_friction_brakes_a_spinning_plate():
    # friction torque 0.05 N m on a plate spinning at 2 rad/s about a vertical hinge
    s = Scene().set_gravity([0, 0, -G])
    s.add_body(Cuboid([0.1, 0.1, 0.02]), [0, 0, 1], density=1000.0,
               angular_velocity=[0, 0, 2.0])
    s.add_joint("revolute", 0, None, anchor=[0, 0, 1], axis=[0, 0, 1], friction=0.05)
    sim = Simulation(s)
    sim.run(200)
    i = 1000.0 * 0.2 * 0.2 * 0.04 * 0.02 / 3.0
    assert abs(sim.angular_velocities[0][2] - (2.0 - 0.05 / i * sim.time)) < 1e-9
    sim.run(600)
    assert abs(sim.angular_velocities[0][2]) < 1e-9
