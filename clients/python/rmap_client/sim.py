"""Simulated sensors in rooms of axis-aligned boxes, for the example and the tests.

Exact ray casting (no voxels), so what a scan sees is known in closed form:
a 3D lidar inside a box room, and a planar laser in a room with box pillars.
Units: metres, radians.
"""

from __future__ import annotations

import math
import random
from collections.abc import Sequence
from dataclasses import dataclass, field

Vec3 = Sequence[float]


def _exit_distance(origin: Sequence[float], direction: Sequence[float], lo: Sequence[float], hi: Sequence[float]) -> float:
    """Distance along a unit ray from a point inside a box to the box's boundary."""
    t = math.inf
    for o, d, a, b in zip(origin, direction, lo, hi):
        if d > 1e-12:
            t = min(t, (b - o) / d)
        elif d < -1e-12:
            t = min(t, (a - o) / d)
    return t


def _entry_distance(origin: Sequence[float], direction: Sequence[float], lo: Sequence[float], hi: Sequence[float]) -> float:
    """Distance along a ray from an outside point to where it enters a box (inf: it misses)."""
    near, far = -math.inf, math.inf
    for o, d, a, b in zip(origin, direction, lo, hi):
        if abs(d) < 1e-12:
            if o < a or o > b:
                return math.inf
            continue
        t1, t2 = (a - o) / d, (b - o) / d
        near, far = max(near, min(t1, t2)), min(far, max(t1, t2))
    return near if 0.0 < near <= far else math.inf


@dataclass(frozen=True)
class BoxRoom:
    """A closed room: floor, ceiling and four walls, corners in metres.

    The default's walls lie 1 cm outside the cell edges of a 0.1 m grid, so
    the cells holding them are (almost) all outside the room: rays along a
    wall to its neighbours' cells do not cross and clear them.
    """

    min_m: tuple[float, float, float] = (-2.01, -1.51, -0.01)
    max_m: tuple[float, float, float] = (4.01, 3.01, 2.51)

    def contains(self, point_m: Vec3, margin_m: float = 0.0) -> bool:
        return all(lo + margin_m <= p <= hi - margin_m for lo, p, hi in zip(self.min_m, point_m, self.max_m))

    def lidar_cloud(
        self, sensor_m: Vec3, *, azimuth_step_deg: float = 1.0, elevations_deg: Sequence[float] = tuple(range(-70, 71, 2))
    ) -> list[tuple[float, float, float]]:
        """Where the beams of a spinning lidar at ``sensor_m`` (inside) hit the room, map frame.

        One beam per azimuth step and elevation; every beam returns (the room is closed).
        """
        if not self.contains(sensor_m, 1e-6):
            raise ValueError(f"sensor {tuple(sensor_m)} is not inside the room")
        points = []
        steps = round(360.0 / azimuth_step_deg)
        for elevation in elevations_deg:
            e = math.radians(elevation)
            for k in range(steps):
                a = math.radians(k * azimuth_step_deg)
                d = (math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e))
                t = _exit_distance(sensor_m, d, self.min_m, self.max_m)
                points.append(tuple(o + t * c for o, c in zip(sensor_m, d)))
        return points


@dataclass(frozen=True)
class Laser2d:
    """A planar laser scanner: beams evenly over the field of view, Gaussian range noise."""

    beams: int = 361
    fov_rad: float = math.radians(270.0)
    range_min_m: float = 0.05
    range_max_m: float = 20.0
    range_noise_sigma_m: float = 0.01

    @property
    def angle_min_rad(self) -> float:
        return -self.fov_rad / 2

    @property
    def angle_increment_rad(self) -> float:
        return self.fov_rad / (self.beams - 1)


@dataclass(frozen=True)
class PillarRoom:
    """A rectangular room (walls at ``min_m``/``max_m``, x and y) with box pillars inside.

    The default's faces lie in the middle of the cells of a 0.05 m grid, so
    returns with centimetre noise stay in the face's cell.
    """

    min_m: tuple[float, float] = (0.025, 0.025)
    max_m: tuple[float, float] = (10.025, 6.025)
    pillars: tuple[tuple[tuple[float, float], tuple[float, float]], ...] = (
        ((6.025, 2.225), (6.825, 3.425)),
        ((2.425, 4.225), (3.025, 6.025)),
    )

    def scan(self, laser: Laser2d, pose: Sequence[float], rng: random.Random) -> list[float]:
        """Ranges (m) of the laser at planar pose (x_m, y_m, yaw_rad); inf for no return."""
        x, y, yaw = pose
        ranges = []
        for i in range(laser.beams):
            a = yaw + laser.angle_min_rad + i * laser.angle_increment_rad
            d = (math.cos(a), math.sin(a))
            t = _exit_distance((x, y), d, self.min_m, self.max_m)
            for lo, hi in self.pillars:
                t = min(t, _entry_distance((x, y), d, lo, hi))
            t += rng.gauss(0.0, laser.range_noise_sigma_m)
            ranges.append(t if laser.range_min_m <= t <= laser.range_max_m else math.inf)
        return ranges


def compose2(a: Sequence[float], b: Sequence[float]) -> tuple[float, float, float]:
    """Planar pose a ∘ b: b (in a's frame) expressed in a's parent frame."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], math.remainder(a[2] + b[2], math.tau))


def between2(a: Sequence[float], b: Sequence[float]) -> tuple[float, float, float]:
    """Planar motion from pose a to pose b, in a's frame (a⁻¹ ∘ b)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return (c * dx + s * dy, -s * dx + c * dy, math.remainder(b[2] - a[2], math.tau))


@dataclass
class DriftingOdometry:
    """Wheel odometry that drifts: each step's true motion with a relative error
    of the forward motion, a lateral error per metre and an absolute heading error.

    Starts at the true pose (odometry in the map frame, as robots sharing a map send it).
    """

    start: tuple[float, float, float]
    forward_sigma: float = 0.05
    lateral_sigma_per_m: float = 0.02
    heading_sigma_rad: float = 0.02
    rng: random.Random = field(default_factory=lambda: random.Random(1))

    def __post_init__(self) -> None:
        self.pose = tuple(self.start)
        self._truth = tuple(self.start)

    def step(self, truth: Sequence[float]) -> tuple[float, float, float]:
        """Moves with the robot to its new true pose; returns the odometry pose."""
        dx, dy, dtheta = between2(self._truth, truth)
        distance = math.hypot(dx, dy)
        measured = (
            dx * (1 + self.forward_sigma * self.rng.gauss(0, 1)),
            dy + self.lateral_sigma_per_m * distance * self.rng.gauss(0, 1),
            dtheta + self.heading_sigma_rad * self.rng.gauss(0, 1),
        )
        self.pose = compose2(self.pose, measured)
        self._truth = tuple(truth)
        return self.pose


def tour(waypoints: Sequence[Sequence[float]], step_m: float = 0.2, turn_step_rad: float = 0.25) -> list[tuple[float, float, float]]:
    """Planar poses driving through waypoints (x_m, y_m): straight legs of ``step_m``
    steps, turning on the spot (at most ``turn_step_rad`` per step) at each waypoint."""
    poses: list[tuple[float, float, float]] = []
    x, y = waypoints[0]
    yaw = math.atan2(waypoints[1][1] - y, waypoints[1][0] - x)
    poses.append((x, y, yaw))
    for tx, ty in waypoints[1:]:
        heading = math.atan2(ty - y, tx - x)
        turn = math.remainder(heading - yaw, math.tau)
        for _ in range(math.ceil(abs(turn) / turn_step_rad)):
            yaw = math.remainder(yaw + math.copysign(min(turn_step_rad, abs(turn)), turn), math.tau)
            turn = math.remainder(heading - yaw, math.tau)
            poses.append((x, y, yaw))
        steps = max(1, round(math.hypot(tx - x, ty - y) / step_m))
        x0, y0 = x, y
        for k in range(1, steps + 1):
            x, y = x0 + (tx - x0) * k / steps, y0 + (ty - y0) * k / steps
            poses.append((x, y, yaw))
    return poses
