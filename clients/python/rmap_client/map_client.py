"""rmapd's HTTP API with urllib: maps, occupancy queries, robots (docs/API.md §6).

Coordinates are metres in the map frame; a map's base cell i along an axis
spans [i * resolution_m, (i + 1) * resolution_m).
"""

from __future__ import annotations

import json
import urllib.error
import urllib.parse
import urllib.request
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

from . import proto
from .errors import ConnectionClosed, HttpError

State = Literal["free", "occupied", "unknown"]
Vec3 = Sequence[float]

_BATCH_STATES: dict[int, State] = {
    proto.CellState.Value("UNKNOWN"): "unknown",
    proto.CellState.Value("FREE"): "free",
    proto.CellState.Value("OCCUPIED"): "occupied",
}


@dataclass(frozen=True)
class Cuboid:
    """A stored cuboid of cells with one occupancy: corners in metres (``max_m`` is the upper edge)."""

    min_m: tuple[float, float, float]
    max_m: tuple[float, float, float]
    probability: float
    state: State

    def contains(self, point_m: Vec3) -> bool:
        return all(lo <= p < hi for lo, p, hi in zip(self.min_m, point_m, self.max_m))


@dataclass(frozen=True)
class Occupancy:
    """The state of the base cell holding a point.

    ``probability`` is 0.5 when unknown. ``cuboid`` is the stored cuboid
    holding the cell (point queries only; None when unknown and in batch answers).
    """

    state: State
    probability: float
    cuboid: Cuboid | None = None

    @property
    def occupied(self) -> bool:
        return self.state == "occupied"

    @property
    def free(self) -> bool:
        return self.state == "free"

    @property
    def unknown(self) -> bool:
        return self.state == "unknown"


def _vec3(values: Iterable[float]) -> tuple[float, float, float]:
    x, y, z = (float(v) for v in values)
    return (x, y, z)


def _csv(point_m: Vec3) -> str:
    return ",".join(repr(float(v)) for v in point_m)


class MapClient:
    """Blocking HTTP client of one rmapd (one request per call, urllib).

    Example::

        maps = MapClient("http://127.0.0.1:8080")
        if maps.occupancy("lab", (1.0, 2.0, 0.5)).occupied: ...
    """

    def __init__(self, server_url: str = "http://127.0.0.1:8080", *, token: str | None = None, timeout_s: float = 10.0) -> None:
        """
        Args:
            server_url: ``http://HOST:PORT`` of rmapd (``ws://`` is read as ``http://``)
            token: bearer token, any role (None in loopback-only mode)
            timeout_s: socket timeout of each request
        """
        parts = urllib.parse.urlsplit(server_url)
        scheme = {"http": "http", "ws": "http", "https": "https", "wss": "https"}.get(parts.scheme)
        if scheme is None or not parts.netloc:
            raise ValueError(f"server URL must be http://HOST:PORT, not {server_url!r}")
        self._base = urllib.parse.urlunsplit((scheme, parts.netloc, parts.path.rstrip("/"), "", ""))
        self._token = token
        self._timeout_s = timeout_s

    # ------------------------------------------------------------ requests

    def request(
        self,
        method: str,
        path: str,
        query: dict[str, Any] | None = None,
        body: bytes | None = None,
        content_type: str | None = None,
    ) -> tuple[bytes, dict[str, str]]:
        """One request; returns the body and the headers (names lower-case).

        Raises:
            HttpError: an error answer, with rmapd's code and message
            ConnectionClosed: no answer (connection refused, reset, timeout)
        """
        url = self._base + path
        if query:
            url += "?" + urllib.parse.urlencode({k: v for k, v in query.items() if v is not None})
        request = urllib.request.Request(url, data=body, method=method)
        if self._token:
            request.add_header("Authorization", f"Bearer {self._token}")
        if content_type:
            request.add_header("Content-Type", content_type)
        try:
            with urllib.request.urlopen(request, timeout=self._timeout_s) as response:
                return response.read(), {k.lower(): v for k, v in response.headers.items()}
        except urllib.error.HTTPError as error:
            raise HttpError.from_body(error.code, error.read(), f"{method} {path}") from None
        except (urllib.error.URLError, OSError) as error:
            raise ConnectionClosed(f"{method} {url}: {getattr(error, 'reason', error)}") from error

    def get_json(self, path: str, query: dict[str, Any] | None = None) -> Any:
        body, _ = self.request("GET", path, query)
        return json.loads(body)

    @staticmethod
    def _map_path(map_name: str, rest: str = "") -> str:
        return "/v1/maps/" + urllib.parse.quote(map_name, safe="") + rest

    # ------------------------------------------------------------- the API

    def health(self) -> dict[str, Any]:
        """``GET /healthz``: ``{"status": "ok", "maps": N, "version": ...}`` (no token needed)."""
        return self.get_json("/healthz")

    def maps(self) -> list[dict[str, Any]]:
        """Every map: name, resolution_m, version, cuboids, bounds, ... (docs/API.md §6.4)."""
        return self.get_json("/v1/maps")["maps"]

    def map_info(self, map_name: str) -> dict[str, Any]:
        """One map's figures. Raises HttpError 404 ``map_not_found``."""
        return self.get_json(self._map_path(map_name))

    def occupancy(self, map_name: str, point_m: Vec3) -> Occupancy:
        """State of the base cell holding ``point_m`` (x, y, z in metres)."""
        x, y, z = (float(v) for v in point_m)
        answer = self.get_json(self._map_path(map_name, "/occupancy"), {"x": repr(x), "y": repr(y), "z": repr(z)})
        cuboid = answer.get("cuboid")
        return Occupancy(
            answer["state"],
            float(answer["probability"]),
            None if cuboid is None else Cuboid(_vec3(cuboid["min"]), _vec3(cuboid["max"]), float(answer["probability"]), answer["state"]),
        )

    def occupancy_batch(self, map_name: str, points_m: Iterable[Vec3]) -> list[Occupancy]:
        """States of many points in one protobuf request, in request order (no cuboids).

        At most ``limits.max_batch_points`` points (2,000,000 by default; beyond:
        HttpError 413 ``too_many_points``).
        """
        request = proto.OccupancyBatchRequest()
        for point in points_m:
            x, y, z = point
            request.xyz_m.extend((x, y, z))
        body, _ = self.request(
            "POST", self._map_path(map_name, "/occupancy:batch"), body=request.SerializeToString(), content_type="application/x-protobuf"
        )
        answer = proto.OccupancyBatchResponse()
        answer.ParseFromString(body)
        return [Occupancy(_BATCH_STATES.get(s, "unknown"), p) for s, p in zip(answer.states, answer.probabilities)]

    def occupancy_box(self, map_name: str, min_m: Vec3, max_m: Vec3, *, page_size: int = 1000, max_cuboids: int | None = None) -> list[Cuboid]:
        """The stored cuboids (free and occupied) intersecting a box, whole (not clipped).

        Follows the server's pages of ``page_size`` cuboids (1..100,000) until
        the last one or until ``max_cuboids`` are read. Pages come from the
        live map: while it changes, cuboids may be missed or repeated.
        """
        cuboids: list[Cuboid] = []
        token: str | None = None
        while max_cuboids is None or len(cuboids) < max_cuboids:
            limit = page_size if max_cuboids is None else min(page_size, max_cuboids - len(cuboids))
            page = self.get_json(
                self._map_path(map_name, "/occupancy/box"),
                {"min": _csv(min_m), "max": _csv(max_m), "limit": limit, "page_token": token},
            )
            cuboids.extend(Cuboid(_vec3(c["min"]), _vec3(c["max"]), float(c["probability"]), c["state"]) for c in page["cuboids"])
            token = page.get("next_page_token")
            if token is None:
                break
        return cuboids

    def robots(self) -> list[dict[str, Any]]:
        """Every robot that ever sent a Hello: id, map, connected, last_seq, sensors, pose."""
        return self.get_json("/v1/robots")["robots"]

    def robot(self, robot_id: str) -> dict[str, Any]:
        """One robot. Raises HttpError 404 ``robot_not_found``."""
        return self.get_json("/v1/robots/" + urllib.parse.quote(robot_id, safe=""))

    def trajectory(self, robot_id: str, *, since_ns: int | None = None, limit: int | None = None) -> list[dict[str, Any]]:
        """The robot's poses (``position`` m, ``orientation`` [w, x, y, z], ``stamp_ns``, ``seq``), by stamp.

        One per applied cloud (its sensor pose) and per laser scan the 2D SLAM
        used (the estimated base pose); written up to ~0.5 s after the ack.
        """
        path = "/v1/robots/" + urllib.parse.quote(robot_id, safe="") + "/trajectory"
        return self.get_json(path, {"since_ns": since_ns, "limit": limit})["poses"]

    def layers(self, map_name: str) -> dict[str, Any]:
        """The map's 2D layers (laser SLAM): resolution, extent, scans (docs/API.md §7a)."""
        return self.get_json(self._map_path(map_name, "/layers"))

    def loop_closures(self, **filters: Any) -> list[dict[str, Any]]:
        """Stored loop closures; filters ``map``, ``robot``, ``source``, ``since``, ``limit`` (docs/API.md §6.10)."""
        return self.get_json("/v1/loop-closures", filters)["loop_closures"]
