"""Python client of rmapd, the rmap mapping server.

- RobotClient: stream point clouds, 2D laser scans, images and odometry over
  ``/v1/stream/robot``; get acks, the 2D SLAM's pose estimates and errors.
- ViewerStream: change notices of ``/v1/stream/viewer`` (tiles, poses, loop closures).
- MapClient: occupancy queries (point, box, batch), maps and robots over HTTP.
- messages: builders of the protocol's messages; errors: the exceptions.

Needs the Debian packages python3-protobuf and python3-websockets, and the
protobuf modules the build generates into build/python (see proto.py).
Units are metres, radians and nanoseconds throughout.
"""

from . import messages, proto
from .errors import ConnectionClosed, HttpError, RmapError, RmapTimeout, StreamError
from .map_client import Cuboid, MapClient, Occupancy
from .messages import camera_image, laser_scan, odometry, planar_pose3, point_cloud, pose2, pose3, sensor, yaw_rad
from .robot import RobotClient
from .viewer import ViewerStream

__all__ = [
    "ConnectionClosed",
    "Cuboid",
    "HttpError",
    "MapClient",
    "Occupancy",
    "RmapError",
    "RmapTimeout",
    "RobotClient",
    "StreamError",
    "ViewerStream",
    "camera_image",
    "laser_scan",
    "messages",
    "odometry",
    "planar_pose3",
    "point_cloud",
    "pose2",
    "pose3",
    "proto",
    "sensor",
    "yaw_rad",
]
