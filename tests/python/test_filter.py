"""denoise() and denoise_depth(): output bit-identical to range_nlm_denoise, NaN handling, the
GIL released while filtering, no memory growth over many calls."""

import threading
import time

import numpy as np
import pytest

import range_nlm
from conftest import SMALL, SMALL_CLI, bits, plane, run_tool, seconds_to_interrupt


def test_denoise_is_bit_identical_to_the_cli(scene, tmp_path):
    source = scene / "noisy" / "frame_0000.pcd"
    run_tool("range_nlm_denoise", source, tmp_path / "out.pcd", *SMALL_CLI)
    expected = range_nlm.read_pcd(str(tmp_path / "out.pcd"))
    points = range_nlm.read_pcd(str(source))
    result = range_nlm.denoise(points, **SMALL)
    assert result.shape == points.shape and result.dtype == np.float32
    assert not np.array_equal(bits(result), bits(points))  # the filter did move points
    assert np.array_equal(bits(result), bits(expected))


def test_parameters_object_and_keywords_give_the_same_result(frames):
    by_keywords = range_nlm.denoise(frames[0], iterations=1, **SMALL)
    by_object = range_nlm.denoise(frames[0], range_nlm.Parameters(iterations=1, **SMALL))
    assert np.array_equal(bits(by_keywords), bits(by_object))
    assert not np.array_equal(bits(by_keywords), bits(range_nlm.denoise(frames[0], **SMALL)))


def test_denoise_depth_is_bit_identical_to_the_cli_png(scene, tmp_path):
    points = range_nlm.read_pcd(str(scene / "noisy" / "frame_0000.pcd"))
    depth = np.nan_to_num(np.round(points[:, :, 2] * 5000.0), nan=0.0).astype(np.uint16)
    range_nlm.write_depth_png(str(tmp_path / "in.png"), depth)
    (tmp_path / "intrinsics.txt").write_text("fx 60\nfy 60\ncx 31.5\ncy 23.5\ndepth_scale 5000\n")
    run_tool("range_nlm_denoise", tmp_path / "in.png", tmp_path / "out.png", "--intrinsics",
             tmp_path / "intrinsics.txt", *SMALL_CLI)
    expected = range_nlm.read_depth_png(str(tmp_path / "out.png"))
    intrinsics = range_nlm.read_intrinsics(tmp_path / "intrinsics.txt")
    result = range_nlm.denoise_depth(depth, intrinsics, **SMALL)
    assert result.dtype == np.uint16 and result.shape == depth.shape
    assert not np.array_equal(result, depth)
    assert np.array_equal(result, expected)
    # The same frame as a dict of intrinsics, and as float metres: the same depth image, but for
    # the last bit of each input depth (value / 5000 rounded to float32), which the re-projection
    # onto the rays can carry across a rounding step of the 16-bit encoding.
    as_dict = {"fx": 60, "fy": 60, "cx": 31.5, "cy": 23.5}
    metres = range_nlm.denoise_depth(depth.astype(np.float32) / 5000.0, as_dict, **SMALL)
    assert metres.dtype == np.float32
    encoded = np.round(metres.astype(np.float64) * 5000.0).astype(np.int64)
    assert np.array_equal(encoded == 0, expected == 0)
    assert np.abs(encoded - expected.astype(np.int64)).max() <= 1


def test_denoise_depth_points_output_is_the_cli_pcd_output(scene, tmp_path):
    # output="points" gives the filtered points themselves (as a PCD output of the same depth
    # image holds them); the depth output puts each of them on its pixel's ray first.
    points = range_nlm.read_pcd(str(scene / "noisy" / "frame_0001.pcd"))
    depth = np.nan_to_num(np.round(points[:, :, 2] * 1000.0), nan=0.0).astype(np.uint16)
    range_nlm.write_depth_png(str(tmp_path / "in.png"), depth)
    (tmp_path / "intrinsics.txt").write_text("fx 60\nfy 60\ncx 31.5\ncy 23.5\ndepth_scale 1000\n")
    run_tool("range_nlm_denoise", tmp_path / "in.png", tmp_path / "out.pcd", "--intrinsics",
             tmp_path / "intrinsics.txt", *SMALL_CLI)
    expected = range_nlm.read_pcd(str(tmp_path / "out.pcd"))
    intrinsics = range_nlm.Intrinsics(fx=60, fy=60, cx=31.5, cy=23.5, depth_scale=1000)
    out_points = range_nlm.denoise_depth(depth, intrinsics, output="points", **SMALL)
    out_depth = range_nlm.denoise_depth(depth, intrinsics, **SMALL)
    assert out_points.shape == depth.shape + (3,) and out_points.dtype == np.float32
    assert np.array_equal(bits(out_points), bits(expected))
    assert np.array_equal(depth == 0, out_depth == 0)  # no measurement stays none


def test_nan_in_gives_nan_out_in_all_coordinates():
    points = plane()
    points[10, 20] = np.nan
    points[30, 5, 0] = np.nan  # one coordinate is enough to make the point invalid
    result = range_nlm.denoise(points, **SMALL)
    invalid = np.zeros(points.shape[:2], bool)
    invalid[10, 20] = invalid[30, 5] = True
    assert np.array_equal(np.isnan(result).any(axis=2), invalid)
    assert np.isnan(result[invalid]).all()
    assert np.isfinite(result[~invalid]).all()


def test_float64_input_gives_float64_output_of_the_float32_result():
    points = plane(dtype=np.float64)
    result = range_nlm.denoise(points, **SMALL)
    assert result.dtype == np.float64 and result.shape == points.shape
    single = range_nlm.denoise(points.astype(np.float32), **SMALL)
    assert np.array_equal(result.astype(np.float32), single)


def test_all_nan_frame_comes_back_unchanged_with_the_reason():
    points = np.full((12, 16, 3), np.nan, np.float32)
    result, info = range_nlm.denoise(points, return_info=True)
    assert np.isnan(result).all()
    assert info["filtered"] is False and info["reason"]


def test_return_info_gives_the_bandwidths_the_filter_chose():
    points = plane()
    _, info = range_nlm.denoise(points, return_info=True, **SMALL)
    assert info["filtered"] and info["reason"] is None
    assert info["distance_bandwidth"] > 0 and info["similarity_bandwidth"] > 0
    # A bandwidth given explicitly is the one used.
    _, given = range_nlm.denoise(points, return_info=True, distance_bandwidth=0.05, similarity_bandwidth=0.01,
                                 bandwidth_model="global", **SMALL)
    assert given["distance_bandwidth"] == pytest.approx(0.05)
    assert given["similarity_bandwidth"] == pytest.approx(0.01)


@pytest.mark.parametrize(
    "make, error, words",
    [
        (lambda p: p[:, :, 2], ValueError, "H x W x 3"),
        (lambda p: p.astype(np.int32), TypeError, "float32 or float64"),
        (lambda p: [["a", "b", "c"]], TypeError, "array-like of numbers"),
        (lambda p: object(), TypeError, "array-like of numbers"),
        (lambda p: p.tolist()[:2] + [[[1.0]]], TypeError, "array-like"),
        (lambda p: p[:0], ValueError, "shape (0, 64, 3)"),
    ],
)
def test_wrong_arrays_raise_errors_that_say_what_is_wrong(make, error, words):
    with pytest.raises(error, match=r".*" + words.replace("(", r"\(").replace(")", r"\)")):
        range_nlm.denoise(make(plane()))


def test_infinite_coordinate_is_refused_naming_the_pixel():
    points = plane()
    points[3, 7, 2] = np.inf
    with pytest.raises(ValueError, match=r"infinite coordinate at pixel \(7, 3\)"):
        range_nlm.denoise(points)


@pytest.mark.parametrize("bad, text", [(np.inf, "inf"), (-np.inf, "-inf"), (np.nan, "nan")])
def test_non_finite_viewpoint_is_refused_naming_it_and_its_value(tmp_path, bad, text):
    # Ranges are measured from the viewpoint: a non-finite one would leave nothing to filter.
    points = plane(width=20, height=10)
    message = r"viewpoint must be finite, got \(%s, 0, 0\)" % text
    with pytest.raises(ValueError, match=message):
        range_nlm.denoise(points, viewpoint=(bad, 0, 0))
    # write_pcd refuses what read_pcd would refuse.
    with pytest.raises(ValueError, match=message):
        range_nlm.write_pcd(str(tmp_path / "far.pcd"), points, viewpoint=(bad, 0, 0))
    assert not (tmp_path / "far.pcd").exists()
    assert range_nlm.denoise(points, viewpoint=(0.5, 0, -1), **SMALL).shape == points.shape


def test_depth_errors_name_the_problem():
    with pytest.raises(TypeError, match="uint16, float32 or float64"):
        range_nlm.denoise_depth(np.ones((8, 8), np.int32))
    with pytest.raises(ValueError, match="output must be 'depth' or 'points'"):
        range_nlm.denoise_depth(np.ones((8, 8), np.uint16), output="cloud")
    with pytest.raises(ValueError, match="but the intrinsics"):
        range_nlm.denoise_depth(np.ones((8, 8), np.uint16), range_nlm.Intrinsics(width=640, height=480))


def test_gil_is_released_while_a_frame_is_filtered():
    # One OpenMP thread for the filter leaves a core to this thread; while the GIL is held by a
    # call, this thread would stand still for the whole call.
    points = plane(width=320, height=240)
    params = dict(threads=1, search_window=9, iterations=2)
    start = time.perf_counter()
    range_nlm.denoise(points, **params)
    call = time.perf_counter() - start
    done = threading.Event()
    worker = threading.Thread(target=lambda: (range_nlm.denoise(points, **params), done.set()))
    stamps = []
    worker.start()
    while not done.is_set():
        stamps.append(time.perf_counter())
        time.sleep(0.001)
    worker.join()
    gaps = np.diff(stamps)
    assert len(stamps) > 10
    assert gaps.max() < 0.5 * call, "this thread stood still for %.3f s of a %.3f s call" % (gaps.max(), call)


def test_ctrl_c_stops_a_long_call_soon_and_the_module_goes_on():
    # The filter checks for signals between its stages: KeyboardInterrupt comes well before the
    # call would have ended (measured here, on this machine), and the next call is unaffected.
    points = plane(width=1200, height=900)
    expected = range_nlm.denoise(points)
    start = time.perf_counter()  # a second call, as the interrupted one, reuses the buffers
    range_nlm.denoise(points)
    whole = time.perf_counter() - start
    stopped = seconds_to_interrupt(lambda: range_nlm.denoise(points), 0.2 * whole)
    assert stopped is not None, "the call of %.2f s ended before the signal" % whole
    assert stopped < 0.6 * whole, "KeyboardInterrupt after %.2f s of a %.2f s call" % (stopped, whole)
    assert np.array_equal(bits(range_nlm.denoise(points)), bits(expected))


def _rss_kb():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096 // 1024


def test_no_memory_growth_over_a_thousand_calls():
    # The cheapest setting on a tiny frame: what is measured is what a call keeps, not the filter.
    points = plane(width=12, height=9)
    depth = np.full((9, 12), 7500, np.uint16)
    depth[::3, ::5] += 20
    intrinsics = range_nlm.Intrinsics(fx=60, fy=60, cx=6, cy=4.5)
    params = dict(search_window=3, patch_size=1, normal_window=3, normal_presmooth_window=0, iterations=1,
                  dilation=1, outlier_sigmas=0, bandwidth_samples=20, threads=1)

    def calls(n):
        for _ in range(n // 2):
            range_nlm.denoise(points, **params)
            range_nlm.denoise_depth(depth, intrinsics, **params)

    calls(100)
    before = _rss_kb()
    calls(1000)
    grown = _rss_kb() - before
    assert grown < 512, "RSS grew by %d kB over 1000 calls" % grown


def test_depth_to_points_back_projects_as_the_library_reads_a_png(tmp_path):
    depth = np.full((6, 8), 5000, np.uint16)
    depth[2, 3] = 0
    intrinsics = range_nlm.Intrinsics(fx=100, fy=100, cx=3.5, cy=2.5, depth_scale=5000)
    points = range_nlm.depth_to_points(depth, intrinsics)
    assert points.dtype == np.float32 and points.shape == (6, 8, 3)
    assert np.isnan(points[2, 3]).all()
    assert points[0, 0].tolist() == pytest.approx([-0.035, -0.025, 1.0])
    metres = range_nlm.depth_to_points(depth.astype(np.float32) / 5000, intrinsics)
    assert np.array_equal(bits(metres), bits(points))


@pytest.mark.parametrize(
    "view",
    [
        lambda p: p[::2, ::3],                                   # a strided view
        lambda p: np.asfortranarray(p),                          # another order
        lambda p: p.astype(p.dtype.newbyteorder(">")),           # another byte order
        lambda p: np.lib.stride_tricks.as_strided(p, p.shape, p.strides),  # writeable=False view
    ],
)
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_a_view_that_is_not_contiguous_gives_the_bytes_of_its_contiguous_copy(view, dtype):
    points = plane(dtype=dtype)
    points[5, 9] = np.nan
    strided = view(points)
    copy = np.ascontiguousarray(strided, dtype=dtype)
    result = range_nlm.denoise(strided, **SMALL)
    assert result.dtype == dtype and result.shape == copy.shape
    assert np.array_equal(bits(result), bits(range_nlm.denoise(copy, **SMALL)))
    assert np.array_equal(bits(strided), bits(view(points)))  # the input is left as it was


def test_a_strided_depth_view_gives_the_bytes_of_its_contiguous_copy():
    depth = np.nan_to_num(np.round(plane(128, 48)[:, :, 2] * 5000.0), nan=0.0).astype(np.uint16)
    strided = depth[:, ::2]
    assert not strided.flags.c_contiguous
    intrinsics = range_nlm.Intrinsics(fx=30, fy=60, cx=31.5, cy=23.5)
    copy = np.ascontiguousarray(strided)
    assert np.array_equal(range_nlm.denoise_depth(strided, intrinsics, **SMALL),
                          range_nlm.denoise_depth(copy, intrinsics, **SMALL))
    metres = (strided / 5000.0).T  # float64, transposed
    assert np.array_equal(bits(range_nlm.denoise_depth(metres, intrinsics, **SMALL)),
                          bits(range_nlm.denoise_depth(np.ascontiguousarray(metres), intrinsics, **SMALL)))


def test_lists_are_read_as_numpy_reads_them():
    points = plane(width=24, height=16, dtype=np.float64)
    result = range_nlm.denoise(points.tolist(), **SMALL)
    assert result.dtype == np.float64  # numpy.asarray of floats
    assert np.array_equal(bits(result), bits(range_nlm.denoise(points, **SMALL)))
    # Integers (millimetres, say) become float64.
    integers = np.round(points * 1000).astype(np.int64)
    assert np.array_equal(bits(range_nlm.denoise(integers.tolist(), **SMALL)),
                          bits(range_nlm.denoise(integers.astype(np.float64), **SMALL)))
    # A depth image as a list of floats (metres), also through a stream.
    depth = points[:, :, 2]
    intrinsics = range_nlm.Intrinsics(fx=60, fy=60, cx=12, cy=8)
    assert np.array_equal(bits(range_nlm.denoise_depth(depth.tolist(), intrinsics, **SMALL)),
                          bits(range_nlm.denoise_depth(depth, intrinsics, **SMALL)))
    stream = range_nlm.Stream(0, intrinsics=intrinsics, **SMALL)
    assert np.array_equal(bits(stream.push(depth.tolist())[0]), bits(range_nlm.denoise_depth(depth, intrinsics, **SMALL)))
    # A list of integers is no depth image: raw values need their dtype.
    with pytest.raises(TypeError, match="dtype=numpy.uint16"):
        range_nlm.denoise_depth(np.round(depth * 5000).astype(int).tolist(), intrinsics, **SMALL)
