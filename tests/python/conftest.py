"""Shared fixtures of the Python module's tests: the built tools, and small generated frames.

The test command (ctest) sets PYTHONPATH to the built module and RANGE_NLM_TOOLS_DIR to the
built tools.
"""

import os
import signal
import subprocess
import threading
import time

import numpy as np
import pytest

import range_nlm

TOOLS_DIR = os.environ.get("RANGE_NLM_TOOLS_DIR", "")
SOURCE_DIR = os.environ.get("RANGE_NLM_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))

# Small windows, so that the command-line runs and the filter take milliseconds on 64 x 48 frames.
SMALL = {"search_window": 5, "patch_size": 3, "normal_window": 5, "threads": 1}
SMALL_CLI = ["--search-window", "5", "--patch", "3", "--normal-window", "5", "--threads", "1", "--quiet"]


def tool(name):
    path = os.path.join(TOOLS_DIR, name)
    if not os.path.exists(path):
        pytest.skip("%s is not built (set RANGE_NLM_TOOLS_DIR)" % name)
    return path


def run_tool(name, *args):
    """Runs a built tool; fails the test with its stderr if it fails."""
    done = subprocess.run([tool(name), *map(str, args)], capture_output=True, text=True)
    assert done.returncode == 0, "%s %s failed: %s" % (name, " ".join(map(str, args)), done.stderr)
    return done.stdout


@pytest.fixture(scope="session")
def scene(tmp_path_factory):
    """Three 64 x 48 frames of the generated boxes scene with Kinect noise, as range_nlm_synth
    writes them (noisy/ and truth/)."""
    out = tmp_path_factory.mktemp("scene")
    run_tool("range_nlm_synth", "--output-dir", out, "--frames", 3, "--width", 64, "--height", 48, "--fx", 60,
             "--fy", 60, "--noise", "kinect", "--dropout", 0.05, "--quiet")
    return out


@pytest.fixture(scope="session")
def frames(scene):
    names = sorted(os.listdir(scene / "noisy"))
    return [range_nlm.read_pcd(str(scene / "noisy" / name)) for name in names]


def bits(a):
    """The array's bytes as integers: equality of these is bit-identity, NaN included."""
    a = np.ascontiguousarray(a)
    return a.view({2: np.uint16, 4: np.uint32, 8: np.uint64}[a.dtype.itemsize])


def plane(width=64, height=48, depth=1.5, noise=0.003, seed=3, dtype=np.float32):
    """A noisy fronto-parallel plane seen by a pinhole camera (f = 60 px), H x W x 3."""
    rng = np.random.default_rng(seed)
    v, u = np.mgrid[0:height, 0:width].astype(np.float64)
    z = depth + noise * rng.standard_normal((height, width))
    points = np.stack([(u - width / 2) * z / 60.0, (v - height / 2) * z / 60.0, z], axis=-1)
    return np.ascontiguousarray(points, dtype=dtype)


def seconds_to_interrupt(call, after):
    """Runs call() with SIGINT sent to this process `after` seconds in (Python's handler raising
    KeyboardInterrupt installed meanwhile, as in an interactive session); returns the seconds
    until KeyboardInterrupt came out of the call, or None if it returned first. A signal that
    arrives only after the call is caught here too, so that it cannot end the test session."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(after, os.kill, (os.getpid(), signal.SIGINT))
    elapsed = None
    try:
        start = time.perf_counter()
        timer.start()
        try:
            call()
        except KeyboardInterrupt:
            elapsed = time.perf_counter() - start
        try:
            timer.join()
            time.sleep(0.05)  # a signal sent at the end is handled here
        except KeyboardInterrupt:
            pass
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    return elapsed
