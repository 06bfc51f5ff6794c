"""A 2D-laser robot streamed through RobotClient: scans with drifting wheel
odometry in a room with pillars get the server's 2D SLAM pose estimates,
which follow the true path where the odometry drifts away, and the scans
build the 2D layers and a planar slice of the 3D map at the laser's height."""

from __future__ import annotations

import math
import random
import threading
import time
import unittest

from rmap_client import MapClient, RobotClient, laser_scan, planar_pose3, pose2, sensor, yaw_rad
from rmap_client.sim import DriftingOdometry, Laser2d, PillarRoom, compose2, tour

from rmapd_process import RmapdTestCase

MOUNT_FORWARD_M = 0.15
MOUNT_HEIGHT_M = 0.5
STEP_NS = 100_000_000


class Laser2dRobotTest(RmapdTestCase):
    def test_pose_estimates_follow_the_truth_and_the_scans_make_the_maps(self) -> None:
        room, laser = PillarRoom(), Laser2d()
        truth_path = tour([(1.5, 1.5), (8.5, 1.5), (8.5, 4.5), (4.5, 4.5), (4.5, 1.5), (1.5, 1.5)])
        odometry = DriftingOdometry(truth_path[0], rng=random.Random(7))
        rng = random.Random(11)

        mount = planar_pose3(MOUNT_FORWARD_M, 0.0, 0.0, z_m=MOUNT_HEIGHT_M)
        robot = RobotClient(self.rmapd.ws_url, "py-walker", "floor", sensors=[sensor("front", "LASER_2D", "py_laser", mount)],
                            resolution_m=0.05)
        estimates = {}
        lock = threading.Lock()

        def on_pose(estimate) -> None:
            with lock:
                estimates[estimate.seq] = estimate

        robot.on_pose = on_pose
        robot.connect()
        truth_by_seq, odometry_by_seq = {}, {}
        for k, base in enumerate(truth_path):
            odometry_pose = odometry.step(base) if k else odometry.pose
            ranges = room.scan(laser, compose2(base, (MOUNT_FORWARD_M, 0.0, 0.0)), rng)
            scan = laser_scan(ranges, angle_min_rad=laser.angle_min_rad, angle_increment_rad=laser.angle_increment_rad,
                              range_min_m=laser.range_min_m, range_max_m=laser.range_max_m,
                              odometry=pose2(*odometry_pose), stamp_ns=k * STEP_NS, sensor_name="front")
            seq = robot.send(scan)
            truth_by_seq[seq], odometry_by_seq[seq] = base, odometry_pose
        self.assertTrue(robot.wait_all_acked(60))
        self.assertEqual(robot.acked_count, len(truth_path))
        robot.close()

        # Every scan got its estimate (sent before its ack): the robot base on z = 0, within
        # 0.1 m and 0.05 rad of the truth all along, while the odometry drifted much further.
        with lock:
            self.assertEqual(sorted(estimates), sorted(truth_by_seq))
        worst_m = worst_rad = odometry_end_m = 0.0
        for seq, base in truth_by_seq.items():
            e = estimates[seq]
            self.assertEqual(e.stamp_ns, (seq - 1) * STEP_NS)
            self.assertEqual(e.pose.position_m.z, 0.0)
            worst_m = max(worst_m, math.dist((e.pose.position_m.x, e.pose.position_m.y), base[:2]))
            worst_rad = max(worst_rad, abs(math.remainder(yaw_rad(e.pose) - base[2], math.tau)))
            odometry_end_m = math.dist(odometry_by_seq[seq][:2], base[:2])
        print(f"[ estimates ] {len(estimates)} scans, worst error {worst_m:.3f} m, {worst_rad:.4f} rad; "
              f"odometry ends {odometry_end_m:.3f} m off")
        self.assertLess(worst_m, 0.1)
        self.assertLess(worst_rad, 0.05)
        self.assertGreater(odometry_end_m, 3 * worst_m)

        maps = MapClient(self.rmapd.http_url)
        layers = maps.layers("floor")
        self.assertEqual(layers["scans"], len(truth_path))
        self.assertAlmostEqual(layers["resolution_m"], 0.05)
        self.assertEqual(set(layers["layers"]), {"occupancy", "reflectivity"})
        # The room's outline seen from inside, within a cell of its walls.
        lo, hi = layers["known_bounds"]["min"], layers["known_bounds"]["max"]
        for axis in range(2):
            self.assertAlmostEqual(lo[axis], room.min_m[axis], delta=0.1)
            self.assertAlmostEqual(hi[axis], room.max_m[axis], delta=0.1)

        # The planar cloud in the 3D map at the laser's height: walls and pillars occupied, the floor free.
        z = MOUNT_HEIGHT_M + 0.01
        pillar_lo = room.pillars[0][0]
        occupied = [(room.max_m[0], 3.0, z), (5.0, room.min_m[1], z), (pillar_lo[0], pillar_lo[1] + 0.5, z)]
        free = [(3.5, 3.0, z), (8.0, 3.0, z), (5.5, 1.0, z)]
        answers = maps.occupancy_batch("floor", occupied + free + [(3.5, 3.0, z + 1.0)])
        self.assertEqual([a.state for a in answers], ["occupied"] * 3 + ["free"] * 3 + ["unknown"])

        # The trajectory holds the estimates (written in batches, up to ~0.5 s after the acks).
        deadline = time.monotonic() + 10
        while len(poses := maps.trajectory("py-walker")) < len(truth_path) and time.monotonic() < deadline:
            time.sleep(0.1)
        self.assertEqual(len(poses), len(truth_path))
        last = estimates[max(estimates)]
        self.assertAlmostEqual(poses[-1]["position"][0], last.pose.position_m.x, places=5)


if __name__ == "__main__":
    unittest.main()
