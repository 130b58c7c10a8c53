"""Stream: the temporal filter frame by frame, bit-identical to range_nlm_denoise --input-dir."""

import os
import time

import numpy as np
import pytest

import range_nlm
from conftest import SMALL, SMALL_CLI, bits, plane, run_tool, seconds_to_interrupt


def _cli_run(scene, tmp_path, *options):
    out = tmp_path / "out"
    run_tool("range_nlm_denoise", "--input-dir", scene / "noisy", "--output-dir", out, *SMALL_CLI, *options)
    return [range_nlm.read_pcd(str(out / name)) for name in sorted(os.listdir(out))]


@pytest.mark.parametrize("mode, options", [("centred", []), ("causal", ["--causal"]), ("recursive", ["--recursive"])])
def test_stream_is_bit_identical_to_the_cli_directory_run(scene, frames, tmp_path, mode, options):
    expected = _cli_run(scene, tmp_path, "--temporal-radius", "1", *options)
    stream = range_nlm.Stream(radius=1, mode=mode, **SMALL)
    results = []
    for frame in frames:
        results += stream.push(frame)
    results += stream.finish()
    assert len(results) == len(frames) == len(expected)
    for got, want, raw in zip(results, expected, frames):
        assert np.array_equal(bits(got), bits(want))
        assert not np.array_equal(bits(got), bits(raw))


def test_centred_window_lags_by_the_radius_and_finish_gives_the_tail(frames):
    stream = range_nlm.Stream(radius=1, **SMALL)
    assert stream.push(frames[0]) == []
    assert len(stream.push(frames[1])) == 1
    assert len(stream.push(frames[2])) == 1
    assert stream.info[0]["filtered"] and stream.info[0]["distance_bandwidth"] > 0
    assert len(stream.finish()) == 1


def test_stream_of_radius_zero_equals_denoise_of_each_frame(frames):
    stream = range_nlm.Stream(radius=0, **SMALL)
    for frame, out in zip(frames, stream.filter(frames)):
        assert np.array_equal(bits(out), bits(range_nlm.denoise(frame, **SMALL)))


def test_generator_equals_push_and_finish(frames):
    pushed = range_nlm.Stream(radius=1, mode="causal", **SMALL)
    by_push = [out for frame in frames for out in pushed.push(frame)] + pushed.finish()
    by_filter = list(range_nlm.Stream(radius=1, mode="causal", **SMALL).filter(frames))
    assert all(np.array_equal(bits(a), bits(b)) for a, b in zip(by_push, by_filter))
    assert len(by_push) == len(by_filter) == len(frames)


def test_depth_frames_come_out_as_depth_images(scene, frames, tmp_path):
    # The CLI on a directory of depth PNGs, and the stream on the same images.
    (tmp_path / "png").mkdir()
    depths = []
    for k, frame in enumerate(frames):
        depth = np.nan_to_num(np.round(frame[:, :, 2] * 5000.0), nan=0.0).astype(np.uint16)
        range_nlm.write_depth_png(str(tmp_path / "png" / ("f%d.png" % k)), depth)
        depths.append(depth)
    out = tmp_path / "out"
    run_tool("range_nlm_denoise", "--input-dir", tmp_path / "png", "--output-dir", out, "--fx", 60, "--fy", 60,
             "--cx", 31.5, "--cy", 23.5, "--temporal-radius", 1, *SMALL_CLI)
    intrinsics = {"fx": 60, "fy": 60, "cx": 31.5, "cy": 23.5, "depth_scale": 5000}
    results = list(range_nlm.Stream(1, intrinsics=intrinsics, **SMALL).filter(depths))
    for k, result in enumerate(results):
        assert result.dtype == np.uint16
        assert np.array_equal(result, range_nlm.read_depth_png(str(out / ("f%d.png" % k))))


def test_a_refused_frame_leaves_the_stream_as_it_was(frames):
    stream = range_nlm.Stream(radius=1, mode="causal", **SMALL)
    stream.push(frames[0])
    with pytest.raises(ValueError, match="is 32 x 48 but the sequence is 64 x 48"):
        stream.push(np.ascontiguousarray(frames[1][:, :32]))
    clean = range_nlm.Stream(radius=1, mode="causal", **SMALL)
    clean.push(frames[0])
    assert np.array_equal(bits(stream.push(frames[1])[0]), bits(clean.push(frames[1])[0]))


def test_stream_arguments_are_checked():
    with pytest.raises(ValueError, match="mode must be 'centred', 'causal' or 'recursive'"):
        range_nlm.Stream(1, mode="sideways")
    with pytest.raises(ValueError, match="radius must be >= 0"):
        range_nlm.Stream(-1)
    with pytest.raises(TypeError, match="unexpected keyword argument 'windw'"):
        range_nlm.Stream(1, windw=3)


def test_ctrl_c_stops_a_push_soon_and_the_stream_goes_on():
    # An interrupted push keeps its frame: its result comes with the next push (or finish()),
    # the same as without the interruption.
    frames = [plane(width=900, height=675, seed=k) for k in range(2)]
    reference = range_nlm.Stream(0)
    start = time.perf_counter()
    expected = reference.push(frames[0])
    whole = time.perf_counter() - start
    expected += reference.push(frames[1])
    stream = range_nlm.Stream(0)
    stopped = seconds_to_interrupt(lambda: stream.push(frames[0]), 0.2 * whole)
    assert stopped is not None, "the push of %.2f s ended before the signal" % whole
    assert stopped < 0.6 * whole, "KeyboardInterrupt after %.2f s of a %.2f s push" % (stopped, whole)
    out = stream.push(frames[1])
    assert len(out) == 2 and len(stream.info) == 2
    for a, b in zip(out, expected):
        assert np.array_equal(bits(a), bits(b))
    assert stream.finish() == []


def test_ctrl_c_stops_a_finish_which_can_be_called_again():
    frames = [plane(width=900, height=675, seed=k) for k in range(2)]
    reference = range_nlm.Stream(1)
    expected = reference.push(frames[0]) + reference.push(frames[1])
    start = time.perf_counter()
    expected += reference.finish()
    whole = time.perf_counter() - start
    stream = range_nlm.Stream(1)
    assert len(stream.push(frames[0]) + stream.push(frames[1])) == 1
    stopped = seconds_to_interrupt(stream.finish, 0.2 * whole)
    assert stopped is not None and stopped < 0.6 * whole
    out = stream.finish()
    assert len(out) == 1 and np.array_equal(bits(out[0]), bits(expected[1]))


def test_a_live_stream_is_recursive_and_bit_identical_to_the_cli(scene, frames, tmp_path):
    expected = _cli_run(scene, tmp_path, "--preset", "live", "--temporal-radius", "1", "--recursive")
    stream = range_nlm.Stream(radius=1, parameters="live", **SMALL)
    assert stream.mode == "recursive"
    results = list(stream.filter(frames))
    assert len(results) == len(frames) == len(expected)
    for got, want in zip(results, expected):
        assert np.array_equal(bits(got), bits(want))
    # The same frames with the default preset give other bytes: the preset reached the filter.
    default = list(range_nlm.Stream(radius=1, mode="recursive", **SMALL).filter(frames))
    assert not all(np.array_equal(bits(a), bits(b)) for a, b in zip(results, default))
    assert range_nlm.Stream(radius=1, **SMALL).mode == "centred"
