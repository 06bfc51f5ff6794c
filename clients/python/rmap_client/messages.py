"""Builders of the robot stream's messages from plain Python values.

Units: metres, radians, nanoseconds (``stamp_ns``, Unix time); quaternions are
(w, x, y, z). A ``stamp_ns`` of None takes the current time.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable, Sequence

from . import proto

Vec3 = Sequence[float]
"""(x, y, z) in metres."""


def pose3(position_m: Vec3 = (0.0, 0.0, 0.0), orientation_wxyz: Sequence[float] = (1.0, 0.0, 0.0, 0.0)) -> proto.Pose3:
    """A rigid pose: position in metres, unit quaternion (w, x, y, z)."""
    pose = proto.Pose3()
    pose.position_m.x, pose.position_m.y, pose.position_m.z = (float(v) for v in position_m)
    o = pose.orientation
    o.w, o.x, o.y, o.z = (float(v) for v in orientation_wxyz)
    return pose


def planar_pose3(x_m: float, y_m: float, yaw_rad: float, z_m: float = 0.0) -> proto.Pose3:
    """A pose rotated about z only: (x, y, z) in metres, heading in radians."""
    return pose3((x_m, y_m, z_m), (math.cos(yaw_rad / 2), 0.0, 0.0, math.sin(yaw_rad / 2)))


def yaw_rad(pose: proto.Pose3) -> float:
    """Heading of a pose rotated about z only (as PoseEstimate poses are), radians in (-pi, pi]."""
    o = pose.orientation
    return math.atan2(2 * (o.w * o.z + o.x * o.y), 1 - 2 * (o.y * o.y + o.z * o.z))


def pose2(x_m: float, y_m: float, theta_rad: float) -> proto.Pose2:
    """A planar pose in the map frame."""
    return proto.Pose2(x_m=x_m, y_m=y_m, theta_rad=theta_rad)


def sensor(name: str, kind: str, model: str = "", mount: proto.Pose3 | None = None) -> proto.SensorDescription:
    """A sensor for the Hello.

    Args:
        name: what data messages name in their ``sensor`` field
        kind: ``"LASER_2D"``, ``"LIDAR_3D"``, ``"CAMERA"`` or ``"ODOMETRY"``
        model: scanner or camera model (the 2D SLAM's intensity calibration is per model)
        mount: the sensor frame in the robot base frame; for a LASER_2D its x, y
            and yaw place the laser for the 2D SLAM and its z is the height of the
            planar cloud the scans add to the 3D map (docs/API.md §7a.6)
    """
    description = proto.SensorDescription(name=name, kind=proto.SensorDescription.Kind.Value(kind), model=model)
    description.mount.CopyFrom(mount if mount is not None else pose3())
    return description


def _stamp(stamp_ns: int | None) -> int:
    return time.time_ns() if stamp_ns is None else int(stamp_ns)


def point_cloud(
    points_m: Iterable[Vec3],
    sensor_pose: proto.Pose3,
    *,
    frame: str = "map",
    intensities: Iterable[float] | None = None,
    stamp_ns: int | None = None,
    sensor_name: str = "lidar",
) -> proto.PointCloud:
    """A 3D point cloud.

    Args:
        points_m: (x, y, z) points in metres, finite; 1 to 2,000,000 by default
        sensor_pose: the sensor in the map frame at ``stamp_ns``: the origin of every ray
        frame: ``"map"`` when the points are in the map frame, ``"sensor"`` when
            they are in the sensor frame (the server applies ``sensor_pose``)
        intensities: one per point, or None
    """
    cloud = proto.PointCloud(sensor=sensor_name, stamp_ns=_stamp(stamp_ns), frame=proto.PointCloud.Frame.Value(frame.upper()))
    cloud.sensor_pose.CopyFrom(sensor_pose)
    flat: list[float] = []
    count = 0
    for point in points_m:
        flat.extend(point)
        count += 1
    if len(flat) != 3 * count:
        raise ValueError("points_m must hold (x, y, z) triples")
    cloud.xyz_m.extend(flat)
    if intensities is not None:
        cloud.intensities.extend(intensities)
    return cloud


def laser_scan(
    ranges_m: Iterable[float],
    *,
    angle_min_rad: float,
    angle_increment_rad: float,
    range_min_m: float,
    range_max_m: float,
    odometry: proto.Pose2 | None = None,
    intensities: Iterable[float] | None = None,
    stamp_ns: int | None = None,
    sensor_name: str = "laser",
) -> proto.LaserScan2D:
    """A planar laser scan for the server's 2D SLAM, which answers a PoseEstimate.

    Beam i points at ``angle_min_rad + i * angle_increment_rad`` in the laser
    frame; a range of ``math.inf`` (or above ``range_max_m``) is no return.
    ``odometry`` is the robot base pose from odometry at ``stamp_ns`` (the
    SLAM's motion prior; robots sharing a map send it in the map frame).
    """
    scan = proto.LaserScan2D(
        sensor=sensor_name,
        stamp_ns=_stamp(stamp_ns),
        angle_min_rad=angle_min_rad,
        angle_increment_rad=angle_increment_rad,
        range_min_m=range_min_m,
        range_max_m=range_max_m,
    )
    scan.ranges_m.extend(ranges_m)
    if intensities is not None:
        scan.intensities.extend(intensities)
    if odometry is not None:
        scan.odometry.CopyFrom(odometry)
    return scan


def camera_image(
    data: bytes,
    encoding: str,
    *,
    width: int = 0,
    height: int = 0,
    camera_pose: proto.Pose3 | None = None,
    stamp_ns: int | None = None,
    sensor_name: str = "camera",
) -> proto.CameraImage:
    """A camera image (place recognition input).

    ``encoding`` is ``"JPEG"``, ``"PNG"``, ``"MONO8"`` or ``"RGB8"``; raw
    encodings need ``width`` and ``height`` in pixels. ``camera_pose`` is the
    camera in the map frame when known.
    """
    image = proto.CameraImage(
        sensor=sensor_name,
        stamp_ns=_stamp(stamp_ns),
        encoding=proto.CameraImage.Encoding.Value(encoding),
        width=width,
        height=height,
        data=data,
    )
    if camera_pose is not None:
        image.camera_pose.CopyFrom(camera_pose)
    return image


def odometry(pose: proto.Pose3, stamp_ns: int | None = None) -> proto.Odometry:
    """The robot base pose in the odometry frame; the planar part is the prior of later scans without odometry."""
    message = proto.Odometry(stamp_ns=_stamp(stamp_ns))
    message.pose.CopyFrom(pose)
    return message


def robot_message(body: proto.PointCloud | proto.LaserScan2D | proto.CameraImage | proto.Odometry) -> proto.RobotMessage:
    """Wraps a data message body into a RobotMessage (seq left 0 for the sender)."""
    message = proto.RobotMessage()
    field = {
        proto.PointCloud: "cloud",
        proto.LaserScan2D: "scan",
        proto.CameraImage: "image",
        proto.Odometry: "odometry",
    }.get(type(body))
    if field is None:
        raise TypeError(f"not a robot message body: {type(body).__name__}")
    getattr(message, field).CopyFrom(body)
    return message
