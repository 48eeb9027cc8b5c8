"""Shared fixtures: the office files, the workspace binaries, unique live scenes."""
import itertools
import os
import pathlib
import subprocess
import time

import pytest

import yggdrasil

REPO = pathlib.Path(__file__).resolve().parents[2]
LAYOUTS = ("vanilla", "chocolate", "mint", "saffron")
# Test scenes are named and prefixed like ygg-testkit's (`ygt<pid>x<n>_`), so that
# .ci/run's /dev/shm check knows them.
PREFIX_TAG = "ygt"
_counter = itertools.count(1000)


def binary(name):
    """A workspace binary: $YGG_BIN_DIR/name, else target/{debug,release}/name."""
    dirs = [os.environ.get("YGG_BIN_DIR")] if os.environ.get("YGG_BIN_DIR") else []
    dirs += [REPO / "target" / "debug", REPO / "target" / "release"]
    for d in dirs:
        p = pathlib.Path(d) / name
        if p.exists():
            return str(p)
    pytest.fail(f"{name} is not built (cargo build -p ygg-cli)")


@pytest.fixture(scope="session")
def office_dir(tmp_path_factory):
    """The built-in office (seed 7, full size): Spark-DSG JSON and a .ygg per layout."""
    d = tmp_path_factory.mktemp("office")
    yggdrasil.write_office(d / "office.json")
    for layout in LAYOUTS:
        yggdrasil.office_graph(layout).save(d / f"{layout}.ygg")
    return d


@pytest.fixture(scope="session")
def small_office(tmp_path_factory):
    """A small office (scale 0.05) as Spark-DSG JSON and binary."""
    d = tmp_path_factory.mktemp("small")
    yggdrasil.write_office(d / "office.json", scale=0.05)
    yggdrasil.write_office(d / "office.sparkdsg", scale=0.05)
    return d


def _files_of(prefix):
    found = []
    # iceoryx2's node and service files are below /dev/shm too (/dev/shm/iceoryx2).
    for root, _, files in os.walk("/dev/shm"):
        found += [os.path.join(root, f) for f in files if f.startswith(prefix)]
    return found


@pytest.fixture
def scene_name(monkeypatch):
    """A unique scene name with its own iceoryx2 prefix (set in this process's and every
    child's environment); fails the test if the scene leaves shared memory behind."""
    n = next(_counter)
    pid = os.getpid()
    prefix = f"{PREFIX_TAG}{pid}x{n}_"
    monkeypatch.setenv("YGG_IOX2_PREFIX", prefix)
    monkeypatch.delenv("IOX2_LOG_LEVEL", raising=False)
    yield f"py-{pid}-{n}"
    import gc

    gc.collect()
    deadline = time.monotonic() + 5
    left = [f for f in _files_of(prefix) if not f.endswith(".global_mgmt")]
    # A bounded poll: no event says that another process removed its files.
    while left and time.monotonic() < deadline:
        time.sleep(0.05)
        gc.collect()
        left = [f for f in _files_of(prefix) if not f.endswith(".global_mgmt")]
    for f in _files_of(prefix):
        if f.endswith(".global_mgmt"):
            os.remove(f)
    assert not left, f"shared memory left behind: {left}"


class Proc:
    """A child process killed at the end of the test (a watchdog for hung children)."""

    def __init__(self, args, **kw):
        self.p = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)

    def wait(self, timeout):
        out, err = self.p.communicate(timeout=timeout)
        return self.p.returncode, out, err

    def stop(self, timeout=10):
        if self.p.poll() is None:
            self.p.send_signal(2)  # SIGINT: a clean exit that removes shared memory
            try:
                self.p.wait(timeout)
            except subprocess.TimeoutExpired:
                self.p.kill()
                self.p.wait()


@pytest.fixture
def procs():
    """Starts children with ``procs(args)``; every one is stopped after the test."""
    started = []

    def start(args, **kw):
        p = Proc(args, **kw)
        started.append(p)
        return p

    yield start
    for p in started:
        p.stop()
