"""Exceptions of the rmap client: every failure the server reports keeps its stable code."""

from __future__ import annotations

import json


class RmapError(Exception):
    """Base class of every error this package raises."""


class HttpError(RmapError):
    """An HTTP error answer of rmapd, also a refused WebSocket upgrade.

    rmapd answers errors as ``{"error": {"code": ..., "message": ...}}``
    (docs/API.md §4); ``code`` is the stable machine-readable part.
    """

    def __init__(self, status: int, code: str, message: str, what: str = "") -> None:
        self.status = status
        self.code = code
        self.message = message
        prefix = f"{what}: " if what else ""
        super().__init__(f"{prefix}HTTP {status} {code}: {message}")

    @classmethod
    def from_body(cls, status: int, body: bytes, what: str = "") -> "HttpError":
        """Reads rmapd's error JSON; a body that is not one is kept as the message."""
        try:
            error = json.loads(body.decode("utf-8"))["error"]
            return cls(status, str(error["code"]), str(error["message"]), what)
        except (ValueError, KeyError, TypeError, UnicodeDecodeError):
            text = body.decode("utf-8", "replace").strip()
            return cls(status, "", text or "(no body)", what)


class StreamError(RmapError):
    """An ``Error`` message of the robot stream (docs/API.md §5.5).

    ``seq`` is the refused message's sequence number (0 when the error is not
    tied to one); after a ``fatal`` error the server closes the stream.
    """

    def __init__(self, code: str, message: str, seq: int = 0, fatal: bool = False) -> None:
        self.code = code
        self.message = message
        self.seq = seq
        self.fatal = fatal
        where = f" (seq {seq})" if seq else ""
        kind = "fatal " if fatal else ""
        super().__init__(f"server {kind}error {code}{where}: {message}")


class ConnectionClosed(RmapError):
    """The WebSocket ended: closed by the server (with its close code and reason) or lost."""

    def __init__(self, description: str, code: int | None = None, reason: str = "") -> None:
        self.code = code
        self.reason = reason
        super().__init__(description)


class RmapTimeout(RmapError, TimeoutError):
    """A wait ran out of time (connect, Welcome, a full in-flight window, a frame)."""
