"""The I/O side shared by the WebSocket clients: an asyncio loop on its own
thread (so the public API is plain blocking calls) and the WebSocket opening
that turns a refused upgrade into rmapd's HTTP error."""

from __future__ import annotations

import asyncio
import concurrent.futures
import threading
import urllib.parse
from collections.abc import Coroutine
from typing import Any, Self, TypeVar

from websockets.exceptions import InvalidHandshake, InvalidURI
from websockets.legacy.client import WebSocketClientProtocol, connect

from .errors import ConnectionClosed, HttpError, RmapTimeout

T = TypeVar("T")

_MAX_ERROR_BODY_BYTES = 1 << 16


class LoopThread:
    """An event loop running on a daemon thread until stop()."""

    def __init__(self, name: str) -> None:
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self.loop.run_forever, name=name, daemon=True)
        self._thread.start()

    def submit(self, coroutine: Coroutine[Any, Any, T]) -> concurrent.futures.Future[T]:
        return asyncio.run_coroutine_threadsafe(coroutine, self.loop)

    def run(self, coroutine: Coroutine[Any, Any, T], timeout_s: float, what: str) -> T:
        """Runs a coroutine on the loop and waits for its result.

        Raises:
            RmapTimeout: after ``timeout_s`` (the coroutine is cancelled)
        """
        future = self.submit(coroutine)
        try:
            return future.result(timeout_s)
        except concurrent.futures.TimeoutError:
            future.cancel()
            raise RmapTimeout(f"{what}: no answer within {timeout_s:g} s") from None

    def stop(self) -> None:
        """Cancels what still runs on the loop, stops it and joins the thread."""
        if not self._thread.is_alive():
            return

        async def cancel_all() -> None:
            tasks = [t for t in asyncio.all_tasks() if t is not asyncio.current_task()]
            for task in tasks:
                task.cancel()
            await asyncio.gather(*tasks, return_exceptions=True)

        try:
            self.submit(cancel_all()).result(5.0)
        except concurrent.futures.TimeoutError:
            pass
        self.loop.call_soon_threadsafe(self.loop.stop)
        self._thread.join()
        self.loop.close()


def stream_url(server_url: str, path: str, query: dict[str, str] | None = None) -> str:
    """The WebSocket URL of one of rmapd's streams.

    ``server_url`` is ``ws://HOST:PORT`` (``http://`` is read as ``ws://``,
    ``https://`` as ``wss://``); a path other than ``/`` is kept as a prefix
    (a proxy's), then ``path`` is appended.
    """
    parts = urllib.parse.urlsplit(server_url)
    scheme = {"ws": "ws", "http": "ws", "wss": "wss", "https": "wss"}.get(parts.scheme)
    if scheme is None or not parts.netloc:
        raise ValueError(f"server URL must be ws://HOST:PORT (or http://, wss://, https://), not {server_url!r}")
    prefix = parts.path.rstrip("/")
    encoded = urllib.parse.urlencode(query) if query else ""
    return urllib.parse.urlunsplit((scheme, parts.netloc, prefix + path, encoded, ""))


class _RefusalReadingProtocol(WebSocketClientProtocol):
    """Reads the body of a refused upgrade, which carries rmapd's error JSON."""

    async def read_http_response(self) -> Any:
        status, headers = await super().read_http_response()
        if status != 101:
            body = b""
            length = headers.get("Content-Length", "")
            if length.isdigit() and int(length) > 0:
                try:
                    body = await asyncio.wait_for(
                        self.reader.readexactly(min(int(length), _MAX_ERROR_BODY_BYTES)), timeout=5.0
                    )
                except asyncio.IncompleteReadError as partial:
                    body = partial.partial
                except asyncio.TimeoutError:
                    pass
            raise HttpError.from_body(status, body, "WebSocket upgrade refused")
        return status, headers


async def open_websocket(url: str, token: str | None, timeout_s: float, max_frame_bytes: int) -> WebSocketClientProtocol:
    """Opens a WebSocket to rmapd.

    The token goes in ``Authorization: Bearer``. No client pings: rmapd pings
    its peers and the library answers them; a client ping unanswered while
    the server pauses reading (back-pressure) would close a live stream.

    Raises:
        HttpError: the server refused the upgrade (its status, code and message)
        ConnectionClosed: the TCP connection or the handshake failed
        RmapTimeout: no upgrade within ``timeout_s``
    """
    headers = {"Authorization": f"Bearer {token}"} if token else None
    try:
        return await connect(
            url,
            create_protocol=_RefusalReadingProtocol,
            extra_headers=headers,
            compression=None,
            open_timeout=timeout_s,
            ping_interval=None,
            max_size=max_frame_bytes,
            user_agent_header="rmap-python-client",
        )
    except HttpError:
        raise
    except asyncio.TimeoutError:
        raise RmapTimeout(f"{url}: no WebSocket upgrade within {timeout_s:g} s") from None
    except (OSError, InvalidHandshake, InvalidURI) as error:
        raise ConnectionClosed(f"{url}: {error}") from error


class Session:
    """``with`` support of the WebSocket clients (which define connect() and close()):
    connects on entry unless connected already, closes on exit."""

    _io: LoopThread | None

    def __enter__(self) -> Self:
        if self._io is None:
            self.connect()  # type: ignore[attr-defined]
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()  # type: ignore[attr-defined]
