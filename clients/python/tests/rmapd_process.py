"""A real rmapd for the tests: a child process on 127.0.0.1 port 0 whose bound
port is read from its first stdout line (as tests/integration/rmapd_process.cc does).

The binary comes from the environment variable RMAPD (ctest sets it).
"""

from __future__ import annotations

import os
import re
import select
import signal
import subprocess
import tempfile
import time
import unittest
from pathlib import Path


class Rmapd:
    """Starts rmapd with ``--listen 127.0.0.1:0 --data-dir TMP`` (plus a config file when given)."""

    def __init__(self, config_yaml: str = "", startup_timeout_s: float = 60.0) -> None:
        binary = os.environ.get("RMAPD")
        if not binary:
            raise RuntimeError("set RMAPD to the rmapd binary (ctest does: build/bin/rmapd)")
        self._dir = tempfile.TemporaryDirectory(prefix="rmap-python-")
        base = Path(self._dir.name)
        args = [binary, "--listen", "127.0.0.1:0", "--data-dir", str(base / "data")]
        if config_yaml:
            (base / "config.yaml").write_text(config_yaml)
            args += ["--config", str(base / "config.yaml")]
        self._log_path = base / "rmapd.log"
        with open(self._log_path, "wb") as log:
            self._process = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=log)
        line = self._first_line(startup_timeout_s)
        match = re.search(r"listening on http://127\.0\.0\.1:(\d+)/", line)
        if not match:
            self.stop()
            raise RuntimeError(f"rmapd did not start (stdout: {line!r}); its log:\n{self.log()}")
        self.port = int(match.group(1))
        self.http_url = f"http://127.0.0.1:{self.port}"
        self.ws_url = f"ws://127.0.0.1:{self.port}"

    def _first_line(self, timeout_s: float) -> str:
        assert self._process.stdout is not None
        out = self._process.stdout.fileno()
        data = b""
        deadline = time.monotonic() + timeout_s
        while b"\n" not in data:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([out], [], [], left)[0]:
                break
            chunk = os.read(out, 256)
            if not chunk:
                break
            data += chunk
        return data.decode("utf-8", "replace")

    def log(self) -> str:
        """What rmapd wrote to stderr so far."""
        return self._log_path.read_text(errors="replace")

    def stop(self) -> int | None:
        """SIGTERM, then SIGKILL after 30 s; returns the exit code and removes the data directory."""
        code = None
        if self._process.poll() is None:
            self._process.send_signal(signal.SIGTERM)
            try:
                code = self._process.wait(30)
            except subprocess.TimeoutExpired:
                self._process.kill()
                self._process.wait()
        else:
            code = self._process.returncode
        if self._process.stdout is not None:
            self._process.stdout.close()
        self._dir.cleanup()
        return code


class RmapdTestCase(unittest.TestCase):
    """Test cases sharing one rmapd per class, started with the class's ``config_yaml``."""

    config_yaml = ""
    rmapd: Rmapd

    @classmethod
    def setUpClass(cls) -> None:
        cls.rmapd = Rmapd(cls.config_yaml)

    @classmethod
    def tearDownClass(cls) -> None:
        cls.rmapd.stop()
