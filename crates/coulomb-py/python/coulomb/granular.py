"""Granular media by Moreau–Jean time stepping (2.5)–(2.7) of rigid spheres
(``coulomb_granular``): at each step the active contacts are detected, the incremental
problem (2.10) is assembled and solved by :func:`coulomb.solve`'s library solver, and the
velocities and positions are updated by the θ-method.

Build your own scene with :class:`Scene` (spheres from numpy arrays, planes, boxes, cylinders,
meshes, moving walls, materials with per-pair laws) and run it with :class:`Simulation`.
Steer a run step by step with :class:`Simulation` (``step()``, ``sim.run(n)``,
``set_velocities``, ``set_params``), or run it at once with :func:`simulate` and a callback.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _coulomb
from ._errors import SceneError
from ._problem import GlobalProblem, Problem

__all__ = ["SCENES", "Motion", "Region", "Scene", "Simulation", "SimulationResult", "simulate",
           "Sphere", "Cuboid", "Capsule", "Cylinder", "Cone", "ConvexHull", "ConvexPolyhedron",
           "Compound"]

#: the scenes of ``coulomb_granular::Scene``
SCENES = ("box", "funnel", "vibrating-plate", "rotating-drum")

#: one step's record (``coulomb_granular::StepRecord``), the same keys for every scene (sphere
#: or rigid) and the columns of ``stats.csv`` (docs/python.md): step, time, status, converged,
#: error (docs/error.md), contacts, warm_started, iterations, solve_seconds, kinetic_energy,
#: potential_energy, max_penetration
StepStats = Dict[str, Any]


# --------------------------------------------------------------------------------------------
# Scenes of your own
# --------------------------------------------------------------------------------------------

def _arg_error(field_: str, msg: str, index: Any = None) -> SceneError:
    e = SceneError(msg)
    e.kind, e.field, e.index = "argument", field_, index
    return e


def _real(name: str, x: Any, positive: bool = False, nonnegative: bool = False) -> float:
    try:
        v = float(x)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a number, got {x!r}") from None
    if not math.isfinite(v) or (positive and v <= 0.0) or (nonnegative and v < 0.0):
        want = "positive" if positive else "nonnegative" if nonnegative else "finite"
        raise _arg_error(name, f"{name} = {v} must be a {want} finite number")
    return v


def _vec3(name: str, v: Any) -> List[float]:
    try:
        a = np.asarray(v, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be 3 numbers, got {v!r}") from None
    if a.shape != (3,):
        raise _arg_error(name, f"{name} must be 3 numbers [x, y, z], got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise _arg_error(name, f"{name} = {a.tolist()} must be finite")
    return [float(x) for x in a]


def _vec3_any(name: str, v: Any, index: int) -> np.ndarray:
    """Three numbers, finite or not (the build names what is not finite)."""
    try:
        a = np.asarray(v, dtype=np.float64)
    except (TypeError, ValueError):
        raise _arg_error(name, f"joint {index}: {name} must be 3 numbers, got {v!r}", index)
    if a.shape != (3,):
        raise _arg_error(name, f"joint {index}: {name} must be 3 numbers, got {v!r}", index)
    if not np.all(np.isfinite(a)):
        raise _arg_error(name, f"joint {index}: {name} {a.tolist()} is not finite", index)
    return a


def _unit(name: str, v: Any) -> List[float]:
    a = np.array(_vec3(name, v))
    n = float(np.linalg.norm(a))
    if n == 0.0:
        raise _arg_error(name, f"{name} must not be the zero vector")
    return [float(x) for x in a / n]


def _array(name: str, x: Any, dtype: Any = np.float64) -> np.ndarray:
    try:
        return np.array(x, dtype=dtype, order="C", copy=True)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be an array of numbers") from None


def _rows3(name: str, x: Any, n: Optional[int] = None) -> np.ndarray:
    a = _array(name, x)
    if a.ndim == 1 and a.shape[0] == 3 and n in (None, 1):
        a = a.reshape(1, 3)
    if a.ndim != 2 or a.shape[1] != 3 or (n is not None and a.shape[0] != n):
        want = "(n, 3)" if n is None else f"({n}, 3)"
        raise _arg_error(name, f"{name} must have shape {want}, got {a.shape}")
    return a


def _material(name: Any) -> str:
    if not isinstance(name, str) or not name:
        raise TypeError(f"material must be a non-empty string, got {name!r}")
    return name


class Motion:
    """Prescribed motions of obstacles (the serde form of ``coulomb_granular::Motion``, plain
    dicts: ``{"kind": "rotate", "center": [...], "axis": [...], "omega": 1.0}``, which may
    be passed as such). Directions and axes are normalized here."""

    @staticmethod
    def fixed() -> Dict[str, Any]:
        """Motionless (the default)."""
        return {"kind": "fixed"}

    @staticmethod
    def translate(velocity: Sequence[float]) -> Dict[str, Any]:
        """Translation d(t) = v t at constant velocity v (m/s)."""
        return {"kind": "translate", "velocity": _vec3("velocity", velocity)}

    @staticmethod
    def oscillate(direction: Sequence[float], amplitude: float,
                  frequency: float) -> Dict[str, Any]:
        """Translation d(t) = A sin(2π f t) · direction (amplitude A in m, frequency f in
        Hz): a vibrating wall or plate."""
        return {"kind": "oscillate", "direction": _unit("direction", direction),
                "amplitude": _real("amplitude", amplitude),
                "frequency": _real("frequency", frequency)}

    @staticmethod
    def rotate(center: Sequence[float], axis: Sequence[float], omega: float) -> Dict[str, Any]:
        """Rotation by the angle ω t (ω in rad/s, right-handed) about the line through
        ``center`` along ``axis``: a rotating drum, a stirrer."""
        return {"kind": "rotate", "center": _vec3("center", center),
                "axis": _unit("axis", axis), "omega": _real("omega", omega)}


def _motion(m: Any) -> Dict[str, Any]:
    if m is None:
        return Motion.fixed()
    if not isinstance(m, Mapping) or "kind" not in m:
        raise TypeError("motion must be a dict with a 'kind' (see coulomb.granular.Motion), "
                        f"got {m!r}")
    return dict(m)


class Region:
    """Regions for :meth:`Scene.fill` (plain dicts, the serde form of
    ``coulomb_granular::generate::Shape``)."""

    @staticmethod
    def box(lo: Sequence[float], hi: Sequence[float]) -> Dict[str, Any]:
        """The box [lo, hi]."""
        return {"kind": "box", "lo": _vec3("lo", lo), "hi": _vec3("hi", hi)}

    @staticmethod
    def cylinder(base: Sequence[float], axis: Sequence[float], radius: float,
                 height: float) -> Dict[str, Any]:
        """The solid cylinder of ``radius`` whose axis runs from ``base`` along ``axis``
        over ``height``."""
        return {"kind": "cylinder", "base": _vec3("base", base), "axis": _unit("axis", axis),
                "radius": _real("radius", radius), "height": _real("height", height)}


    @staticmethod
    def mesh(vertices: Any, triangles: Any) -> Dict[str, Any]:
        """The interior of a closed, consistently oriented triangle mesh (vertices (n, 3),
        triangles (m, 3) integer indices)."""
        v = _rows3("vertices", vertices)
        t = _triangles(triangles)
        return {"kind": "mesh", "vertices": v, "triangles": t}


def _triangles(triangles: Any) -> np.ndarray:
    """Triangles (m, 3) of nonnegative integer vertex indices, as uint64."""
    t = np.asarray(triangles)
    if t.dtype.kind not in "iu":
        raise TypeError(f"triangles must be integers, got dtype {t.dtype}")
    if t.ndim != 2 or t.shape[1] != 3:
        raise _arg_error("triangles", f"triangles must have shape (m, 3), got {t.shape}")
    if t.size and t.min() < 0:
        k = int(np.argmin(t.min(axis=1)))
        raise _arg_error("triangles", f"triangle {k} has a negative vertex index", k)
    return np.ascontiguousarray(t, dtype=np.uint64)


def _sizes(radius: Any) -> Dict[str, Any]:
    """A size distribution: a radius (mono) or a dict of
    ``coulomb_granular::generate::SizeDistribution``."""
    if isinstance(radius, Mapping):
        return dict(radius)
    return {"kind": "mono", "radius": _real("radius", radius, positive=True)}


# --------------------------------------------------------------------------------------------
# Body shapes (coulomb_granular::shape::BodyShape): for Scene.add_body
# --------------------------------------------------------------------------------------------

class _Shape:
    """A body shape in its shape frame; ``spec`` is its serde form (a dict with ``kind``).
    Round shapes (capsule, cylinder, cone) have their axis along the shape frame's **y** axis
    (parry3d's convention). Values are validated in Rust when the scene is built (degenerate
    hulls, zero volume, aspect ratio above 1000: :class:`coulomb.SceneError`)."""

    kind = ""

    def __init__(self, **spec: Any) -> None:
        self.spec: Dict[str, Any] = {"kind": self.kind, **spec}

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.spec.items() if k != "kind")
        return f"{type(self).__name__}({args})"


class Sphere(_Shape):
    """A ball of radius R."""
    kind = "sphere"

    def __init__(self, radius: float) -> None:
        super().__init__(radius=_real("radius", radius))


class Cuboid(_Shape):
    """A box of half-extents (a, b, c) along the shape frame's x, y, z, centred."""
    kind = "cuboid"

    def __init__(self, half_extents: Sequence[float]) -> None:
        super().__init__(half_extents=_vec3("half_extents", half_extents))


class Capsule(_Shape):
    """The points within ``radius`` of the segment from (0, −half_height, 0) to
    (0, half_height, 0): axis along y."""
    kind = "capsule"

    def __init__(self, radius: float, half_height: float) -> None:
        super().__init__(radius=_real("radius", radius),
                         half_height=_real("half_height", half_height))


class Cylinder(_Shape):
    """A circular cylinder about the y axis, from y = −half_height to half_height."""
    kind = "cylinder"

    def __init__(self, radius: float, half_height: float) -> None:
        super().__init__(radius=_real("radius", radius),
                         half_height=_real("half_height", half_height))


class Cone(_Shape):
    """A circular cone about the y axis: base of ``radius`` at y = −half_height, apex at
    y = half_height."""
    kind = "cone"

    def __init__(self, radius: float, half_height: float) -> None:
        super().__init__(radius=_real("radius", radius),
                         half_height=_real("half_height", half_height))


class ConvexHull(_Shape):
    """The convex hull of ``points`` ((n, 3), n ≥ 4, not coplanar)."""
    kind = "convex_hull"

    def __init__(self, points: Any) -> None:
        super().__init__(points=_rows3("points", points).tolist())


class ConvexPolyhedron(_Shape):
    """A convex polyhedron: ``vertices`` (n, 3) and ``faces``, polygons of vertex indices
    counter-clockwise seen from outside."""
    kind = "convex_polyhedron"

    def __init__(self, vertices: Any, faces: Sequence[Sequence[int]]) -> None:
        super().__init__(vertices=_rows3("vertices", vertices).tolist(),
                         faces=[[int(i) for i in f] for f in faces])


def _quaternion(name: str, q: Any) -> List[float]:
    try:
        a = np.asarray(q, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be 4 numbers (w, x, y, z), got {q!r}") from None
    if a.shape != (4,):
        raise _arg_error(name, f"{name} must be 4 numbers (w, x, y, z), got shape {a.shape}")
    return [float(x) for x in a]  # unit norm checked in Rust: refused, never normalized


class Compound(_Shape):
    """A union of convex parts: ``[(shape, position, orientation), ...]`` (orientation a
    unit quaternion (w, x, y, z); parts are not compounds)."""
    kind = "compound"

    def __init__(self, parts: Sequence[Tuple[Any, ...]]) -> None:
        out = []
        for k, part in enumerate(parts):
            if not isinstance(part, (tuple, list)) or len(part) not in (2, 3):
                raise TypeError(f"parts[{k}] must be (shape, position[, orientation])")
            shape, position = part[0], part[1]
            orientation = part[2] if len(part) == 3 else (1.0, 0.0, 0.0, 0.0)
            out.append({"shape": _shape_spec(shape), "position": _vec3("position", position),
                        "orientation": _quaternion("orientation", orientation)})
        super().__init__(parts=out)


def _shape_spec(shape: Any) -> Dict[str, Any]:
    if isinstance(shape, _Shape):
        return dict(shape.spec)
    if isinstance(shape, Mapping) and "kind" in shape:
        return dict(shape)
    raise TypeError("shape must be a coulomb.granular shape (Cuboid, Capsule, Cylinder, Cone, "
                    f"ConvexHull, ConvexPolyhedron, Compound, Sphere), got {shape!r}")


class Scene:
    """A granular scene of your own: spheres, obstacles (planes, boxes, cylinders, spheres,
    triangle meshes) with prescribed motions, gravity and materials with per-pair contact
    laws — the Python face of ``coulomb_granular::SceneModel``.

    Obstacles, materials and gravity are kept as plain data, the spheres as numpy arrays;
    :class:`Simulation` hands them to Rust (one JSON description plus the arrays), where the
    scene is validated and built without the GIL. Materials are names: ``"default"`` always
    exists, others are declared by :meth:`add_material` or by using them; a pair of
    :meth:`set_material_pair` naming a material declared nowhere is refused at build.

    Every ``add_*`` method returns the scene, so calls chain. Lengths in m, masses in kg.
    """

    def __init__(self) -> None:
        self._gravity: List[float] = [0.0, 0.0, -9.81]
        self._names: List[str] = []
        self._default_law: Dict[str, float] = {"mu": 0.3, "restitution": 0.2,
                                               "rolling_friction": 0.0}
        self._pairs: Dict[Tuple[str, str], Dict[str, Any]] = {}
        self._obstacles: List[Dict[str, Any]] = []
        self._meshes: List[Tuple[np.ndarray, np.ndarray]] = []
        # (description, (positions, radii, velocities, angular velocities, masses))
        self._batches: List[Tuple[Dict[str, Any], Tuple[np.ndarray, ...]]] = []
        self._inlets: List[Dict[str, Any]] = []
        # bodies of any shape (coulomb_granular::BodySpec dicts)
        self._bodies: List[Dict[str, Any]] = []
        # insertion order of the bodies: ("body", index in _bodies) or ("batch", index in
        # _batches), one entry per body (a batch's spheres one after the other)
        self._order: List[Tuple[str, int, int]] = []
        # joints (coulomb_granular::rigid::joints::JointDesc dicts, bodies in insertion order)
        self._joints: List[Dict[str, Any]] = []

    # -- materials and gravity --------------------------------------------------------------

    def _use(self, material: Any) -> str:
        m = _material(material)
        if m != "default" and m not in self._names:
            self._names.append(m)
        return m

    def add_material(self, name: str) -> "Scene":
        """Declares the material ``name`` (materials are also declared by using them)."""
        self._use(name)
        return self

    @property
    def materials(self) -> List[str]:
        """The material names: ``default``, then the others in order of declaration."""
        return ["default"] + list(self._names)

    def set_default_law(self, mu: float = 0.3, restitution: float = 0.2,
                        rolling_friction: float = 0.0) -> "Scene":
        """The contact law of every pair of materials not set by :meth:`set_material_pair`:
        friction μ of Coulomb's cone (2.9), Newton restitution e ∈ [0, 1], rolling
        friction μ_r (docs/granular.md, "Rolling resistance")."""
        self._default_law = {"mu": _real("mu", mu), "restitution": _real("restitution",
                                                                         restitution),
                             "rolling_friction": _real("rolling_friction", rolling_friction)}
        return self

    def set_material_pair(self, a: str, b: str, mu: float = 0.3, restitution: float = 0.2,
                          rolling_friction: float = 0.0) -> "Scene":
        """The contact law (μ, e, μ_r) of contacts between materials ``a`` and ``b`` (the
        same for (b, a); set again, it replaces the earlier law). The materials must be
        declared (used, or :meth:`add_material`) by the time the scene is built."""
        a, b = _material(a), _material(b)
        self._pairs[(min(a, b), max(a, b))] = {
            "materials": [a, b], "mu": _real("mu", mu),
            "restitution": _real("restitution", restitution),
            "rolling_friction": _real("rolling_friction", rolling_friction)}
        return self

    def set_gravity(self, g: Sequence[float]) -> "Scene":
        """The gravity vector (m/s², default (0, 0, −9.81))."""
        self._gravity = _vec3("gravity", g)
        return self

    @property
    def gravity(self) -> np.ndarray:
        """The gravity vector."""
        return np.array(self._gravity)

    # -- spheres ----------------------------------------------------------------------------

    def add_spheres(self, positions: Any, radii: Any, density: Optional[float] = 2500.0,
                    velocities: Any = None, material: str = "default",
                    angular_velocities: Any = None, masses: Any = None,
                    fixed: bool = False) -> "Scene":
        """Adds spheres from arrays: ``positions`` (n, 3) centres, ``radii`` (n,) or one
        radius for all, ``density`` (kg/m³; mass ρ 4/3 π R³) or ``masses`` ((n,) or one for
        all; then ``density`` is ignored), ``velocities`` and ``angular_velocities`` (n, 3)
        (default at rest), one ``material``. ``fixed=True`` makes them immobile obstacles.

        The arrays are copied and passed to Rust as one column batch at build (10⁶ spheres
        build in about a second); values are validated there (non-finite or nonpositive
        radius → :class:`coulomb.SceneError` with ``field="radii"`` and the sphere's index).
        """
        pos = _rows3("positions", positions)
        n = pos.shape[0]
        r = _array("radii", radii)
        if r.ndim == 0:
            r = r.reshape(1)
        if r.ndim != 1 or r.shape[0] not in (1, n):
            raise _arg_error("radii", f"radii must be one number or shape ({n},), got {r.shape}")
        empty = np.zeros(0)
        vel = empty if velocities is None else _rows3("velocities", velocities, n).ravel()
        ang = (empty if angular_velocities is None
               else _rows3("angular_velocities", angular_velocities, n).ravel())
        desc: Dict[str, Any] = {"positions": [], "radii": [], "material": self._use(material),
                                "fixed": bool(fixed)}
        if masses is not None:
            m = _array("masses", masses)
            if m.ndim == 0:
                m = m.reshape(1)
            if m.ndim != 1 or m.shape[0] not in (1, n):
                raise _arg_error("masses",
                                 f"masses must be one number or shape ({n},), got {m.shape}")
        else:
            if density is None:
                raise _arg_error("density", "give a density or masses")
            desc["density"] = _real("density", density)
            m = empty
        self._order.extend(("batch", len(self._batches), k) for k in range(n))
        self._batches.append((desc, (pos.ravel(), r, vel, ang, m)))
        return self

    def add_body(self, shape: Any, position: Sequence[float],
                 orientation: Sequence[float] = (1, 0, 0, 0), velocity: Any = None,
                 angular_velocity: Any = None, density: Optional[float] = 2500.0,
                 material: str = "default", mass: Optional[float] = None,
                 inertia: Any = None, fixed: bool = False,
                 centre_of_mass: Optional[Sequence[float]] = None) -> "Scene":
        """Adds one body of any shape (:class:`Cuboid`, :class:`Capsule`, :class:`Cylinder`,
        :class:`Cone`, :class:`ConvexHull`, :class:`ConvexPolyhedron`, :class:`Compound`,
        :class:`Sphere`): the origin of its shape frame at ``position``, turned by the unit
        quaternion ``orientation`` (w, x, y, z; refused when not of unit norm, never
        normalized), with ``velocity`` (of the centre of mass) and ``angular_velocity``
        (world frame). Mass and inertia from ``density`` (kg/m³), or ``mass`` (kg, a uniform
        body of that mass); ``inertia`` (3 × 3, about the centre of mass, shape-frame axes)
        replaces the shape's, and ``centre_of_mass`` (shape frame, with ``inertia``: the
        tensor about it; not for spheres) the shape's centroid (the scene files'
        ``centre_of_mass``). A scene with any body that is not a sphere runs in the
        rigid-body simulator (spheres become balls there)."""
        body: Dict[str, Any] = {
            "shape": _shape_spec(shape), "position": _vec3("position", position),
            "orientation": _quaternion("orientation", orientation),
            "velocity": _vec3("velocity", (0, 0, 0) if velocity is None else velocity),
            "angular_velocity": _vec3("angular_velocity",
                                      (0, 0, 0) if angular_velocity is None
                                      else angular_velocity),
            "material": self._use(material), "fixed": bool(fixed)}
        if mass is not None:
            body["mass"] = _real("mass", mass, positive=True)
        else:
            if density is None:
                raise _arg_error("density", "give a density or a mass")
            body["density"] = _real("density", density, positive=True)
        if inertia is not None:
            i = _array("inertia", inertia)
            if i.shape != (3, 3):
                raise _arg_error("inertia", f"inertia must be 3 x 3, got shape {i.shape}")
            body["inertia"] = i.tolist()
        if centre_of_mass is not None:
            body["centre_of_mass"] = _vec3("centre_of_mass", centre_of_mass)
        self._order.append(("body", len(self._bodies), 0))
        self._bodies.append(body)
        return self

    @property
    def body_count(self) -> int:
        """Number of bodies, spheres of :meth:`add_spheres` (and :meth:`fill`) and bodies of
        :meth:`add_body` together: the bodies are numbered from 0 in insertion order (the
        indices of :meth:`add_joint`)."""
        return len(self._order)

    def add_joint(self, kind: str, body_a: int, body_b: Optional[int], anchor: Sequence[float],
                  axis: Optional[Sequence[float]] = None,
                  limits: Optional[Sequence[float]] = None,
                  motor: Optional[Mapping[str, float]] = None,
                  limit_restitution: Optional[float] = None,
                  friction: Optional[float] = None) -> "Scene":
        """Adds a joint between bodies ``body_a`` and ``body_b`` (indices in insertion order,
        :attr:`body_count`; ``body_b=None``: the world). ``kind``: ``"revolute"`` (hinge),
        ``"spherical"`` (ball), ``"prismatic"`` (slider), ``"cylindrical"``, ``"fixed"``
        (weld). ``anchor`` and ``axis`` (revolute, prismatic, cylindrical) are in world
        coordinates at the initial configuration. ``limits=(lo, hi)`` bounds the joint
        coordinate of a revolute (angle of A relative to B about the axis, rad, within
        [−π, π]) or prismatic joint (travel, m); ``limit_restitution`` ∈ [0, 1] (with
        ``limits``, default 0) is the limits' Newton restitution: 0 stops the coordinate, 1
        sends it back at its speed. ``motor=dict(velocity=..., max_force=...)`` drives its
        rate with at most ``max_force`` (N m or N); ``motor=dict(position=..., max_force=...,
        gain=...)`` is a position servo, target rate ``gain * (position - coordinate)``
        (``gain`` in 1/s, default 10). ``friction`` (N m or N, ≥ 0) is a friction torque or
        force opposing the coordinate's rate (revolute, prismatic). The joint's two bodies do not
        collide with each other. A scene with joints runs in the rigid-body simulator
        (spheres become balls). Bad input raises :class:`coulomb.SceneError` (a
        ``ValueError``) naming the field; the rest (zero axis, lo > hi, both bodies fixed, …)
        is checked at build, naming the joint. docs/joints.md has the model."""
        k = len(self._joints)
        if not isinstance(kind, str):
            raise _arg_error("kind", f"joint {k}: kind must be a string", k)
        j: Dict[str, Any] = {"kind": kind}
        for name, b in (("body_a", body_a), ("body_b", body_b)):
            if b is None and name == "body_b":
                continue
            if isinstance(b, bool) or not isinstance(b, (int, np.integer)):
                raise _arg_error(name, f"joint {k}: {name} must be a body index, got {b!r}", k)
            if not 0 <= int(b) < self.body_count:
                raise _arg_error(name, f"joint {k}: {name} = {b}: no such body (the scene has "
                                 f"{self.body_count} bodies; add them before their joints)", k)
            j[name] = int(b)
        if body_b is not None and int(body_b) == int(body_a):
            raise _arg_error("body_b", f"joint {k}: a joint of body {body_a} with itself", k)
        j["anchor"] = [float(x) for x in _vec3_any("anchor", anchor, k)]
        if axis is not None:
            j["axis"] = [float(x) for x in _vec3_any("axis", axis, k)]
        if limits is not None:
            lim = np.asarray(limits, dtype=np.float64)
            if lim.shape != (2,):
                raise _arg_error("limits", f"joint {k}: limits must be (lo, hi), got {limits!r}",
                                 k)
            if not np.all(np.isfinite(lim)):
                raise _arg_error("limits", f"joint {k}: limits {lim.tolist()} are not finite", k)
            j["limits"] = [float(lim[0]), float(lim[1])]
        for name, x in (("limit_restitution", limit_restitution), ("friction", friction)):
            if x is None:
                continue
            try:
                j[name] = float(x)
            except (TypeError, ValueError):
                raise _arg_error(name, f"joint {k}: {name} must be a number, got {x!r}",
                                 k) from None
            if not np.isfinite(j[name]):
                raise _arg_error(name, f"joint {k}: {name} {j[name]} is not finite", k)
        if motor is not None:
            allowed = {"velocity", "position", "gain", "max_force"}
            if (not isinstance(motor, Mapping) or "max_force" not in motor
                    or not set(motor) <= allowed):
                raise _arg_error("motor", f"joint {k}: motor must be dict(velocity=..., "
                                 f"max_force=...) or dict(position=..., max_force=..., "
                                 f"gain=...), got {motor!r}", k)
            mv = {name: float(x) for name, x in motor.items()}
            for name, x in mv.items():
                if not np.isfinite(x):
                    raise _arg_error(f"motor.{name}", f"joint {k}: motor {name} {x} is not finite",
                                     k)
            j["motor"] = mv
        self._joints.append(j)
        return self

    def add_urdf(self, path: Union[str, "os.PathLike[str]"],
                 position: Sequence[float] = (0.0, 0.0, 0.0),
                 orientation: Sequence[float] = (1, 0, 0, 0), fixed_base: bool = False,
                 material: str = "default") -> List[int]:
        """Adds the robot of the URDF file ``path`` (issue 53; docs/joints.md, "URDF import";
        the same import as a scene file's ``[[urdf]]``): each ``<link>`` becomes a body (its
        ``inertial`` mass, centre of mass and inertia tensor, its ``<collision>`` box,
        cylinder, capsule, sphere and ``.stl``/``.obj`` mesh (convex hull; relative paths
        from the URDF file's folder) as its shape), each joint a joint (``revolute`` and
        ``continuous``: revolute, ``prismatic``, ``fixed``; ``limit lower/upper`` as limits,
        ``effort``/``velocity`` unused: add a motor with :meth:`add_joint` if you want one).
        The root link's frame is put at ``position``, turned by the unit quaternion
        ``orientation`` (w, x, y, z), and is free, or fixed to the world with
        ``fixed_base=True``; every link gets ``material``.

        Returns the body indices (insertion order, :attr:`body_count`) of the links, in the
        order of the file's ``<link>`` elements. Bad input raises
        :class:`coulomb.SceneError` naming the URDF file and the element (``kind``: ``xml``,
        ``link``, ``joint``, ``unknown_link``, ``unsupported_joint`` (floating, planar),
        ``unsupported_geometry``, ``package_uri``, ``tree`` (cycle, two parents, several
        roots), ``options``), an unreadable file ``OSError``."""
        placement = {"position": _vec3("position", position),
                     "orientation": _quaternion("orientation", orientation),
                     "fixed_base": bool(fixed_base), "material": _material(material)}
        robot = json.loads(_coulomb.urdf_robot(os.fspath(path),
                                               json.dumps(placement, allow_nan=False)))
        self._use(material)
        first = self.body_count
        for body in robot["bodies"]:
            self._order.append(("body", len(self._bodies), 0))
            self._bodies.append(body)
        for j in robot["joints"]:
            j = dict(j, body_a=first + int(j["body_a"]))
            if j.get("body_b") is not None:
                j["body_b"] = first + int(j["body_b"])
            self._joints.append(j)
        return list(range(first, first + len(robot["bodies"])))

    @property
    def joint_count(self) -> int:
        """Number of joints."""
        return len(self._joints)

    def _model_index(self, i: int) -> int:
        """The index of body ``i`` (insertion order) in the rigid-body simulator's order:
        the bodies of :meth:`add_body`, then the spheres of each batch."""
        what, k, m = self._order[i]
        if what == "body":
            return k
        return (len(self._bodies)
                + sum(a[0].shape[0] // 3 for _, a in self._batches[:k]) + m)

    @property
    def has_shapes(self) -> bool:
        """Whether some body is not a sphere, the scene has joints or an inlet pours another
        shape (the scene then runs in the rigid-body simulator)."""
        return (any(b["shape"]["kind"] != "sphere" for b in self._bodies)
                or bool(self._joints)
                or any(i["inlet"].get("shape", {}).get("kind", "sphere") != "sphere"
                       for i in self._inlets))

    @property
    def sphere_count(self) -> int:
        """Number of spheres added (free and fixed)."""
        return sum(arrays[0].shape[0] // 3 for _, arrays in self._batches)

    def _sphere_arrays(self) -> Tuple[np.ndarray, np.ndarray]:
        """Centres (n, 3) and radii (n,) of every sphere added so far."""
        pos, rad = [np.zeros((0, 3))], [np.zeros(0)]
        for _, (p, r, *_rest) in self._batches:
            n = p.shape[0] // 3
            pos.append(p.reshape(n, 3))
            rad.append(np.broadcast_to(r, (n,)) if r.shape[0] == 1 else r)
        return np.concatenate(pos), np.concatenate(rad)

    def fill(self, region: Mapping[str, Any], count: int, radius: Any = 0.05,
             method: str = "lattice", seed: int = 0, density: float = 2500.0,
             material: str = "default", velocity: Sequence[float] = (0.0, 0.0, 0.0),
             velocity_jitter: float = 0.0, pitch: Optional[float] = None,
             layer_pitch: Optional[float] = None, jitter: float = 0.2,
             max_attempts: Optional[int] = None) -> int:
        """Fills ``region`` (:meth:`Region.box`, :meth:`Region.cylinder`, :meth:`Region.mesh`:
        a closed mesh's interior) with ``count``
        spheres that overlap neither each other nor the spheres already in the scene, and
        adds them; returns how many were placed (fewer when the region is full).

        ``radius``: one radius, or a size distribution as a dict (``{"kind": "uniform",
        "min": .., "max": ..}``, ``{"kind": "normal", "mean": .., "sd": ..}``,
        ``{"kind": "log_normal", "median": .., "sigma": ..}``, ``{"kind": "psd",
        "diameters": [..], "cumulative": [..], "basis": "mass"}``). ``method``:
        ``"lattice"`` (a jittered cubic lattice filled from the bottom up; ``pitch``
        default 2.5 × the largest radius, ``jitter`` as a fraction of it) or ``"rsa"``
        (random sequential addition, at most ``max_attempts`` tries). Deterministic from
        ``seed`` (ChaCha8; ``coulomb_granular::generate::fill``).
        """
        if method == "lattice":
            packing: Dict[str, Any] = {"method": "lattice", "jitter": _real("jitter", jitter)}
            if pitch is not None:
                packing["pitch"] = _real("pitch", pitch, positive=True)
            if layer_pitch is not None:
                packing["layer_pitch"] = _real("layer_pitch", layer_pitch, positive=True)
        elif method in ("rsa", "random"):
            packing = {"method": "random"}
            if max_attempts is not None:
                packing["max_attempts"] = int(max_attempts)
        else:
            raise _arg_error("method", f"fill method {method!r}: 'lattice' or 'rsa'")
        if isinstance(count, bool) or int(count) != count or count < 0:
            raise _arg_error("count", f"count must be a nonnegative int, got {count!r}")
        if not isinstance(region, Mapping):
            raise TypeError("region must be a dict (coulomb.granular.Region.box / .cylinder)")
        spec = {"count": int(count), "sizes": _sizes(radius), "packing": packing,
                "velocity": _vec3("velocity", velocity),
                "velocity_jitter": _real("velocity_jitter", velocity_jitter, nonnegative=True),
                "seed": int(seed)}
        ap, ar = self._sphere_arrays()
        mesh = None
        if region.get("kind") == "mesh":
            mesh = (np.asarray(region["vertices"], dtype=np.float64).ravel(),
                    np.asarray(region["triangles"], dtype=np.uint64).ravel())
            region = {"kind": "mesh"}
        pos, rad, vel, _attempts = _coulomb.scene_fill(
            json.dumps(dict(region)), json.dumps(spec), np.ascontiguousarray(ap).ravel(),
            np.ascontiguousarray(ar), mesh)
        if len(rad):
            self.add_spheres(pos, rad, density=density, material=material,
                             velocities=vel if np.any(vel) else None)
        else:
            self._use(material)
        return int(len(rad))

    def add_inlet(self, region: Mapping[str, Any], rate: float, radius: Any = 0.05,
                  density: float = 2500.0, material: str = "default", rate_kind: str = "count",
                  start: float = 0.0, end: Optional[float] = None,
                  velocity: Sequence[float] = (0.0, 0.0, 0.0), attempts: int = 20,
                  seed: int = 0, shape: Any = None) -> "Scene":
        """Pours spheres into the running simulation: from ``start`` to ``end`` (s),
        ``rate`` spheres per second (``rate_kind="count"``) or kilograms per second
        (``"mass"``) appear in ``region`` (:meth:`Region.box` or :meth:`Region.cylinder`)
        with ``velocity``, radii from ``radius`` (a number or a size distribution as in
        :meth:`fill`). Sphere i is placed at the first of ``attempts`` seeded random
        positions that overlaps nothing, else skipped (``coulomb_granular::generate::Inlet``,
        the rule of ``coulomb simulate``); the spheres due in (t_k, t_{k+1}] are inserted
        after step k, after those already present in the arrays. ``shape`` (a shape of
        :meth:`add_body`, e.g. :class:`Capsule`): bodies of that shape instead, scaled so that
        their bounding radius is the sampled radius and turned at random (the scene files'
        ``[[inlets]] shape``; the scene then runs in the rigid-body simulator)."""
        if rate_kind not in ("count", "mass"):
            raise _arg_error("rate_kind", f"rate_kind {rate_kind!r}: 'count' or 'mass'")
        if not isinstance(region, Mapping) or region.get("kind") not in ("box", "cylinder"):
            raise _arg_error("region", "an inlet's region is a Region.box or Region.cylinder")
        inlet: Dict[str, Any] = {
            "region": dict(region), "sizes": _sizes(radius),
            "density": _real("density", density, positive=True),
            "rate": {rate_kind: _real("rate", rate, nonnegative=True)},
            "start": _real("start", start, nonnegative=True),
            "velocity": _vec3("velocity", velocity), "attempts": int(attempts),
            "seed": int(seed)}
        if end is not None:
            inlet["end"] = _real("end", end)
        if shape is not None:
            inlet["shape"] = _shape_spec(shape)
        self._inlets.append({"inlet": inlet, "material": self._use(material)})
        return self

    # -- obstacles --------------------------------------------------------------------------

    def _obstacle(self, shape: Dict[str, Any], material: str, motion: Any, name: str) -> "Scene":
        if not isinstance(name, str):
            raise TypeError("name must be a string")
        self._obstacles.append({"name": name, "shape": shape, "motion": _motion(motion),
                                "material": self._use(material)})
        return self

    def add_plane(self, point: Sequence[float], normal: Sequence[float],
                  material: str = "default", motion: Any = None, name: str = "") -> "Scene":
        """An infinite plane through ``point``; the spheres live on the side ``normal``
        points to (normalized here)."""
        return self._obstacle({"kind": "plane", "point": _vec3("point", point),
                               "normal": _unit("normal", normal)}, material, motion, name)

    def add_rectangle(self, center: Sequence[float], normal: Sequence[float],
                      u: Sequence[float], half_u: float, half_v: float,
                      material: str = "default", motion: Any = None,
                      name: str = "") -> "Scene":
        """A thin two-sided rectangle: centre, normal, in-plane axis ``u`` (orthogonal to the
        normal; the other axis is normal × u) and half-lengths along them."""
        return self._obstacle({"kind": "rectangle", "center": _vec3("center", center),
                               "normal": _unit("normal", normal), "u": _unit("u", u),
                               "half_u": _real("half_u", half_u),
                               "half_v": _real("half_v", half_v)}, material, motion, name)

    def add_box(self, lo: Sequence[float], hi: Sequence[float], inside: bool = True,
                open_top: bool = False, material: str = "default", motion: Any = None,
                name: str = "") -> "Scene":
        """The axis-aligned box [lo, hi]: a container of six thin walls when ``inside``
        (without its top wall z = hi when ``open_top``), else a solid block the spheres
        stay out of."""
        return self._obstacle({"kind": "box", "lo": _vec3("lo", lo), "hi": _vec3("hi", hi),
                               "inside": bool(inside), "open_top": bool(open_top)},
                              material, motion, name)

    def add_cylinder(self, base: Sequence[float], axis: Sequence[float], radius: float,
                     height: Optional[float], inside: bool = True, bottom_cap: bool = True,
                     top_cap: bool = True, orifice: float = 0.0, material: str = "default",
                     motion: Any = None, name: str = "") -> "Scene":
        """A circular cylinder whose axis runs from ``base`` (centre of the bottom cap) along
        ``axis`` over ``height``. ``inside``: a container (a silo: caps optional, the bottom
        cap pierced by a centred circular ``orifice`` of that radius); otherwise a solid
        cylinder with both caps. ``height=None`` with ``inside``: the inside of an infinite
        cylinder through ``base`` (a drum without end walls)."""
        if height is None:
            if not inside:
                raise _arg_error("height", "an infinite cylinder (height=None) is a container")
            return self._obstacle({"kind": "cylinder_inside", "point": _vec3("base", base),
                                   "axis": _unit("axis", axis),
                                   "radius": _real("radius", radius)}, material, motion, name)
        return self._obstacle({"kind": "cylinder", "base": _vec3("base", base),
                               "axis": _unit("axis", axis), "radius": _real("radius", radius),
                               "height": _real("height", height), "inside": bool(inside),
                               "bottom_cap": bool(bottom_cap), "top_cap": bool(top_cap),
                               "orifice": _real("orifice", orifice)}, material, motion, name)

    def add_sphere(self, center: Sequence[float], radius: float, inside: bool = False,
                   material: str = "default", motion: Any = None, name: str = "") -> "Scene":
        """A spherical obstacle: a ball the spheres stay out of, or (``inside``) a spherical
        container."""
        return self._obstacle({"kind": "sphere", "center": _vec3("center", center),
                               "radius": _real("radius", radius), "inside": bool(inside)},
                              material, motion, name)

    def add_mesh(self, vertices: Any, triangles: Any, motion: Any = None,
                 material: str = "default", side: str = "surface", name: str = "") -> "Scene":
        """A triangle mesh obstacle: ``vertices`` (n, 3) floats, ``triangles`` (m, 3)
        integer vertex indices. ``side``: ``"surface"`` (either side, open or closed: a
        chute, a drum's shell), ``"inside"`` (a closed, consistently oriented container) or
        ``"outside"`` (a closed solid). Contacts are found through a bounding-volume
        hierarchy (O(contacts) per step). Validated at build: finite vertices, indices in
        range, no degenerate triangle (errors name ``vertices`` / ``triangles`` and the
        index)."""
        v = _rows3("vertices", vertices)
        t = _triangles(triangles)
        if side not in ("surface", "inside", "outside"):
            raise _arg_error("side", f"side {side!r}: 'surface', 'inside' or 'outside'")
        k = len(self._meshes)
        self._meshes.append((v.ravel(), t.ravel()))
        return self._obstacle({"kind": "mesh", "mesh": k, "side": side}, material, motion, name)

    @property
    def obstacles(self) -> List[Dict[str, Any]]:
        """The obstacles as dicts (meshes by their index in the scene's meshes)."""
        return [dict(o) for o in self._obstacles]

    # -- hand-over to Rust ------------------------------------------------------------------

    def _description(self) -> str:
        """The scene without its arrays, as JSON (``coulomb_granular::SceneModel``)."""
        desc = {
            "gravity": self._gravity,
            "materials": {"names": list(self._names), "default": dict(self._default_law),
                          "pairs": [dict(p) for p in self._pairs.values()]},
            "bodies": self._bodies,
            "sphere_batches": [d for d, _ in self._batches],
            "obstacles": self._obstacles,
        }
        if self._joints:
            desc["joints"] = [
                dict(j, body_a=self._model_index(j["body_a"]),
                     **({"body_b": self._model_index(j["body_b"])} if "body_b" in j else {}))
                for j in self._joints]
        return json.dumps(desc, allow_nan=False)

    def _parts(self) -> Tuple[str, List[Tuple[np.ndarray, ...]], List[Tuple[np.ndarray, ...]]]:
        return self._description(), [a for _, a in self._batches], list(self._meshes)

    def save(self, path: Union[str, "os.PathLike[str]"], steps: Optional[int] = None,
             **params: Any) -> None:
        """Writes the scene as a scene file (``.toml`` or ``.json``, the format of ``coulomb
        simulate SCENE.toml``, docs/granular.md "Scene files") that builds the same bodies,
        obstacles, materials and inlets, in the same order and to the bit (unit normals and
        axes are normalized again when read). ``params`` are the step settings of
        :class:`Simulation` (``h``, ``theta``, ``tol``, ``method``, ``max_sweeps``,
        ``relaxation``, ``mu``, ``restitution``, ``rolling_friction``, ``warm_start``,
        ``gap_closure``) with its defaults (a scene with shaped bodies: h = 1e-3 s,
        tol = 1e-8), so that ``coulomb simulate`` on the file steps as
        ``Simulation(scene, **params)`` does; ``steps``: the run's length (default 200).

        Written atomically (a failed write leaves an existing file as it was); a ``path``
        that exists and is not a regular file is refused (``ValueError``). What a scene
        file cannot hold is refused (:class:`coulomb.SceneError`): two inlets of one material
        with different densities."""
        if steps is not None and (isinstance(steps, bool) or int(steps) != steps or steps < 0):
            raise _arg_error("steps", f"steps must be a nonnegative int, got {steps!r}")
        desc, batches, meshes = self._parts()
        _coulomb.scene_save(desc, batches, meshes, json.dumps(self._inlets, allow_nan=False),
                            dict(params), os.fspath(path),
                            None if steps is None else int(steps))



def _sweeps(resolve_overlaps: Optional[int]) -> Optional[int]:
    """``resolve_overlaps`` checked: None, or a number of sweeps ≥ 0."""
    if resolve_overlaps is None:
        return None
    if isinstance(resolve_overlaps, bool) or not isinstance(resolve_overlaps, int) \
            or resolve_overlaps < 0:
        raise _arg_error("resolve_overlaps",
                         f"must be a number of sweeps >= 0, got {resolve_overlaps!r}")
    return resolve_overlaps


class Simulation:
    """A granular simulation of a :class:`Scene` of your own, or of the built-in ``scene``
    (``box``, ``funnel``, ``vibrating-plate``, ``rotating-drum``) with ``beads`` spheres built
    deterministically from ``seed``.

    Step settings (those of ``coulomb simulate``): ``h`` (time step, 0.02 s), ``theta`` (θ of
    (2.7), 0.5), ``tol`` (tolerance on the error of docs/error.md reached at every step,
    1e-4), ``method`` (``"nsgs"``: body-level nonsmooth Gauss–Seidel, finished by the
    library's solver where it stalls — the default; ``"library"``: the library's solver on
    each step's problem (2.10)), ``max_sweeps`` (20 000) and ``relaxation`` (ω, 1.5) of
    ``nsgs``. Contact law of every pair of materials without its own law: ``restitution``
    (Newton's e, 0.2), ``mu`` (friction, 0.3), ``rolling_friction`` (μ_r: resisting torque ≤
    μ_r R r_N, 0 = off; docs/granular.md, "Rolling resistance"). Also ``warm_start`` (True),
    ``gap_closure`` (True: a sphere at rest settles onto an obstacle instead of hovering at
    the activation rule's look-ahead distance; docs/granular.md, "Resting on an obstacle").
    ``solver`` holds keyword settings of :func:`coulomb.solve` that replace the library
    solver's (used by ``method="library"`` and as the fallback of ``nsgs``).
    A scene with bodies of other shapes than spheres runs at the rigid scene files' defaults
    ``h = 1e-3`` and ``tol = 1e-8``; an ``h`` in which a body falls (g h²) or travels more than
    half its thinnest width, or a sphere more than its radius, raises :class:`ValueError`.

    ``resolve_overlaps`` (a number of sweeps, as ``coulomb simulate --resolve-overlaps
    SWEEPS``; the command's default is 1000): bodies of any shape overlapping each other or an
    obstacle at the start are moved apart first, and the scene is refused if some overlap is
    left; without it such a scene raises :class:`coulomb.SceneError`.

    Unknown names raise :class:`TypeError`, values out of range :class:`ValueError`; a scene
    that cannot be built raises :class:`coulomb.SceneError` (a ``ValueError``) naming the
    datum. Building and stepping run without the GIL.
    """

    def __init__(self, scene: Union[Scene, str] = "box", beads: int = 100, seed: int = 1,
                 solver: Optional[Mapping[str, Any]] = None,
                 resolve_overlaps: Optional[int] = None, **params: Any) -> None:
        relax = _sweeps(resolve_overlaps)
        if isinstance(scene, Scene):
            desc, batches, meshes = scene._parts()
            inlets = json.dumps(scene._inlets, allow_nan=False)
            if scene.has_shapes:
                if solver:
                    raise _arg_error("solver", "solver= sets the sphere engine's library solver; "
                                     "a scene with bodies of other shapes uses its defaults")
                self._sim = _coulomb._RigidSimulation.from_scene(desc, batches, meshes,
                                                                 dict(params), inlets, relax)
                return
            self._sim = _coulomb._Simulation.from_scene(desc, batches, meshes, dict(params),
                                                        dict(solver or {}), inlets, relax)
        elif isinstance(scene, str):
            if relax is not None:
                raise _arg_error("resolve_overlaps", "the built-in scenes have no overlaps to "
                                 "relax; it is for scenes of your own")
            self._sim = _coulomb._Simulation(scene, int(beads), int(seed), dict(params),
                                             dict(solver or {}))
        else:
            raise TypeError(f"scene must be a coulomb.granular.Scene or the name of a built-in "
                            f"scene {SCENES}, got {type(scene).__name__}")

    @staticmethod
    def from_file(path: Union[str, "os.PathLike[str]"], seed: Optional[int] = None,
                  solver: Optional[Mapping[str, Any]] = None,
                  resolve_overlaps: Optional[int] = None,
                  **params: Any) -> "Simulation":
        """The scene of a scene file (``.toml`` or ``.json``, the format of ``coulomb
        simulate SCENE.toml``, docs/granular.md "Scene files"); ``seed`` replaces the file's,
        ``params`` (as for :class:`Simulation`) override its ``[step]`` settings. Errors name
        the file, line and key (:class:`coulomb.SceneError`; ``OSError`` when it cannot be
        read). The file's inlets pour as in ``coulomb simulate``, spheres or bodies of any
        shape, into a sphere or a rigid-body scene alike."""
        sim = Simulation.__new__(Simulation)
        sim._sim = _coulomb._Simulation.from_file(
            os.fspath(path), None if seed is None else int(seed), dict(params),
            dict(solver or {}), _sweeps(resolve_overlaps))
        return sim

    def step(self) -> StepStats:
        """Advances one step t_k → t_{k+1} (GIL released) and returns its statistics; then
        the scene's inlets insert the bodies due in (t_k, t_{k+1}]."""
        return self._sim.step()

    def run(self, steps: int) -> List[StepStats]:
        """Advances ``steps`` steps at once (GIL released for each, inlets pouring after
        each) and returns their statistics (a list; use :meth:`step` to read or steer the
        state between steps)."""
        return self._sim.run(int(steps))

    @property
    def is_rigid(self) -> bool:
        """Whether the scene runs in the rigid-body simulator (some body is not a sphere)."""
        return isinstance(self._sim, _coulomb._RigidSimulation)

    @property
    def joint_forces(self) -> np.ndarray:
        """Force and torque of each joint on its body A in the last step, shape
        (n_joints, 6): (F, τ) in world axes, τ about the joint's anchor on A; the step's
        impulse / h (zeros before the first step; (0, 6) without joints)."""
        if self.is_rigid:
            return self._sim.joint_forces
        return np.zeros((0, 6))

    @property
    def joint_drift(self) -> float:
        """Largest violation of the joints' constraints at t_k (m for positions, rad for
        angles; 0 without joints)."""
        return self._sim.joint_drift if self.is_rigid else 0.0

    @property
    def body_positions(self) -> np.ndarray:
        """Origins of the bodies' shape frames at t_k (sphere centres), shape (n, 3)."""
        if self.is_rigid:
            return self._sim.body_positions
        return self._sim.positions

    @property
    def body_orientations(self) -> np.ndarray:
        """Orientations (w, x, y, z) at t_k, shape (n, 4). The sphere simulator does not
        track the spheres' rotation (only their angular velocities): in a sphere-only scene
        every orientation is the identity (1, 0, 0, 0)."""
        if self.is_rigid:
            return self._sim.body_orientations
        n = self._sim.positions.shape[0]
        q = np.zeros((n, 4))
        q[:, 0] = 1.0
        return q

    @property
    def contacts(self) -> List[Dict[str, Any]]:
        """The last step's contacts, one dict each: body ``a``, partner ``b``
        (``{"kind": "body" | "obstacle", "index": i}``), ``point``, unit ``normal`` from b
        to a, first tangent ``t1``, ``gap`` at t_k, ``impulse`` (r_N, r_T1, r_T2)."""
        return self._sim.contacts

    @property
    def positions(self) -> np.ndarray:
        """Sphere centres at t_k, shape (n, 3) (a copy); in a rigid-body scene, the origins
        of the bodies' shape frames."""
        if self.is_rigid:
            return self._sim.body_positions
        return self._sim.positions

    @property
    def velocities(self) -> np.ndarray:
        """Velocities at t_k of the sphere centres (in a rigid-body scene, of the bodies'
        centres of mass), shape (n, 3) (a copy)."""
        return self._sim.velocities

    @property
    def angular_velocities(self) -> np.ndarray:
        """Angular velocities ω at t_k, shape (n, 3)."""
        return self._sim.angular_velocities

    @property
    def radii(self) -> np.ndarray:
        """Radii, shape (n,); in a rigid-body scene a sphere body's radius and NaN for every
        other shape (it has no radius)."""
        return self._sim.radii

    @property
    def masses(self) -> np.ndarray:
        """Masses, shape (n,) (every scene)."""
        return self._sim.masses

    @property
    def time(self) -> float:
        """t_k."""
        return self._sim.time

    @property
    def steps_done(self) -> int:
        """k."""
        return self._sim.steps_done

    @property
    def params(self) -> Dict[str, Any]:
        """Time-stepping parameters and solver settings."""
        return self._sim.params

    def set_velocities(self, v: Any) -> None:
        """Replaces the velocities (shape (n, 3), finite) before the next step: of the sphere
        centres, or in a rigid-body scene of the bodies' centres of mass (a fixed body's must
        stay 0); ``ValueError`` otherwise, nothing changed."""
        a = _rows3("velocities", v, self.masses.shape[0])
        self._sim.set_velocities(np.ascontiguousarray(a).ravel())

    def set_positions(self, x: Any) -> None:
        """Replaces the sphere centres (shape (n, 3), finite) before the next step; in a
        rigid-body scene the origins of the bodies' shape frames (as :attr:`positions`),
        their orientations unchanged and their centres of mass following (a fixed body must
        stay where it is); ``ValueError`` otherwise, nothing changed. Overlaps are not
        checked. A rigid body given its current position keeps its state to the bit."""
        a = _rows3("positions", x, self.positions.shape[0])
        self._sim.set_positions(np.ascontiguousarray(a).ravel())

    def set_params(self, **params: Any) -> None:
        """Changes the step settings and default law of :class:`Simulation` (h, theta, tol,
        method, max_sweeps, relaxation, restitution, mu, rolling_friction, warm_start,
        gap_closure, projection_velocities) for the following steps, checked as there; a
        rigid-body scene takes h, theta, tol, max_sweeps, relaxation, mu and restitution
        (its checkpoints hold them)."""
        self._sim.set_params(**params)

    def set_solver(self, **settings: Any) -> None:
        """Replaces the solver settings (keyword arguments of :func:`coulomb.solve`, checked
        as there) for the following steps; in a rigid-body scene those of the library's
        solver that finishes the steps Gauss–Seidel leaves above the tolerance (or takes
        every step with ``method="library"``), its ``tol`` being the scene's
        (``set_params(tol=...)``); checkpoints hold them."""
        self._sim.set_solver(**settings)

    @property
    def keep_problem(self) -> bool:
        """When True, each step's problem (2.10) is kept in :attr:`last_problem`; False
        drops it (the steps are the same to the bit); checkpoints hold it."""
        return self._sim.keep_problem

    @keep_problem.setter
    def keep_problem(self, keep: bool) -> None:
        self._sim.keep_problem = bool(keep)

    @property
    def last_problem(self) -> Optional[GlobalProblem]:
        """The last step's global problem (needs ``keep_problem``), e.g. to write as FCLIB."""
        p = self._sim.last_problem
        return None if p is None else Problem._wrap(p)  # type: ignore[return-value]

    def write_frames(self, dir: Union[str, "os.PathLike[str]"]) -> None:
        """Writes the current state as a ParaView frame into the folder ``dir`` (created), with
        the writer of ``coulomb simulate --output``: ``frames/*.vtp`` and the ``.pvd``
        collections (``bodies.pvd`` for every scene: spheres as points with a ``radius``
        array, other shapes as polygons; with ``contacts.pvd`` and ``obstacles.pvd``). Called again with the same folder, the frame
        is added to the collections (call it after each :meth:`run`). A link, folder or
        special file where one of these files goes is refused with ``ValueError``; nothing is
        written through a link (docs/outputs-and-signals.md)."""
        self._sim.write_frames(os.fspath(dir))

    def save_checkpoint(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Writes the full state of the simulation (spheres, obstacles, materials, gravity,
        parameters and solver settings, time, step count, warm-start impulses, last contacts)
        into the HDF5 file ``path``, atomically (a complete file replaces an existing one or
        nothing does). :meth:`load_checkpoint` continues it to the bit; ``coulomb simulate
        --restart path`` continues it from the command line. A scene's inlets are not stored
        in the file: give the scene to :meth:`load_checkpoint` (``scene=``) and they keep
        pouring. A scene with bodies of other shapes (the rigid-body simulator) stores its
        scene model, the bodies' states, the warm start and the contact detector's caches
        (docs/granular.md, "Checkpoint and restart")."""
        self._sim.save_checkpoint(os.fspath(path))

    @staticmethod
    def load_checkpoint(path: Union[str, "os.PathLike[str]"],
                        scene: Union[Scene, str, "os.PathLike[str]", None] = None
                        ) -> "Simulation":
        """The simulation stored in the checkpoint file ``path`` (written by
        :meth:`save_checkpoint` or ``coulomb simulate --checkpoint-every``): stepping it gives
        the same numbers as stepping the saved one. Raises :class:`coulomb.CheckpointError`
        for a file of another format version, a damaged or truncated one, and ``OSError`` when
        it cannot be read.

        ``scene``: the :class:`Scene` or scene file (``.toml``/``.json``) the stored run was
        built from, when it has inlets: they go on pouring after each step as in the
        uninterrupted run (an inlet's emissions depend only on its seed, the time and the
        spheres present, so the continued run is the uninterrupted one to the bit, as
        ``coulomb simulate SCENE.toml --restart FILE``). The scene is built to read its
        inlets and compared with the checkpoint: another gravity or other obstacles raise
        ``ValueError``. A rigid checkpoint (bodies of other shapes) holds its whole scene and
        step settings; a ``scene`` given with it must have the same bodies (those its inlets
        poured aside), obstacles, materials and gravity (else ``ValueError``), and its inlets
        go on pouring bodies of any shape the same way."""
        sim = Simulation.__new__(Simulation)
        rigid = _coulomb._checkpoint_is_rigid(os.fspath(path))
        engine = _coulomb._RigidSimulation if rigid else _coulomb._Simulation
        sim._sim = engine.load_checkpoint(os.fspath(path))
        if scene is None:
            return sim
        if isinstance(scene, Scene):
            probe = Simulation(scene)
        elif isinstance(scene, (str, os.PathLike)):
            probe = Simulation.from_file(scene)
        else:
            raise TypeError(f"scene must be a coulomb.granular.Scene or a scene file, got "
                            f"{type(scene).__name__}")
        if probe.is_rigid != rigid or not sim._sim.pour_from(probe._sim):
            raise ValueError(f"the scene given is not the scene of the checkpoint "
                             f"{os.fspath(path)}: its bodies, obstacles, materials or gravity "
                             f"differ")
        return sim


@dataclass
class SimulationResult:
    """What :func:`simulate` returns."""

    #: per-step statistics, one list entry per step
    steps: List[StepStats]
    #: final sphere centres, shape (n, 3)
    positions: np.ndarray
    #: final velocities, shape (n, 3)
    velocities: np.ndarray
    #: radii, shape (n,)
    radii: np.ndarray
    #: with ``record=True``: centres after each step, shape (steps + 1, n, 3)
    trajectory: Optional[np.ndarray] = None
    #: with ``record=True``: velocities after each step, shape (steps + 1, n, 3)
    velocity_trajectory: Optional[np.ndarray] = None
    #: the simulation itself, to continue it
    simulation: Optional[Simulation] = field(default=None, repr=False)

    def column(self, name: str) -> np.ndarray:
        """One statistic over the steps as an array, e.g. ``column("solve_ms")``."""
        return np.array([s[name] for s in self.steps])


def simulate(scene: str = "box", beads: int = 100, steps: int = 50, seed: int = 1,
             callback: Optional[Callable[[Simulation, StepStats], Optional[bool]]] = None,
             record: bool = False, solver: Optional[Mapping[str, Any]] = None,
             **params: Any) -> SimulationResult:
    """Runs ``steps`` time steps of ``scene`` with ``beads`` spheres.

    ``callback(sim, stats)`` is called after every step; it may read or change the state
    (``sim.set_velocities``, ``sim.set_params``) and returns ``False`` to stop the run.
    ``params`` and ``solver`` as in :class:`Simulation`.
    """
    sim = Simulation(scene, beads, seed, solver=solver, **params)
    traj = [sim.positions] if record else None
    vtraj = [sim.velocities] if record else None
    stats: List[StepStats] = []
    for _ in range(int(steps)):
        s = sim.step()
        stats.append(s)
        if traj is not None and vtraj is not None:
            traj.append(sim.positions)
            vtraj.append(sim.velocities)
        if callback is not None and callback(sim, s) is False:
            break
    return SimulationResult(
        steps=stats, positions=sim.positions, velocities=sim.velocities, radii=sim.radii,
        trajectory=None if traj is None else np.stack(traj),
        velocity_trajectory=None if vtraj is None else np.stack(vtraj), simulation=sim)
