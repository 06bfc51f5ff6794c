"""Bad input gets the server's error, as a clear exception or Error message,
and changes nothing; tokens and roles are enforced on both kinds of stream."""

from __future__ import annotations

import math
import socket
import time
import unittest

from rmap_client import (
    ConnectionClosed,
    HttpError,
    MapClient,
    RobotClient,
    StreamError,
    ViewerStream,
    camera_image,
    point_cloud,
    pose3,
)
from rmap_client.sim import BoxRoom

from rmapd_process import RmapdTestCase

ROOM = BoxRoom()
SENSOR_M = (0.0, 0.0, 1.2)


def room_cloud():
    return point_cloud(ROOM.lidar_cloud(SENSOR_M), pose3(SENSOR_M))


class BadInputTest(RmapdTestCase):
    config_yaml = "limits:\n  max_frame_bytes: 400000\n  max_batch_points: 1000\n"

    def setUp(self) -> None:
        self.maps = MapClient(self.rmapd.http_url)

    def test_a_refused_cloud_gets_an_error_and_changes_nothing(self) -> None:
        errors = []
        with RobotClient(self.rmapd.ws_url, "py-bad", "bad") as robot:
            robot.on_error = errors.append
            bad = point_cloud([(9.0, 9.0, 9.0), (1.0, math.nan, 1.0)], pose3(SENSOR_M))
            bad_seq = robot.send(bad)
            good_seq = robot.send(room_cloud())
            self.assertTrue(robot.wait_all_acked(30))
            self.assertEqual((robot.acked_count, robot.refused_count), (1, 1))
            self.assertTrue(robot.connected)  # not fatal: the stream goes on
        self.assertEqual(len(errors), 1)
        self.assertEqual((errors[0].code, errors[0].seq, errors[0].fatal), ("invalid_message", bad_seq, False))
        self.assertIn("point 1 is not finite", errors[0].message)
        self.assertEqual(good_seq, bad_seq + 1)
        # The refused cloud's valid point was not applied; the good cloud was.
        self.assertEqual(self.maps.occupancy("bad", (9.0, 9.0, 9.0)).state, "unknown")
        self.assertEqual(self.maps.occupancy("bad", (ROOM.max_m[0], 0.5, 1.0)).state, "occupied")
        self.assertEqual(self.maps.robot("py-bad")["last_seq"], good_seq)

    def test_a_refused_image_is_reported_with_its_seq(self) -> None:
        with RobotClient(self.rmapd.ws_url, "py-bad-image", "bad") as robot:
            seq = robot.send(camera_image(b"not a jpeg", "JPEG"))
            self.assertTrue(robot.wait_all_acked(30))
            self.assertEqual((robot.acked_count, robot.refused_count), (0, 1))
            self.assertEqual((robot.last_error.code, robot.last_error.seq), ("invalid_message", seq))

    def test_a_bad_hello_is_refused_with_a_fatal_error(self) -> None:
        robot = RobotClient(self.rmapd.ws_url, "not a valid id", "bad")
        with self.assertRaises(StreamError) as refused:
            robot.connect()
        self.assertEqual(refused.exception.code, "invalid_hello")
        self.assertTrue(refused.exception.fatal)
        self.assertIn("robot_id", refused.exception.message)
        with self.assertRaises(RuntimeError):
            robot.send(room_cloud())  # no session

    def test_a_replaced_session_ends_with_the_fatal_error(self) -> None:
        first = RobotClient(self.rmapd.ws_url, "py-twice", "twice", timeout_s=5)
        first.connect()
        with RobotClient(self.rmapd.ws_url, "py-twice", "twice") as second:
            deadline = time.monotonic() + 5
            while first.connected and time.monotonic() < deadline:
                time.sleep(0.02)
            self.assertFalse(first.connected)
            self.assertEqual((first.last_error.code, first.last_error.fatal), ("replaced", True))
            with self.assertRaises(StreamError) as ended:
                first.send(room_cloud())
            self.assertEqual(ended.exception.code, "replaced")
            second.send(room_cloud())
            self.assertTrue(second.wait_all_acked(30))
        first.close()

    def test_a_frame_over_the_servers_limit_is_refused_before_sending(self) -> None:
        with RobotClient(self.rmapd.ws_url, "py-big", "big") as robot:
            self.assertEqual(robot.welcome.max_frame_bytes, 400000)
            huge = point_cloud([(1.0, 1.0, 1.0)] * 40000, pose3(SENSOR_M))
            with self.assertRaisesRegex(ValueError, "exceeds the server's max_frame_bytes"):
                robot.send(huge)
            with self.assertRaisesRegex(ValueError, r"\(x, y, z\) triples"):
                point_cloud([(1.0, 2.0, 3.0), (1.0, 2.0)], pose3(SENSOR_M))
            self.assertEqual(robot.send(room_cloud()), 1)  # the refused one took no seq
            self.assertTrue(robot.wait_all_acked(30))

    def test_http_errors_carry_the_servers_code_and_message(self) -> None:
        with self.assertRaises(HttpError) as missing:
            self.maps.occupancy("no-such-map", (0.0, 0.0, 0.0))
        self.assertEqual((missing.exception.status, missing.exception.code), (404, "map_not_found"))
        self.assertEqual(missing.exception.message, "no map named 'no-such-map'")

        with RobotClient(self.rmapd.ws_url, "py-http", "http") as robot:
            robot.send(room_cloud())
            self.assertTrue(robot.wait_all_acked(30))
        with self.assertRaises(HttpError) as bad_box:
            self.maps.occupancy_box("http", (1.0, 1.0, 1.0), (0.0, 2.0, 2.0))
        self.assertEqual((bad_box.exception.status, bad_box.exception.code), (400, "invalid_argument"))
        self.assertIn("min must not exceed max", bad_box.exception.message)
        with self.assertRaises(HttpError) as too_many:
            self.maps.occupancy_batch("http", [(0.0, 0.0, 0.0)] * 1001)
        self.assertEqual((too_many.exception.status, too_many.exception.code), (413, "too_many_points"))
        with self.assertRaises(HttpError) as no_robot:
            self.maps.robot("nobody")
        self.assertEqual(no_robot.exception.code, "robot_not_found")

        with self.assertRaises(HttpError) as no_stream:
            ViewerStream(self.rmapd.ws_url, "no-such-map").connect()
        self.assertEqual((no_stream.exception.status, no_stream.exception.code), (404, "map_not_found"))

    def test_no_server_is_a_connection_error(self) -> None:
        with socket.socket() as s:  # a port nobody listens on
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        with self.assertRaises(ConnectionClosed):
            MapClient(f"http://127.0.0.1:{port}", timeout_s=2).health()
        with self.assertRaises(ConnectionClosed):
            RobotClient(f"ws://127.0.0.1:{port}", "py-none", "none", timeout_s=2).connect()
        with self.assertRaises(ValueError):
            MapClient("ftp://127.0.0.1:8080")


class TokenTest(RmapdTestCase):
    config_yaml = (
        "auth:\n  tokens:\n"
        "    - {token: robot-secret-01, role: robot, robot_id: bot-1}\n"
        "    - {token: viewer-secret-1, role: viewer}\n"
    )

    def test_roles_are_enforced(self) -> None:
        url = self.rmapd.ws_url
        with self.assertRaises(HttpError) as anonymous:
            RobotClient(url, "bot-1", "lab").connect()
        self.assertEqual((anonymous.exception.status, anonymous.exception.code), (401, "unauthenticated"))
        with self.assertRaises(HttpError) as viewer:
            RobotClient(url, "bot-1", "lab", token="viewer-secret-1").connect()
        self.assertEqual((viewer.exception.status, viewer.exception.code), (403, "permission_denied"))
        with self.assertRaises(StreamError) as impostor:
            RobotClient(url, "bot-2", "lab", token="robot-secret-01").connect()
        self.assertEqual((impostor.exception.code, impostor.exception.fatal), ("permission_denied", True))
        self.assertIn("bot-1", impostor.exception.message)

        with RobotClient(url, "bot-1", "lab", token="robot-secret-01") as robot:
            robot.send(room_cloud())
            self.assertTrue(robot.wait_all_acked(30))
            self.assertEqual(robot.acked_count, 1)

        with self.assertRaises(HttpError) as no_token:
            MapClient(self.rmapd.http_url).maps()
        self.assertEqual((no_token.exception.status, no_token.exception.code), (401, "unauthenticated"))
        maps = MapClient(self.rmapd.http_url, token="viewer-secret-1")
        self.assertEqual([m["name"] for m in maps.maps()], ["lab"])
        self.assertEqual(maps.occupancy("lab", (ROOM.max_m[0], 0.5, 1.0)).state, "occupied")
        stream = ViewerStream(url, "lab", token="viewer-secret-1")
        self.assertEqual(stream.connect(), {"map": "lab", "type": "hello"})
        stream.close()
        with self.assertRaises(HttpError) as viewer_anonymous:
            ViewerStream(url, "lab").connect()
        self.assertEqual(viewer_anonymous.exception.status, 401)


if __name__ == "__main__":
    unittest.main()
