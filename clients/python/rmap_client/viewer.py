"""Change notices: the viewer stream ``/v1/stream/viewer`` (docs/API.md §8).

The server pushes JSON text frames: ``hello`` once, then ``tiles`` (changed
map tiles with their versions), ``poses`` (latest robot poses),
``loop_closure``, ``loop_closure_withdrawn`` (the 2D pose graph dropped a stored
closure) and ``resync`` (frames were skipped: re-read the state over HTTP).
"""

from __future__ import annotations

import json
import queue
import time
from collections.abc import Callable, Iterator
from typing import Any

from websockets.exceptions import ConnectionClosed as _WebSocketClosed
from websockets.legacy.client import WebSocketClientProtocol

from ._io import LoopThread, Session, open_websocket, stream_url
from .errors import ConnectionClosed, RmapTimeout

Frame = dict[str, Any]

_RESYNC: Frame = {"type": "resync"}


class ViewerStream(Session):
    """Subscribes to a map's change notices (or every map's).

    Frames are queued as they arrive; a reader that falls more than
    ``max_queued_frames`` behind loses frames and then gets a
    ``{"type": "resync"}`` frame, as the server does to slow viewers.

    Example::

        with ViewerStream("ws://127.0.0.1:8080", "lab") as viewer:
            frame = viewer.wait_for(lambda f: f["type"] == "tiles", timeout_s=5)
    """

    def __init__(
        self,
        server_url: str,
        map_name: str | None = None,
        *,
        token: str | None = None,
        timeout_s: float = 10.0,
        max_queued_frames: int = 4096,
        max_frame_bytes: int = 64 << 20,
    ) -> None:
        """
        Args:
            server_url: ``ws://HOST:PORT`` of rmapd
            map_name: the one map to follow; None = every map
            token: bearer token, any role (None in loopback-only mode)
            timeout_s: bound of connect() and of the default frame wait
            max_queued_frames: frames held for the reader before it is made to resync
            max_frame_bytes: largest frame accepted, bytes
        """
        query = {"map": map_name} if map_name else None
        self._url = stream_url(server_url, "/v1/stream/viewer", query)
        self._token = token
        self._timeout_s = timeout_s
        self._max_queued = max(2, max_queued_frames)
        self._max_frame_bytes = max_frame_bytes
        self._frames: queue.Queue[Frame | Exception] = queue.Queue()
        self._dropping = False
        self._io: LoopThread | None = None
        self._ws: WebSocketClientProtocol | None = None

    def connect(self) -> Frame:
        """Opens the stream and returns its ``hello`` frame.

        Raises:
            HttpError: refused upgrade (401, 403 or 404 map_not_found)
            ConnectionClosed, RmapTimeout: no stream
        """
        if self._io is not None:
            raise RuntimeError("connect() was called already")
        self._io = LoopThread("rmap-viewer")
        try:
            self._ws = self._io.run(
                open_websocket(self._url, self._token, self._timeout_s, self._max_frame_bytes),
                self._timeout_s + 1.0,
                self._url,
            )
            self._io.submit(self._read(self._ws))
            hello = self.next_frame()
            if hello.get("type") != "hello":
                raise ConnectionClosed(f"{self._url}: the first frame is not a hello: {hello}")
        except BaseException:
            self.close()
            raise
        return hello

    def next_frame(self, timeout_s: float | None = None) -> Frame:
        """The next frame, waiting at most ``timeout_s`` (default: the stream's timeout).

        Raises:
            RmapTimeout: no frame in time
            ConnectionClosed: the stream ended (after every frame it delivered was read)
        """
        return self._take(self._timeout_s if timeout_s is None else timeout_s)

    def _take(self, wait_s: float | None) -> Frame:
        """The next frame; ``wait_s`` None waits as long as the stream lasts."""
        try:
            item = self._frames.get(timeout=wait_s)
        except queue.Empty:
            raise RmapTimeout(f"{self._url}: no frame within {wait_s:g} s") from None
        if isinstance(item, Exception):
            self._frames.put(item)  # every later read ends the same way
            raise item
        return item

    def wait_for(self, predicate: Callable[[Frame], bool], timeout_s: float) -> Frame:
        """Reads frames until one satisfies ``predicate``; returns it (the others are consumed).

        Raises:
            RmapTimeout: none within ``timeout_s``
        """
        deadline = time.monotonic() + timeout_s
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise RmapTimeout(f"{self._url}: no matching frame within {timeout_s:g} s")
            frame = self.next_frame(left)
            if predicate(frame):
                return frame

    def __iter__(self) -> Iterator[Frame]:
        """Frames as they come, until the stream closes."""
        while True:
            try:
                yield self._take(None)
            except ConnectionClosed:
                return

    def close(self) -> None:
        """Closes the WebSocket and stops the I/O thread."""
        if self._io is None:
            return
        try:
            if self._ws is not None:
                self._io.run(self._ws.close(), self._timeout_s, "close")
        except RmapTimeout:
            pass
        self._io.stop()

    async def _read(self, ws: WebSocketClientProtocol) -> None:
        try:
            async for text in ws:
                try:
                    frame = json.loads(text)
                except ValueError:
                    continue  # not one of the server's frames; nothing to deliver
                self._deliver(frame)
            self._frames.put(ConnectionClosed(f"viewer stream closed (code {ws.close_code}: {ws.close_reason})",
                                              ws.close_code, ws.close_reason))
        except _WebSocketClosed as closed:
            self._frames.put(ConnectionClosed(f"viewer stream lost ({closed})", closed.code, closed.reason))

    def _deliver(self, frame: Frame) -> None:
        # Same rule as the server's for slow viewers: drop while full, resync once below half.
        if self._dropping:
            if self._frames.qsize() > self._max_queued // 2:
                return
            self._frames.put(_RESYNC)
            self._dropping = False
        if self._frames.qsize() >= self._max_queued:
            self._dropping = True
            return
        self._frames.put(frame)
