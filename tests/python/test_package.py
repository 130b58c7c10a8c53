"""The package itself: __version__, the warning about default intrinsics, reprs, a clean dir()."""

import os
import re
import subprocess
import warnings

import numpy as np
import pytest

import range_nlm
from conftest import SMALL, SOURCE_DIR, plane, tool


def _project_version():
    with open(os.path.join(SOURCE_DIR, "CMakeLists.txt")) as f:
        return re.search(r"project\(range_nlm VERSION ([0-9.]+)", f.read()).group(1)


def test_version_is_the_projects():
    assert range_nlm.__version__ == _project_version()
    assert range_nlm._range_nlm.__version__ == _project_version()


@pytest.fixture
def fresh_warning(monkeypatch):
    """As in a new process: the warning about default intrinsics not given yet."""
    monkeypatch.setattr(range_nlm, "_default_intrinsics_warned", False, raising=False)


def _depth():
    points = plane(64, 48)
    return np.nan_to_num(np.round(points[:, :, 2] * 5000.0), nan=0.0).astype(np.uint16)


def _cli_warning(tmp_path, depth):
    range_nlm.write_depth_png(str(tmp_path / "in.png"), depth)
    done = subprocess.run([tool("range_nlm_denoise"), str(tmp_path / "in.png"), str(tmp_path / "out.png"), "--quiet",
                           "--search-window", "5", "--patch", "3", "--threads", "1"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return done.stderr


def test_denoise_depth_without_intrinsics_warns_once_with_the_clis_words(fresh_warning, tmp_path):
    depth = _depth()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        range_nlm.denoise_depth(depth, **SMALL)
        range_nlm.denoise_depth(depth, **SMALL)
        range_nlm.depth_to_points(depth)
    warned = [w for w in caught if issubclass(w.category, UserWarning)]
    assert len(warned) == 1, [str(w.message) for w in caught]
    message = str(warned[0].message)
    assert warned[0].filename == __file__  # points at the caller's line
    assert "denoise_depth" in message
    # The command line's wording, from "default intrinsics (" to "camera)", and its advice.
    cli = _cli_warning(tmp_path, depth)
    shared = re.search(r"default intrinsics \(.*?camera\)", cli)
    assert shared, cli
    assert shared.group(0) == "default intrinsics (fx 525, fy 525, cx 319.5, cy 239.5, depth-scale 5000: a 640 x 480 " \
                              "Kinect v1 / TUM RGB-D camera)"
    assert shared.group(0) in message
    assert message.endswith("for your camera, or the depths and positions are wrong")


def test_no_warning_with_intrinsics(fresh_warning):
    depth = _depth()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        range_nlm.denoise_depth(depth, range_nlm.Intrinsics(), **SMALL)
        range_nlm.denoise_depth(depth, {"fx": 60, "fy": 60, "cx": 31.5, "cy": 23.5}, **SMALL)
        range_nlm.depth_to_points(depth, range_nlm.Intrinsics())
    assert not range_nlm._default_intrinsics_warned


def test_stream_repr_shows_radius_mode_and_held_frames():
    stream = range_nlm.Stream(1, "causal", **SMALL)
    assert repr(stream) == "range_nlm.Stream(radius=1, mode='causal', held_frames=0)"
    stream.push(plane(64, 48))
    assert repr(stream) == "range_nlm.Stream(radius=1, mode='causal', held_frames=%d)" % stream.held_frames
    assert stream.held_frames == 1
    assert repr(range_nlm.Stream(2, **SMALL)) == "range_nlm.Stream(radius=2, mode='centred', held_frames=0)"


def test_dir_lists_the_api_and_nothing_else():
    public = {name for name in dir(range_nlm) if not name.startswith("_")}
    # No helper module or imported name leaks (operator, os, warnings, numpy, interop, ...).
    assert public == set(range_nlm.__all__)
    for name in range_nlm.__all__:
        assert getattr(range_nlm, name).__module__.startswith("range_nlm"), name


def test_reprs_say_what_the_objects_hold():
    assert repr(range_nlm.Intrinsics(fx=500, fy=501, cx=320, cy=240, width=640, height=480)) == (
        "range_nlm.Intrinsics(fx=500.0, fy=501.0, cx=320.0, cy=240.0, depth_scale=5000.0, width=640, height=480)")
    p = range_nlm.Parameters(search_window=7)
    assert repr(p).startswith("range_nlm.Parameters(") and "search_window=7" in repr(p)


def test_a_depth_list_without_intrinsics_warns_too(fresh_warning):
    depth = (_depth() / 5000.0).tolist()  # metres, as floats
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        range_nlm.denoise_depth(depth, **SMALL)
        range_nlm.denoise_depth(depth, **SMALL)
    warned = [w for w in caught if issubclass(w.category, UserWarning)]
    assert len(warned) == 1 and "default intrinsics" in str(warned[0].message)
    # Depth scale 1 for floats: the CLI's "depth-scale 5000" applies to 16-bit images only.
    assert "depth-scale" not in str(warned[0].message)
