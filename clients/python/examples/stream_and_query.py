#!/usr/bin/python3
"""Streams a few lidar clouds of a simulated box room into rmapd, waits for
their acknowledgements, then asks the map what it holds at a few points.

    PYTHONPATH=build/python:clients/python /usr/bin/python3 clients/python/examples/stream_and_query.py \\
        --server 127.0.0.1:8080 --map py-demo [--token T]
"""

from __future__ import annotations

import argparse
import sys
import time

from rmap_client import MapClient, RmapError, RobotClient, point_cloud, pose3, sensor
from rmap_client.sim import BoxRoom


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--server", default="127.0.0.1:8080", help="rmapd's HOST:PORT")
    parser.add_argument("--map", default="py-demo", help="map to write (created on first use)")
    parser.add_argument("--robot", default="py-demo-robot", help="robot id")
    parser.add_argument("--token", default=None, help="bearer token (robot or admin role; none in loopback-only mode)")
    args = parser.parse_args()

    room = BoxRoom()
    sensors_m = [(0.0, 0.0, 1.2), (2.0, 1.5, 1.0), (-1.0, 2.0, 1.5)]
    try:
        with RobotClient(f"ws://{args.server}", args.robot, args.map, token=args.token,
                         sensors=[sensor("lidar", "LIDAR_3D", "simulated")], resolution_m=0.1) as robot:
            print(f"connected as {robot.welcome.robot_id} to map {robot.welcome.map} "
                  f"(resolution {robot.welcome.resolution_m} m, resuming after seq {robot.welcome.last_durable_seq})")
            latencies_s: list[float] = []
            robot.on_ack = lambda ack, latency_s: latencies_s.append(latency_s)
            points = 0
            for position_m in sensors_m:
                cloud = room.lidar_cloud(position_m)
                seq = robot.send(point_cloud(cloud, pose3(position_m), stamp_ns=time.time_ns()))
                points += len(cloud)
                print(f"sent cloud seq {seq}: {len(cloud)} points from {position_m}")
            if not robot.wait_all_acked(30):
                print(f"error: {robot.in_flight} clouds unacknowledged after 30 s", file=sys.stderr)
                return 1
            if robot.refused_count:
                print(f"error: {robot.refused_count} clouds refused: {robot.last_error}", file=sys.stderr)
                return 1
            print(f"{robot.acked_count} clouds ({points} points) acknowledged: durable and in the map; "
                  f"ack latency max {max(latencies_s) * 1e3:.1f} ms")

        maps = MapClient(f"http://{args.server}", token=args.token)
        info = maps.map_info(args.map)
        print(f"map {info['name']}: {info['cuboids']} cuboids, {info['occupied_cells']} occupied cells, "
              f"bounds {info['bounds']}")
        queries = {"the +x wall": (room.max_m[0], 0.5, 1.0), "the middle of the room": (1.0, 0.75, 1.2),
                   "outside the room": (10.0, 0.5, 1.0)}
        for name, point in queries.items():
            answer = maps.occupancy(args.map, point)
            where = f", cuboid {answer.cuboid.min_m}..{answer.cuboid.max_m} m" if answer.cuboid else ""
            print(f"{name} {point}: {answer.state} (p = {answer.probability:.3f}{where})")
    except RmapError as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
