"""Clouds of a box room streamed through RobotClient into a real rmapd: every
message is acknowledged, the occupancy answers (point, batch, box) match the
room, and a reconnecting robot's sequence numbers continue after the server's."""

from __future__ import annotations

import threading
import unittest

from rmap_client import (
    MapClient,
    RobotClient,
    ViewerStream,
    camera_image,
    odometry,
    planar_pose3,
    point_cloud,
    pose3,
    proto,
    sensor,
)
from rmap_client.messages import robot_message
from rmap_client.sim import BoxRoom

from rmapd_process import RmapdTestCase

ROOM = BoxRoom()
SENSORS_M = [(0.0, 0.0, 1.2), (2.0, 1.5, 1.0), (-1.0, 2.0, 1.5), (3.0, -0.5, 0.8)]


class RobotStreamTest(RmapdTestCase):
    def stream_room(self, robot_id: str, map_name: str) -> tuple[RobotClient, list[int], list[int]]:
        """Streams one cloud per sensor position; returns the client, the sent and the acked seqs."""
        lidar = sensor("lidar", "LIDAR_3D", "box-room-lidar")
        robot = RobotClient(self.rmapd.ws_url, robot_id, map_name, sensors=[lidar], resolution_m=0.1, max_in_flight=2)
        acked: list[int] = []
        lock = threading.Lock()

        def on_ack(ack, latency_s: float) -> None:
            self.assertFalse(ack.duplicate)
            self.assertGreaterEqual(latency_s, 0.0)
            with lock:
                acked.append(ack.seq)

        robot.on_ack = on_ack
        welcome = robot.connect()
        self.assertEqual(welcome.robot_id, robot_id)
        self.assertEqual(welcome.map, map_name)
        self.assertAlmostEqual(welcome.resolution_m, 0.1)
        sent = [robot.send(point_cloud(ROOM.lidar_cloud(s), pose3(s), stamp_ns=1_000 + k)) for k, s in enumerate(SENSORS_M)]
        self.assertTrue(robot.wait_all_acked(30), f"unanswered: {robot.in_flight}")
        return robot, sent, acked

    def test_every_cloud_is_acked_and_the_map_holds_the_room(self) -> None:
        robot, sent, acked = self.stream_room("py-room", "room")
        robot.close()
        self.assertEqual(sent, [1, 2, 3, 4])
        self.assertEqual(sorted(acked), sent)
        self.assertEqual(robot.refused_count, 0)

        maps = MapClient(self.rmapd.http_url)
        info = maps.map_info("room")
        self.assertEqual(info["name"], "room")
        self.assertGreater(info["occupied_cells"], 0)
        # The known cells span the room: its walls' cells, and nothing beyond.
        lo, hi = info["bounds"]["min"], info["bounds"]["max"]
        for axis in range(3):
            self.assertAlmostEqual(lo[axis], ROOM.min_m[axis], delta=0.1 + 1e-9)
            self.assertAlmostEqual(hi[axis], ROOM.max_m[axis], delta=0.1 + 1e-9)

        walls = [(ROOM.max_m[0], 0.5, 1.0), (ROOM.min_m[0], 0.5, 1.0), (1.0, ROOM.max_m[1], 1.3), (0.5, 0.5, ROOM.min_m[2])]
        inside = [(1.0, 0.5, 1.0), (0.0, 1.0, 1.5), (2.5, 0.0, 1.2)]
        outside = [(6.0, 0.5, 1.0), (1.0, 1.0, 5.0), (40.0, -30.0, 2.0)]
        for p in walls:
            answer = maps.occupancy("room", p)
            self.assertEqual(answer.state, "occupied", p)
            self.assertGreater(answer.probability, 0.5)
            self.assertIsNotNone(answer.cuboid)
            self.assertTrue(answer.cuboid.contains(p), (p, answer.cuboid))
        for p in inside:
            answer = maps.occupancy("room", p)
            self.assertEqual(answer.state, "free", p)
            self.assertLess(answer.probability, 0.5)
        for p in outside:
            answer = maps.occupancy("room", p)
            self.assertEqual(answer.state, "unknown", p)
            self.assertEqual(answer.probability, 0.5)
            self.assertIsNone(answer.cuboid)

        # The protobuf batch answers what the point queries answer, in request order.
        points = walls + inside + outside
        batch = maps.occupancy_batch("room", points)
        self.assertEqual([a.state for a in batch], ["occupied"] * 4 + ["free"] * 3 + ["unknown"] * 3)
        for p, a in zip(points, batch):
            self.assertAlmostEqual(a.probability, maps.occupancy("room", p).probability, places=6)

        # Every beam's end is occupied (but for a few corner cells that rays along the other
        # wall cross) and the middle of every beam is free.
        ends = [p for s in SENSORS_M for p in ROOM.lidar_cloud(s)]
        middles = [tuple((a + b) / 2 for a, b in zip(s, p)) for s in SENSORS_M for p in ROOM.lidar_cloud(s)]
        end_states = [a.state for a in maps.occupancy_batch("room", ends)]
        self.assertGreater(end_states.count("occupied"), 0.99 * len(ends))
        self.assertEqual([a.state for a in maps.occupancy_batch("room", middles)], ["free"] * len(middles))

        # A box around the +x wall: occupied cuboids at the wall, free ones inside, read over pages.
        box = maps.occupancy_box("room", (3.5, 0.0, 0.5), (4.5, 1.0, 1.5), page_size=7)
        self.assertGreater(len(box), 7)
        self.assertTrue(any(c.state == "occupied" and c.min_m[0] <= ROOM.max_m[0] < c.max_m[0] for c in box))
        self.assertTrue(all(c.max_m[0] <= ROOM.max_m[0] + 0.1 + 1e-9 for c in box))  # nothing known beyond the wall
        self.assertEqual(len(maps.occupancy_box("room", (3.5, 0.0, 0.5), (4.5, 1.0, 1.5), max_cuboids=3)), 3)

    def test_a_reconnecting_robot_continues_after_the_last_durable_seq(self) -> None:
        first, sent, _ = self.stream_room("py-again", "again")
        first.close()
        second = RobotClient(self.rmapd.ws_url, "py-again", "again")
        duplicates = []
        second.on_ack = lambda ack, latency_s: duplicates.append((ack.seq, ack.duplicate))
        with second:
            self.assertEqual(second.welcome.last_durable_seq, sent[-1])
            seq = second.send(point_cloud(ROOM.lidar_cloud((0.5, 0.5, 1.0)), pose3((0.5, 0.5, 1.0))))
            self.assertEqual(seq, sent[-1] + 1)
            # A message of the first session sent again with its seq: acked as a duplicate,
            # whatever it holds, and not applied (it would mark a point far outside the room).
            again = robot_message(point_cloud([(30.0, 30.0, 1.0)], pose3(SENSORS_M[1])))
            again.seq = sent[1]
            self.assertEqual(second.resend(again), sent[1])
            self.assertTrue(second.wait_all_acked(30))
            self.assertEqual(second.acked_count, 2)
            self.assertEqual(second.send(point_cloud([(1.0, 1.0, 1.0)], pose3(SENSORS_M[0]))), seq + 1)
            self.assertTrue(second.wait_all_acked(30))
        self.assertEqual(sorted(duplicates), [(sent[1], True), (seq, False), (seq + 1, False)])
        self.assertEqual(MapClient(self.rmapd.http_url).occupancy("again", (30.0, 30.0, 1.0)).state, "unknown")
        robot = MapClient(self.rmapd.http_url).robot("py-again")
        self.assertEqual(robot["last_seq"], sent[-1] + 2)
        self.assertFalse(robot["connected"])
        self.assertEqual(robot["sensors"], [])  # the second Hello declared none

    def test_images_and_odometry_are_acked_and_a_posed_image_places_the_robot(self) -> None:
        pixels = bytes((x * 7 + y * 13) % 256 for y in range(48) for x in range(64))
        camera_pose = planar_pose3(1.5, -0.5, 0.3, z_m=1.1)
        with RobotClient(self.rmapd.ws_url, "py-camera", "camera") as robot:
            robot.send(odometry(pose3((0.2, 0.1, 0.0)), stamp_ns=10))
            robot.send(camera_image(pixels, "MONO8", width=64, height=48, camera_pose=camera_pose, stamp_ns=20))
            self.assertTrue(robot.wait_all_acked(30))
            self.assertEqual((robot.acked_count, robot.refused_count), (2, 0))
            with self.assertRaisesRegex(TypeError, "not a robot message body"):
                robot.send(proto.Pose3())
        pose = MapClient(self.rmapd.http_url).robot("py-camera")["pose"]
        self.assertEqual(pose["seq"], 2)
        self.assertEqual(pose["stamp_ns"], 20)
        for axis, value in enumerate((1.5, -0.5, 1.1)):
            self.assertAlmostEqual(pose["position"][axis], value, places=6)
        self.assertAlmostEqual(pose["orientation"][3], camera_pose.orientation.z, places=6)

    def test_the_viewer_stream_announces_changed_tiles_and_poses(self) -> None:
        with ViewerStream(self.rmapd.ws_url) as viewer:  # every map: "watched" does not exist yet
            robot, sent, _ = self.stream_room("py-watched", "watched")
            robot.close()
            tiles = viewer.wait_for(lambda f: f["type"] == "tiles" and f["map"] == "watched", timeout_s=10)
            self.assertEqual(tiles["map"], "watched")
            self.assertGreater(len(tiles["tiles"]), 0)
            levels = {t[0] for t in tiles["tiles"]}
            self.assertEqual(levels, set(range(7)))  # a changed block changes a tile on every level
            poses = viewer.wait_for(lambda f: f["type"] == "poses" and f["map"] == "watched", timeout_s=10)
            ours = [p for p in poses["poses"] if p["robot_id"] == "py-watched"]
            self.assertEqual(len(ours), 1)
            self.assertIn(ours[0]["seq"], sent)
            # The pose is the sensor pose of that cloud.
            expected = SENSORS_M[sent.index(ours[0]["seq"])]
            for axis in range(3):
                self.assertAlmostEqual(ours[0]["position"][axis], expected[axis], places=5)


if __name__ == "__main__":
    unittest.main()
