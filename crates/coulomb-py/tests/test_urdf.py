"""URDF import from Python (issue 53): Scene.add_urdf returns the links' body indices in
insertion order, builds the same robot as the scene file's [[urdf]] (the shipped double
pendulum) and the same as the bodies and joints written by hand, simulates, and refuses bad
input with coulomb.SceneError naming the URDF file and the element (OSError for a missing
file)."""

import math
from pathlib import Path

import numpy as np
import pytest

from coulomb import SceneError
from coulomb.granular import Compound, Cuboid, Scene, Simulation

RIGID = Path(__file__).resolve().parents[3] / "examples" / "scenes" / "rigid"
URDF = RIGID / "double-pendulum.urdf"
# the robot's placement in double-pendulum-urdf.toml: turned by 0.5 rad about y
Q = (math.cos(0.25), 0.0, -math.sin(0.25), 0.0)
P = (0.0, 0.0, 1.2)


def rotate(q, v):
    w, x, y, z = q
    u = np.array([x, y, z])
    v = np.asarray(v, dtype=float)
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def test_add_urdf_returns_the_links_body_indices_after_the_bodies_before():
    s = Scene()
    s.add_body(Cuboid([0.1, 0.1, 0.1]), [3, 0, 1])
    ids = s.add_urdf(URDF, position=P, orientation=Q, fixed_base=True)
    assert ids == [1, 2, 3]
    assert s.body_count == 4
    assert s.joint_count == 2
    # a joint of the user's own to a link of the robot, by the returned index
    s.add_joint("spherical", 0, ids[2], anchor=[3, 0, 1])
    assert s.joint_count == 3


def test_add_urdf_is_the_scene_file_and_the_hand_written_robot():
    s = Scene()
    s.add_urdf(str(URDF), position=P, orientation=Q, fixed_base=True)
    sim = Simulation(s)
    from_file = Simulation.from_file(RIGID / "double-pendulum-urdf.toml")
    np.testing.assert_allclose(sim.body_positions, from_file.body_positions, atol=1e-15)
    np.testing.assert_allclose(sim.masses, [1.0, 0.8, 0.8], rtol=1e-12)
    # written by hand: each link a body whose shape frame is the link frame (a one-part
    # compound placing the cuboid), hinges at the origin and at the elbow
    h = Scene()
    at = lambda z: np.array(P) + rotate(Q, [0, 0, z])  # noqa: E731
    part = lambda half, z: Compound([(Cuboid(half), [0, 0, z], (1, 0, 0, 0))])  # noqa: E731
    h.add_body(part([0.05, 0.05, 0.025], 0.05), P, orientation=Q, mass=1.0, fixed=True)
    h.add_body(part([0.02, 0.02, 0.25], -0.25), P, orientation=Q, density=1000.0)
    h.add_body(part([0.02, 0.02, 0.25], -0.25), at(-0.5), orientation=Q, density=1000.0)
    axis = rotate(Q, [0, 1, 0])
    h.add_joint("revolute", 1, 0, anchor=P, axis=axis)
    h.add_joint("revolute", 2, 1, anchor=at(-0.5), axis=axis)
    hand = Simulation(h)
    # the links' frames (body_positions) and masses the same before and after 200 steps
    np.testing.assert_allclose(sim.body_positions, hand.body_positions, atol=1e-12)
    np.testing.assert_allclose(sim.masses, hand.masses, rtol=1e-12)
    start = sim.body_positions.copy()
    sim.run(200)
    hand.run(200)
    np.testing.assert_allclose(sim.body_positions, hand.body_positions, atol=1e-9)
    assert np.linalg.norm(sim.body_positions[2] - start[2]) > 0.01  # it swings
    assert sim.joint_drift < 1e-6


def test_add_body_takes_a_centre_of_mass_with_its_inertia():
    # a cube hinged at its centre: balanced with its own centre of mass, it swings with one
    # moved 5 cm along x
    def hinged(com):
        s = Scene()
        s.add_body(Cuboid([0.1, 0.1, 0.1]), [0, 0, 1], mass=1.0, inertia=np.eye(3) * 0.01,
                   centre_of_mass=com)
        s.add_joint("revolute", 0, None, anchor=[0, 0, 1], axis=[0, 1, 0])
        sim = Simulation(s)
        sim.run(100)
        return sim.body_orientations[0]
    np.testing.assert_allclose(hinged(None), [1, 0, 0, 0], atol=1e-12)
    assert abs(hinged([0.05, 0, 0])[2]) > 0.01
    # without inertia, refused
    s = Scene()
    s.add_body(Cuboid([0.1, 0.1, 0.1]), [0, 0, 1], mass=1.0, centre_of_mass=[0, 0, -0.05])
    with pytest.raises(SceneError, match="centre_of_mass"):
        Simulation(s)


LINK = ('<link name="{name}"><inertial><mass value="{mass}"/><inertia ixx="0.01" ixy="0" '
        'ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial><collision><geometry>{geometry}'
        '</geometry></collision></link>')
BOX = '<box size="0.1 0.1 0.1"/>'


def link(name, geometry=BOX, mass=1.0):
    return LINK.format(name=name, geometry=geometry, mass=mass)


def joint(name, kind, parent, child):
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{child}"/><axis xyz="0 1 0"/></joint>')


@pytest.mark.parametrize("body, kind, words", [
    (link("a") + joint("j", "continuous", "a", "ghost"), "unknown_link", "'ghost'"),
    (link("a") + link("b") + joint("free", "floating", "a", "b"), "unsupported_joint",
     "joint 'free'"),
    (link("a") + link("b") + joint("flat", "planar", "a", "b"), "unsupported_joint",
     "joint 'flat'"),
    (link("a", mass=0.0), "link", "link 'a'"),
    (link("a", mass=-2.0), "link", "mass -2"),
    (link("a") + link("b") + joint("ab", "continuous", "a", "b")
     + joint("ba", "continuous", "b", "a"), "tree", "cycle"),
    (link("a") + link("b") + link("c") + joint("ac", "continuous", "a", "c")
     + joint("bc", "continuous", "b", "c"), "tree", "two parents"),
    (link("m", '<mesh filename="package://arm/m.stl"/>'), "package_uri", "package://"),
    (link("m", '<mesh filename="m.dae"/>'), "unsupported_geometry", "link 'm'"),
])
def test_bad_urdf_is_refused_naming_the_file_and_the_element(tmp_path, body, kind, words):
    path = tmp_path / "bad.urdf"
    path.write_text(f'<robot name="r">{body}</robot>')
    with pytest.raises(SceneError) as e:
        Scene().add_urdf(path)
    assert e.value.kind == kind
    assert "bad.urdf" in str(e.value) and words in str(e.value), str(e.value)


def test_malformed_missing_and_misplaced_urdf_are_refused(tmp_path):
    path = tmp_path / "broken.urdf"
    path.write_text('<robot name="r"><link name="a">')
    with pytest.raises(SceneError) as e:
        Scene().add_urdf(path)
    assert e.value.kind == "xml" and "broken.urdf" in str(e.value)
    with pytest.raises(FileNotFoundError):
        Scene().add_urdf(tmp_path / "none.urdf")
    with pytest.raises(SceneError) as e:
        Scene().add_urdf(URDF, orientation=(1, 0, 0, 0.5))
    assert e.value.kind == "options"
    with pytest.raises(ValueError):
        Scene().add_urdf(URDF, position=(0, 0, float("nan")))
    # nothing was added by the refused calls
    s = Scene()
    with pytest.raises(SceneError):
        s.add_urdf(path)
    assert s.body_count == 0 and s.joint_count == 0


def test_a_scene_with_a_urdf_robot_saves_as_its_bodies_and_joints(tmp_path):
    s = Scene()
    s.add_urdf(URDF, position=P, orientation=Q, fixed_base=True)
    path = tmp_path / "robot.toml"
    s.save(path)
    text = path.read_text()
    assert "centre_of_mass" in text and "[[joints]]" in text and "[[urdf]]" not in text
    a, b = Simulation(s), Simulation.from_file(path)
    a.run(50)
    b.run(50)
    np.testing.assert_array_equal(a.body_positions, b.body_positions)
