"""A robot's stream to rmapd: WebSocket ``/v1/stream/robot``, one protobuf
``RobotMessage`` per binary frame out and one ``ServerMessage`` per frame back
(proto/rmap/v1/robot_stream.proto, docs/API.md §5)."""

from __future__ import annotations

import asyncio
import logging
import threading
import time
from collections.abc import Callable, Sequence

from google.protobuf.message import DecodeError
from websockets.exceptions import ConnectionClosed as _WebSocketClosed
from websockets.legacy.client import WebSocketClientProtocol

from . import proto
from ._io import LoopThread, Session, open_websocket, stream_url
from .errors import ConnectionClosed, RmapTimeout, StreamError
from .messages import robot_message

_log = logging.getLogger("rmap_client")

# The largest ServerMessage rmapd sends is far below this; it bounds a broken peer.
_MAX_SERVER_FRAME_BYTES = 1 << 20

AckCallback = Callable[[proto.Ack, float], None]
PoseCallback = Callable[[proto.PoseEstimate], None]
ErrorCallback = Callable[[proto.Error], None]
Body = proto.RobotMessage | proto.PointCloud | proto.LaserScan2D | proto.CameraImage | proto.Odometry


def _stream_error(error: proto.Error) -> StreamError:
    return StreamError(error.code, error.message, error.seq, error.fatal)


def _parse_reply(frame: bytes | str) -> proto.ServerMessage | None:
    """The ServerMessage of a binary frame; None for anything else."""
    if not isinstance(frame, bytes):
        return None
    reply = proto.ServerMessage()
    try:
        reply.ParseFromString(frame)
    except DecodeError:
        return None
    return reply


class RobotClient(Session):
    """One robot session: Hello, Welcome, then data messages acknowledged once durable.

    Sequence numbers continue after ``Welcome.last_durable_seq``, so a robot
    that reconnects with the same id never reuses one. At most
    ``max_in_flight`` messages are unanswered: ``send()`` blocks beyond that,
    which paces the robot to what the server makes durable (keep it below
    the server's ``limits.max_in_flight_per_robot``, 256 by default).

    Callbacks run on the client's I/O thread, before the message counts as
    answered (so when ``wait_all_acked()`` returns True every callback of
    those messages has run); they must not call ``send()``,
    ``wait_all_acked()`` or ``close()``. Set them before ``connect()``.

    One session per instance: to reconnect, make a new client with the same
    robot id and resend() the messages that were never acknowledged (those
    the server held already are acked as duplicates).

    Example::

        with RobotClient("ws://127.0.0.1:8080", "bot-1", "lab") as robot:
            robot.send(point_cloud(points, sensor_pose=pose3((0, 0, 1))))
            robot.wait_all_acked(10)
    """

    def __init__(
        self,
        server_url: str,
        robot_id: str,
        map_name: str,
        *,
        token: str | None = None,
        sensors: Sequence[proto.SensorDescription] = (),
        resolution_m: float = 0.0,
        max_in_flight: int = 64,
        timeout_s: float = 10.0,
    ) -> None:
        """
        Args:
            server_url: ``ws://HOST:PORT`` of rmapd (the stream path is added)
            robot_id: 1..64 characters of [A-Za-z0-9._-]
            map_name: the map this robot writes; created on first use
            token: bearer token (None in loopback-only mode)
            sensors: the robot's sensors for the Hello (see messages.sensor)
            resolution_m: base cell edge of a new map in metres, 0 = server default
            max_in_flight: unanswered messages before send() blocks, >= 1
            timeout_s: bound of connect(), of a blocked send() and of close()
        """
        if max_in_flight < 1:
            raise ValueError("max_in_flight must be >= 1")
        self._url = stream_url(server_url, "/v1/stream/robot")
        self._token = token
        self._hello = proto.Hello(robot_id=robot_id, map=map_name, resolution_m=resolution_m)
        self._hello.sensors.extend(sensors)
        self._max_in_flight = max_in_flight
        self._timeout_s = timeout_s
        self.on_ack: AckCallback | None = None
        self.on_pose: PoseCallback | None = None
        self.on_error: ErrorCallback | None = None

        self._io: LoopThread | None = None
        self._outbox: asyncio.Queue[bytes | None] | None = None
        self._tasks: list[asyncio.Task[None]] = []  # the reader and the writer
        self._send_lock = threading.Lock()  # frames leave in seq order
        self._cv = threading.Condition()
        self._welcome: proto.Welcome | None = None
        self._next_seq = 1
        self._in_flight: dict[int, float] = {}  # seq -> send time, time.monotonic() s
        self._acked = 0
        self._refused = 0
        self._last_error: proto.Error | None = None
        self._failure: Exception | None = None  # why the session ended

    # ------------------------------------------------------------------ API

    def connect(self) -> proto.Welcome:
        """Opens the stream, sends Hello and waits for Welcome.

        Raises:
            HttpError: the upgrade was refused (e.g. 401 unauthenticated, 403 permission_denied)
            StreamError: the server answered the Hello with an Error (e.g. invalid_hello)
            ConnectionClosed, RmapTimeout: no session
        """
        if self._io is not None:
            raise RuntimeError("connect() was called already; make a new RobotClient to reconnect")
        self._io = LoopThread(f"rmap-robot-{self._hello.robot_id}")
        try:
            welcome = self._io.run(self._open(), self._timeout_s, f"{self._url}: Hello")
        except BaseException:
            self._io.stop()
            raise
        return welcome

    @property
    def welcome(self) -> proto.Welcome:
        if self._welcome is None:
            raise RuntimeError("not connected: call connect() first")
        return self._welcome

    def send(self, message: Body) -> int:
        """Numbers a message with the next sequence number, queues it and returns that number.

        ``message`` is a RobotMessage (its ``seq`` is set) or its body
        (PointCloud, LaserScan2D, CameraImage, Odometry; see the builders in
        rmap_client.messages). Blocks while ``max_in_flight`` messages are unanswered.

        Raises:
            ValueError: the frame would exceed ``Welcome.max_frame_bytes``
            StreamError: the session ended with a fatal error
            ConnectionClosed: the stream is closed
            RmapTimeout: the window stayed full for ``timeout_s``
        """
        framed = message if isinstance(message, proto.RobotMessage) else robot_message(message)
        return self._queue(framed, None)

    def resend(self, message: proto.RobotMessage) -> int:
        """Sends a message of an earlier session again, with its own ``seq`` (docs/API.md §5.10).

        One the server holds already is acked with ``duplicate`` set and not
        applied twice; one it does not hold (it was never acked) is stored and
        applied. Later send() calls continue after the highest seq used.
        Raises as send() does, and ValueError for a seq < 1 or one in flight.
        """
        if message.seq < 1:
            raise ValueError("resend() needs the message's original seq (>= 1)")
        return self._queue(message, message.seq)

    def _queue(self, framed: proto.RobotMessage, seq: int | None) -> int:
        """Numbers (unless ``seq`` is given) and queues a message, within the in-flight window."""
        if framed.HasField("hello"):
            raise ValueError("the Hello is sent by connect()")
        welcome = self.welcome
        with self._send_lock:
            with self._cv:
                deadline = time.monotonic() + self._timeout_s
                while self._failure is None and len(self._in_flight) >= self._max_in_flight:
                    left = deadline - time.monotonic()
                    if left <= 0:
                        raise RmapTimeout(
                            f"{len(self._in_flight)} messages unanswered for {self._timeout_s:g} s (in-flight window full)"
                        )
                    self._cv.wait(left)
                if self._failure is not None:
                    raise self._failure
                if seq is None:
                    seq = self._next_seq
                elif seq in self._in_flight:
                    raise ValueError(f"seq {seq} is in flight already")
            framed.seq = seq
            data = framed.SerializeToString()
            if welcome.max_frame_bytes and len(data) > welcome.max_frame_bytes:
                raise ValueError(
                    f"message of {len(data)} bytes exceeds the server's max_frame_bytes ({welcome.max_frame_bytes})"
                )
            with self._cv:
                self._next_seq = max(self._next_seq, seq + 1)
                self._in_flight[seq] = time.monotonic()
            assert self._io is not None and self._outbox is not None
            self._io.loop.call_soon_threadsafe(self._outbox.put_nowait, data)
        return seq

    def wait_all_acked(self, timeout_s: float) -> bool:
        """Waits until every sent message is answered: acked, or refused with an Error.

        Returns False on timeout or when the session ended first. Refused
        messages count in ``refused_count`` and reach ``on_error``.
        """
        deadline = time.monotonic() + timeout_s
        with self._cv:
            while self._in_flight and self._failure is None:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._cv.wait(left)
            return not self._in_flight

    @property
    def last_sent_seq(self) -> int:
        with self._cv:
            return self._next_seq - 1

    @property
    def acked_count(self) -> int:
        """Acks received for messages of this session (duplicate acks included)."""
        with self._cv:
            return self._acked

    @property
    def refused_count(self) -> int:
        """Messages of this session the server answered with an Error."""
        with self._cv:
            return self._refused

    @property
    def in_flight(self) -> int:
        with self._cv:
            return len(self._in_flight)

    @property
    def last_error(self) -> proto.Error | None:
        """The last Error message received, if any."""
        with self._cv:
            return self._last_error

    @property
    def connected(self) -> bool:
        with self._cv:
            return self._welcome is not None and self._failure is None

    def close(self) -> None:
        """Sends the frames still queued, closes the WebSocket normally and stops the I/O thread.

        Messages not yet acknowledged stay unanswered: call wait_all_acked() first.
        """
        if self._io is None:
            return
        if self._outbox is not None:
            self._io.loop.call_soon_threadsafe(self._outbox.put_nowait, None)
            try:
                self._io.run(self._closed(), self._timeout_s, "close")
            except RmapTimeout:
                pass
        self._end(ConnectionClosed("closed by the client"))
        self._io.stop()

    # ------------------------------------------------------------ I/O side

    async def _open(self) -> proto.Welcome:
        ws = await open_websocket(self._url, self._token, self._timeout_s, _MAX_SERVER_FRAME_BYTES)
        try:
            await ws.send(proto.RobotMessage(hello=self._hello).SerializeToString())
            try:
                frame = await ws.recv()
            except _WebSocketClosed as closed:
                raise ConnectionClosed(f"{self._url}: closed before Welcome ({closed})", closed.code, closed.reason)
            reply = _parse_reply(frame)
            if reply is None:
                raise ConnectionClosed(f"{self._url}: the server's first frame is not a ServerMessage")
            if reply.HasField("error"):
                with self._cv:
                    self._last_error = reply.error
                raise _stream_error(reply.error)  # before Welcome any error refuses the session
            if not reply.HasField("welcome"):
                raise ConnectionClosed(f"{self._url}: the server's first frame is not a Welcome")
        except BaseException:
            await ws.close()
            raise
        self._outbox = asyncio.Queue()
        with self._cv:
            self._welcome = reply.welcome
            self._next_seq = reply.welcome.last_durable_seq + 1
        self._tasks = [asyncio.ensure_future(self._read(ws)), asyncio.ensure_future(self._write(ws, self._outbox))]
        return reply.welcome

    async def _closed(self) -> None:
        await asyncio.wait(self._tasks)

    async def _write(self, ws: WebSocketClientProtocol, outbox: asyncio.Queue[bytes | None]) -> None:
        try:
            while (data := await outbox.get()) is not None:
                await ws.send(data)
            await ws.close()
        except (_WebSocketClosed, OSError):
            pass  # the reader reports why the connection ended

    async def _read(self, ws: WebSocketClientProtocol) -> None:
        try:
            async for frame in ws:
                reply = _parse_reply(frame)
                if reply is None:
                    self._end(ConnectionClosed("the server sent a frame that is not a ServerMessage"))
                    await ws.close()
                    return
                self._dispatch(reply)
            self._end(ConnectionClosed(f"stream closed (code {ws.close_code}: {ws.close_reason})", ws.close_code, ws.close_reason))
        except _WebSocketClosed as closed:
            self._end(ConnectionClosed(f"stream lost ({closed})", closed.code, closed.reason))

    def _callback(self, callback: Callable[..., None] | None, *args: object) -> None:
        if callback is None:
            return
        try:
            callback(*args)
        except Exception:
            _log.exception("rmap_client: a RobotClient callback raised")

    def _dispatch(self, reply: proto.ServerMessage) -> None:
        kind = reply.WhichOneof("body")
        if kind == "ack":
            with self._cv:
                sent = self._in_flight.get(reply.ack.seq)
            if sent is None:
                return  # a repeat: it answers nothing in flight
            self._callback(self.on_ack, reply.ack, time.monotonic() - sent)
            with self._cv:
                del self._in_flight[reply.ack.seq]
                self._acked += 1
                self._cv.notify_all()
        elif kind == "pose":
            self._callback(self.on_pose, reply.pose)
        elif kind == "error":
            error = reply.error
            self._callback(self.on_error, error)
            with self._cv:
                self._last_error = error
                if self._in_flight.pop(error.seq, None) is not None:
                    self._refused += 1
                self._cv.notify_all()
            if error.fatal:
                self._end(_stream_error(error))
        # A second Welcome or a newer server's message kind: nothing to do with it.

    def _end(self, why: Exception) -> None:
        """Ends the session; the first reason wins (a fatal Error before the close it causes)."""
        with self._cv:
            if self._failure is None:
                self._failure = why
            self._cv.notify_all()
