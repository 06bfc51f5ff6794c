"""Checks docker/ without a Docker engine: the Dockerfile's syntax and stages, that every
path it copies is in the build context (.dockerignore applied), that its apt packages exist
and that the runtime stage's cover every library the built binaries load, that compose.yaml
wires rmapd and the simulated robots together, and that the entrypoint and the health check
work with the real rmapd.

Environment (ctest sets it): RMAP_SOURCE_DIR, RMAP_BINARIES (the built binaries,
colon-separated, rmapd first) and RMAP_SANITIZED=1 when they are a sanitizer build (whose
runtime libraries the image's Release build does not load).
"""

from __future__ import annotations

import fnmatch
import json
import os
import re
import shlex
import shutil
import signal
import subprocess
import tempfile
import unittest
import urllib.error
import urllib.request
from dataclasses import dataclass, field
from pathlib import Path

import yaml

SOURCE = Path(os.environ.get("RMAP_SOURCE_DIR", Path(__file__).resolve().parents[2]))
DOCKER = SOURCE / "docker"
BINARIES = [Path(p) for p in os.environ.get("RMAP_BINARIES", "").split(":") if p]
SANITIZER_RUNTIMES = re.compile(r"lib(asan|ubsan)\.so") if os.environ.get("RMAP_SANITIZED") == "1" else None

INSTRUCTIONS = {
    "ADD", "ARG", "CMD", "COPY", "ENTRYPOINT", "ENV", "EXPOSE", "FROM", "HEALTHCHECK", "LABEL",
    "MAINTAINER", "ONBUILD", "RUN", "SHELL", "STOPSIGNAL", "USER", "VOLUME", "WORKDIR",
}
# scripts/setup.sh packages that the image's build (no tests, no benchmarks) does not need.
TEST_ONLY_PACKAGES = {
    "libgtest-dev", "libgmock-dev", "libbenchmark-dev", "liboctomap-dev", "chromium", "jq",
    "python3-protobuf", "python3-websockets", "python3-yaml",
    "openssl",  # the command line makes the TLS tests' certificates
    "clang", "libclang-rt-14-dev",  # libFuzzer (tests/fuzz)
}
JSON_FORM = {"CMD", "ENTRYPOINT", "SHELL"}  # instructions whose argument, when it starts with [, is a JSON array


@dataclass
class Instruction:
    line: int
    keyword: str
    args: str


@dataclass
class Stage:
    name: str
    image: str
    instructions: list[Instruction] = field(default_factory=list)


def parse_dockerfile(text: str) -> list[Instruction]:
    """Instructions with their first line number; continuation lines joined, comments dropped."""
    out: list[Instruction] = []
    pending, start = "", 0
    for number, raw in enumerate(text.splitlines(), 1):
        stripped = raw.strip()
        if not pending and (not stripped or stripped.startswith("#")):
            continue
        if pending and stripped.startswith("#"):
            continue  # comment lines inside a continued instruction are dropped
        if not pending:
            start = number
        if stripped.endswith("\\"):
            pending += stripped[:-1] + " "
            continue
        whole = pending + stripped
        pending = ""
        keyword, _, args = whole.partition(" ")
        out.append(Instruction(start, keyword.upper(), args.strip()))
    if pending:
        raise ValueError(f"line {start}: the last instruction ends with a line continuation")
    return out


def stages_of(instructions: list[Instruction]) -> list[Stage]:
    stages: list[Stage] = []
    for ins in instructions:
        if ins.keyword == "FROM":
            words = ins.args.split()
            name = words[2] if len(words) == 3 and words[1].upper() == "AS" else str(len(stages))
            if len(words) not in (1, 3):
                raise ValueError(f"line {ins.line}: FROM IMAGE [AS NAME], not {ins.args!r}")
            stages.append(Stage(name, words[0]))
        elif not stages:
            if ins.keyword != "ARG":
                raise ValueError(f"line {ins.line}: {ins.keyword} before the first FROM")
        else:
            stages[-1].instructions.append(ins)
    return stages


def copy_sources(ins: Instruction) -> tuple[dict[str, str], list[str], str]:
    """Flags, sources and destination of a COPY or ADD."""
    if ins.args.startswith("["):
        words = json.loads(ins.args)
        flags: dict[str, str] = {}
    else:
        words = shlex.split(ins.args)
        flags = {}
        while words and words[0].startswith("--"):
            key, _, value = words.pop(0)[2:].partition("=")
            flags[key] = value
    if len(words) < 2:
        raise ValueError(f"line {ins.line}: {ins.keyword} needs a source and a destination")
    return flags, words[:-1], words[-1]


def apt_packages(stage: Stage) -> list[str]:
    """Package names of every `apt-get install` in a stage's RUN instructions."""
    names: list[str] = []
    for ins in stage.instructions:
        if ins.keyword != "RUN":
            continue
        for command in re.split(r"&&|;|\|\|", ins.args):
            words = command.split()
            if "apt-get" in words and "install" in words:
                rest = words[words.index("install") + 1:]
                names += [w for w in rest if not w.startswith("-")]
    return names


def dockerignore_excludes(patterns: list[str], path: str) -> bool:
    """Whether the build context leaves out `path` (Docker's rules: the last matching pattern
    wins, `!` re-includes, a pattern matching a parent directory matches what it holds)."""
    parts = path.split("/")
    prefixes = ["/".join(parts[: i + 1]) for i in range(len(parts))]
    excluded = False
    for pattern in patterns:
        negate = pattern.startswith("!")
        p = pattern[1:] if negate else pattern
        p = p.strip("/")
        regex = fnmatch.translate(p).replace(".*", "[^/]*").replace("[^/]*[^/]*", ".*")
        if any(re.fullmatch(regex, prefix) for prefix in prefixes):
            excluded = not negate
    return excluded


def read_dockerignore() -> list[str]:
    lines = (SOURCE / ".dockerignore").read_text().splitlines()
    return [line.strip() for line in lines if line.strip() and not line.strip().startswith("#")]


def setup_packages() -> set[str]:
    """The package list of scripts/setup.sh (its `packages=( ... )` array)."""
    text = (SOURCE / "scripts/setup.sh").read_text()
    body = re.search(r"^packages=\((.*?)^\)", text, re.S | re.M)
    assert body, "scripts/setup.sh has no packages=( ... ) list"
    words: set[str] = set()
    for line in body.group(1).splitlines():
        words.update(line.split("#")[0].split())
    extra = re.findall(r"packages\+=\(([^)]*)\)", text)
    for group in extra:
        words.update(group.split())
    return words


def owned_paths(library: str) -> list[str]:
    """The names dpkg may know a library file by: through its symlinks, with and without the
    /usr prefix (Debian 12 merges /lib into /usr/lib, packages still list either)."""
    names = {library, os.path.realpath(library)}
    for name in list(names):
        names.add(name[len("/usr"):] if name.startswith("/usr/") else "/usr" + name)
    return sorted(names)


class DockerfileTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls) -> None:
        cls.instructions = parse_dockerfile((DOCKER / "Dockerfile").read_text())
        cls.stages = stages_of(cls.instructions)
        cls.build, cls.runtime = cls.stages[0], cls.stages[-1]

    def test_instructions_and_stages_are_well_formed(self) -> None:
        for ins in self.instructions:
            self.assertIn(ins.keyword, INSTRUCTIONS, f"line {ins.line}")
            self.assertTrue(ins.args, f"line {ins.line}: {ins.keyword} without arguments")
            if ins.keyword in JSON_FORM and ins.args.startswith("["):
                words = json.loads(ins.args)
                self.assertTrue(words and all(isinstance(w, str) for w in words), f"line {ins.line}")
        self.assertEqual([s.name for s in self.stages], ["build", "runtime"])
        self.assertTrue(all(s.image == "debian:12" for s in self.stages))

    def test_every_copied_path_is_in_the_build_context(self) -> None:
        ignore = read_dockerignore()
        names = set()
        for stage in self.stages:
            for ins in stage.instructions:
                if ins.keyword not in ("COPY", "ADD"):
                    continue
                flags, sources, _ = copy_sources(ins)
                if "from" in flags:
                    self.assertIn(flags["from"], names, f"line {ins.line}: --from names no earlier stage")
                    continue
                for source in sources:
                    self.assertTrue((SOURCE / source).exists(), f"line {ins.line}: {source} does not exist")
                    self.assertFalse(dockerignore_excludes(ignore, source.rstrip("/")),
                                     f"line {ins.line}: .dockerignore leaves {source} out of the context")
                    for file in (SOURCE / source).rglob("*") if (SOURCE / source).is_dir() else []:
                        relative = file.relative_to(SOURCE).as_posix()
                        if file.is_file() and "__pycache__" not in relative:
                            self.assertFalse(dockerignore_excludes(ignore, relative), relative)
            names.add(stage.name)
        # And what the context leaves out stays out.
        for left_out in ("build/bin/rmapd", "web/node_modules/three/package.json", "tests/unit/CMakeLists.txt", ".git/HEAD"):
            self.assertTrue(dockerignore_excludes(ignore, left_out), left_out)

    def test_the_build_stage_configures_from_the_files_it_copies(self) -> None:
        """Lays out the build stage's WORKDIR from its COPYs (.dockerignore applied) and runs its
        CMake configure step there: the context holds everything the build reads."""
        ignore = read_dockerignore()
        with tempfile.TemporaryDirectory(prefix="rmap-docker-context-") as work:
            root = Path(work) / "src"
            root.mkdir()
            for ins in self.build.instructions:
                if ins.keyword != "COPY":
                    continue
                _, sources, destination = copy_sources(ins)
                target = root / destination
                for source in sources:
                    origin = SOURCE / source
                    files = [origin] if origin.is_file() else [f for f in origin.rglob("*") if f.is_file()]
                    for file in files:
                        relative = file.relative_to(SOURCE).as_posix()
                        if dockerignore_excludes(ignore, relative):
                            continue
                        if origin.is_file():
                            into = target / file.name if destination.endswith("/") else target
                        else:
                            into = target / file.relative_to(origin)
                        into.parent.mkdir(parents=True, exist_ok=True)
                        shutil.copy2(file, into)
            configure = next(part for ins in self.build.instructions if ins.keyword == "RUN"
                             for part in ins.args.split("&&") if part.split()[:2] == ["cmake", "-S"])
            result = subprocess.run(shlex.split(configure), cwd=root, capture_output=True, text=True, timeout=60)
            self.assertEqual(result.returncode, 0, result.stdout[-2000:] + result.stderr[-4000:])

    def test_scripts_it_copies_are_executable(self) -> None:
        for script in ("entrypoint.sh", "healthcheck.sh"):
            self.assertTrue(os.access(DOCKER / script, os.X_OK), script)

    def test_the_runtime_stage_runs_rmapd_as_a_user_with_a_volume_and_a_health_check(self) -> None:
        by_keyword: dict[str, list[str]] = {}
        for ins in self.runtime.instructions:
            by_keyword.setdefault(ins.keyword, []).append(ins.args)
        self.assertEqual(by_keyword["USER"], ["rmap"])
        config = yaml.safe_load((DOCKER / "rmapd.yaml").read_text())
        self.assertEqual(json.loads(by_keyword["VOLUME"][0]), [config["data_dir"]])
        self.assertEqual(by_keyword["EXPOSE"], [config["listen"].rsplit(":", 1)[1]])
        self.assertTrue(config["listen"].startswith("0.0.0.0:"))
        self.assertIn("CMD", by_keyword["HEALTHCHECK"][0])
        self.assertIn("/usr/local/bin/rmapd-entrypoint", by_keyword["ENTRYPOINT"][0])
        self.assertIn("--omit=dev", " ".join(i.args for i in self.build.instructions if i.keyword == "RUN"))

    def test_build_packages_are_those_of_setup_sh(self) -> None:
        """The build stage installs what scripts/setup.sh does, but for what only tests and
        benchmarks use: a build dependency added to one and not the other fails here."""
        build = set(apt_packages(self.build))
        self.assertEqual(sorted(build - setup_packages() - {"ca-certificates", "nodejs", "npm"}), [],
                         "build-stage packages that scripts/setup.sh does not install")
        self.assertEqual(sorted(setup_packages() - build - TEST_ONLY_PACKAGES), [],
                         "scripts/setup.sh packages missing from the build stage (or add them to TEST_ONLY_PACKAGES)")

    def test_apt_packages_exist(self) -> None:
        if not any(Path("/var/lib/apt/lists").glob("*_Packages*")):
            self.skipTest("no apt package lists on this machine (apt-get update fills them)")
        for stage in self.stages:
            names = apt_packages(stage)
            self.assertTrue(names, f"stage {stage.name} installs no packages")
            result = subprocess.run(["apt-cache", "show", "--no-all-versions", *names], capture_output=True, text=True)
            self.assertEqual(result.returncode, 0, f"stage {stage.name}: {result.stderr.strip()}")

    def test_runtime_packages_hold_every_library_the_binaries_load(self) -> None:
        if not BINARIES:
            self.skipTest("RMAP_BINARIES not set (ctest sets it to the built binaries)")
        listed = set(apt_packages(self.runtime))
        for binary in BINARIES:
            needed = re.findall(r"\(NEEDED\)\s+Shared library: \[(.+?)\]", subprocess.run(
                ["readelf", "-d", str(binary)], capture_output=True, text=True, check=True).stdout)
            ldd = subprocess.run(["ldd", str(binary)], capture_output=True, text=True, check=True).stdout
            resolved = dict(re.findall(r"^\s*(\S+) => (/\S+)", ldd, re.M))
            resolved.update((Path(p).name, p) for p in re.findall(r"^\s*(/\S+) \(0x", ldd, re.M))  # the loader
            for library in needed:
                if SANITIZER_RUNTIMES and SANITIZER_RUNTIMES.match(library):
                    continue
                self.assertIn(library, resolved, f"{binary.name}: ldd does not find {library}")
                owners = subprocess.run(["dpkg", "-S", *owned_paths(resolved[library])], capture_output=True, text=True)
                packages = {line.split(":")[0] for line in owners.stdout.splitlines()}
                self.assertTrue(packages & listed, f"{binary.name} loads {library} of {sorted(packages)}: "
                                                   "add its package to the runtime stage of docker/Dockerfile")


class ComposeTest(unittest.TestCase):
    def test_rmapd_and_the_simulated_robots_are_wired_together(self) -> None:
        compose = yaml.safe_load((DOCKER / "compose.yaml").read_text())
        services = compose["services"]
        self.assertEqual(set(services), {"rmapd", "sim"})
        rmapd, sim = services["rmapd"], services["sim"]
        for service in (rmapd, sim):
            context = (DOCKER / service["build"]["context"]).resolve()
            self.assertEqual(context, SOURCE.resolve())
            self.assertTrue((context / service["build"]["dockerfile"]).is_file())
            self.assertEqual(service["image"], rmapd["image"])
        for key in ("RMAP_ADMIN_TOKEN", "RMAP_VIEWER_TOKEN"):
            self.assertRegex(rmapd["environment"][key], r"^\$\{" + key + r":\?")  # must be given
        volume, target = rmapd["volumes"][0].split(":")
        self.assertIn(volume, compose["volumes"])
        self.assertEqual(target, "/var/lib/rmap")
        self.assertTrue(rmapd["ports"][0].endswith(":8080"))

        self.assertEqual(sim["entrypoint"], ["rmap-sim"])
        command = sim["command"]
        self.assertEqual(command[command.index("--server") + 1], "ws://rmapd:8080")
        self.assertEqual(command[command.index("--token") + 1], "${RMAP_ADMIN_TOKEN}")
        self.assertEqual(sim["depends_on"]["rmapd"]["condition"], "service_healthy")


class EntrypointTest(unittest.TestCase):
    """docker/entrypoint.sh and docker/healthcheck.sh with the real rmapd on loopback."""

    def setUp(self) -> None:
        if not BINARIES:
            self.skipTest("RMAP_BINARIES not set (ctest sets it to the built binaries)")
        self.dir = tempfile.TemporaryDirectory(prefix="rmap-docker-")
        base = Path(self.dir.name)
        (base / "rmapd.yaml").write_text(f"listen: 127.0.0.1:0\ndata_dir: {base / 'data'}\n")
        self.env = dict(os.environ, PATH=f"{BINARIES[0].parent}:{os.environ['PATH']}", RMAP_CONFIG=str(base / "rmapd.yaml"),
                        TMPDIR=str(base))

    def tearDown(self) -> None:
        self.dir.cleanup()

    def start(self, **tokens: str) -> tuple[subprocess.Popen, int]:
        process = subprocess.Popen(["sh", str(DOCKER / "entrypoint.sh")], env={**self.env, **tokens},
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        line = process.stdout.readline()
        match = re.search(r"listening on http://127\.0\.0\.1:(\d+)/", line)
        if not match:
            process.kill()
            self.fail(f"rmapd did not start: {line!r} {process.stderr.read()}")
        return process, int(match.group(1))

    @staticmethod
    def status(port: int, path: str, token: str | None = None) -> int:
        request = urllib.request.Request(f"http://127.0.0.1:{port}{path}")
        if token:
            request.add_header("Authorization", f"Bearer {token}")
        try:
            with urllib.request.urlopen(request, timeout=5) as response:
                return response.status
        except urllib.error.HTTPError as error:
            return error.code

    def stop(self, process: subprocess.Popen) -> str:
        """Stops rmapd cleanly; returns what the entrypoint and rmapd wrote to stderr."""
        process.send_signal(signal.SIGTERM)
        _, stderr = process.communicate(timeout=30)
        self.assertEqual(process.returncode, 0)
        return stderr

    def test_tokens_from_the_environment_and_the_health_check(self) -> None:
        process, port = self.start(RMAP_ADMIN_TOKEN="admin-it's-secret", RMAP_VIEWER_TOKEN="viewer-secret-1",
                                   RMAP_ROBOT_TOKENS="bot-1=robot-secret-01,bot-2=robot-secret-02")
        try:
            self.assertEqual(self.status(port, "/metrics"), 401)
            self.assertEqual(self.status(port, "/metrics", "admin-it's-secret"), 200)
            self.assertEqual(self.status(port, "/v1/maps", "viewer-secret-1"), 200)
            self.assertEqual(self.status(port, "/metrics", "viewer-secret-1"), 403)
            self.assertEqual(self.status(port, "/v1/robots", "robot-secret-02"), 200)
            health = subprocess.run(["bash", str(DOCKER / "healthcheck.sh")], env={**self.env, "RMAP_PORT": str(port)})
            self.assertEqual(health.returncode, 0)
            # The generated config (it holds the tokens) is written under TMPDIR, 0600.
            generated = list(Path(self.dir.name).glob("rmapd-*.yaml"))
            self.assertEqual(len(generated), 1)
            self.assertEqual(generated[0].stat().st_mode & 0o777, 0o600)
            self.assertIn("robot-secret-02", generated[0].read_text())
        finally:
            self.stop(process)
        down = subprocess.run(["bash", str(DOCKER / "healthcheck.sh")], env={**self.env, "RMAP_PORT": str(port)},
                              capture_output=True)
        self.assertNotEqual(down.returncode, 0)

    def test_without_tokens_it_warns_and_serves_loopback(self) -> None:
        process, port = self.start()
        try:
            self.assertEqual(self.status(port, "/v1/maps"), 200)  # loopback-only mode: loopback is admin
        finally:
            stderr = self.stop(process)
        self.assertIn("rmapd-entrypoint: no tokens", stderr)

    def test_bad_robot_tokens_are_refused(self) -> None:
        result = subprocess.run(["sh", str(DOCKER / "entrypoint.sh")], env={**self.env, "RMAP_ROBOT_TOKENS": "bot-1"},
                                capture_output=True, text=True, timeout=30)
        self.assertEqual(result.returncode, 2)
        self.assertIn("robot_id=token pairs", result.stderr)
        self.assertNotIn("listening", result.stdout)  # rmapd never started


if __name__ == "__main__":
    unittest.main()
