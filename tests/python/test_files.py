"""Files through range_nlm::io: PCD frames, depth PNGs, intrinsics; errors name the file."""

import os

import numpy as np
import pytest

import range_nlm
from conftest import SOURCE_DIR, bits, plane


def test_pcd_round_trip_keeps_points_nan_and_viewpoint(tmp_path):
    points = plane(width=20, height=10)
    points[2, 3] = np.nan
    path = str(tmp_path / "frame.pcd")
    range_nlm.write_pcd(path, points, viewpoint=(0.5, 0.0, -1.0))
    back, viewpoint = range_nlm.read_pcd(path, return_viewpoint=True)
    assert np.array_equal(bits(back), bits(points))
    assert viewpoint == (0.5, 0.0, -1.0)


def test_depth_png_round_trip(tmp_path):
    depth = (np.arange(12 * 9, dtype=np.uint16) * 600).reshape(9, 12)
    path = str(tmp_path / "depth.png")
    range_nlm.write_depth_png(path, depth)
    assert np.array_equal(range_nlm.read_depth_png(path), depth)
    with pytest.raises(TypeError, match="uint16"):
        range_nlm.write_depth_png(path, depth.astype(np.float32))


def test_missing_and_damaged_files_raise_errors_naming_them(tmp_path):
    missing = str(tmp_path / "missing.pcd")
    with pytest.raises(OSError, match="missing.pcd"):
        range_nlm.read_pcd(missing)
    with pytest.raises(range_nlm.InputError):
        range_nlm.read_pcd(missing)
    damaged = tmp_path / "damaged.png"
    damaged.write_bytes(b"not a png")
    with pytest.raises(ValueError, match=r"damaged.png.*not a PNG file"):
        range_nlm.read_depth_png(str(damaged))
    bad = tmp_path / "intrinsics.txt"
    bad.write_text("fx 525\nfocal 3\n")
    with pytest.raises(ValueError, match=r"intrinsics.txt' line 2: unknown key 'focal'"):
        range_nlm.read_intrinsics(bad)


def test_shipped_frame_and_intrinsics_are_read():
    folder = SOURCE_DIR + "/data/depth-images/tum-fr2-desk-pair/"
    depth = range_nlm.read_depth_png(folder + "1_depth.png")
    intrinsics = range_nlm.read_intrinsics(folder + "intrinsics.txt")
    assert depth.shape == (480, 640) and depth.dtype == np.uint16
    assert intrinsics.depth_scale == 5000 and intrinsics.source.endswith("intrinsics.txt")


def test_render_before_after_writes_a_picture(tmp_path):
    points = plane(width=40, height=30)
    after = range_nlm.denoise(points, search_window=5)
    limit = range_nlm.render_before_after(points, after, str(tmp_path / "ba.png"), mode="curvature")
    assert limit > 0
    with open(tmp_path / "ba.png", "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"


def test_prefer_huge_pages_sets_up_the_heap_and_changes_no_result():
    points = plane(width=64, height=48)
    before = range_nlm.denoise(points)
    setup = range_nlm.prefer_huge_pages()
    # glibc (Debian's Python): buffers below 32 MiB come from the heap.
    assert setup["heap_below_bytes"] == 32 << 20
    assert setup["marked_bytes"] >= 0
    assert np.array_equal(bits(range_nlm.denoise(points)), bits(before))


def _path_calls(folder):
    """Every function of the module that takes a path: name -> call(path), each on a file of its
    own under `folder` (the readers' files exist, so that only the path can be at fault)."""
    points = plane(width=8, height=6)
    depth = np.full((6, 8), 5000, dtype=np.uint16)
    range_nlm.write_pcd(str(folder / "in.pcd"), points)
    range_nlm.write_depth_png(str(folder / "in.png"), depth)
    (folder / "intrinsics.txt").write_text("fx 525\nfy 525\ncx 319.5\ncy 239.5\n")
    return {
        "read_pcd": (lambda p: range_nlm.read_pcd(p), "in.pcd"),
        "write_pcd": (lambda p: range_nlm.write_pcd(p, points), "out.pcd"),
        "read_depth_png": (lambda p: range_nlm.read_depth_png(p), "in.png"),
        "write_depth_png": (lambda p: range_nlm.write_depth_png(p, depth), "out.png"),
        "read_intrinsics": (lambda p: range_nlm.read_intrinsics(p), "intrinsics.txt"),
        "render_before_after": (lambda p: range_nlm.render_before_after(points, points, p), "render.png"),
    }


@pytest.mark.parametrize("name", ["read_pcd", "write_pcd", "read_depth_png", "write_depth_png", "read_intrinsics",
                                  "render_before_after"])
def test_every_path_argument_takes_str_bytes_and_path_like(tmp_path, name):
    call, file_name = _path_calls(tmp_path)[name]
    for path in (str(tmp_path / file_name), tmp_path / file_name, os.fsencode(tmp_path / file_name)):
        call(path)
        assert (tmp_path / file_name).exists()
    with pytest.raises(TypeError, match="path must be a str, bytes or os.PathLike path, got int"):
        call(3)


@pytest.mark.parametrize("name", ["read_pcd", "write_pcd", "read_depth_png", "write_depth_png", "read_intrinsics",
                                  "render_before_after"])
def test_a_path_with_an_embedded_null_byte_is_refused_as_open_refuses_it(tmp_path, name):
    call, file_name = _path_calls(tmp_path)[name]
    # The part before the NUL names an existing file (readers) or a writable one (writers): cut
    # there, the call would go through on another file than the one named.
    before = sorted(os.listdir(tmp_path))
    for path in (str(tmp_path / file_name) + "\0/../x", tmp_path / (file_name + "\0x"),
                 os.fsencode(tmp_path / file_name) + b"\0x"):
        with pytest.raises(ValueError, match="path has an embedded null byte"):
            call(path)
    with pytest.raises(ValueError, match="embedded null byte"):
        open(str(tmp_path / file_name) + "\0/../x", "rb")
    assert sorted(os.listdir(tmp_path)) == before


def test_a_bytes_path_need_not_be_utf8_and_errors_still_name_it(tmp_path):
    points = plane(width=8, height=6)
    path = os.fsencode(tmp_path) + b"/\xff.pcd"
    range_nlm.write_pcd(path, points)
    assert os.listdir(os.fsencode(tmp_path)) == [b"\xff.pcd"]
    assert np.array_equal(bits(range_nlm.read_pcd(path)), bits(points))
    with pytest.raises(range_nlm.InputError, match=r"\\xffmissing.pcd'"):
        range_nlm.read_pcd(os.fsencode(tmp_path) + b"/\xffmissing.pcd")
    with pytest.raises(ValueError, match=r"\\xffmissing.png'"):
        range_nlm.read_depth_png(os.fsencode(tmp_path) + b"/\xffmissing.png")
