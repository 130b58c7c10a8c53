"""Open3D interop: organized order and count kept, depth images in both Image types, RGBD."""

import numpy as np
import pytest

import range_nlm
from conftest import SMALL, SOURCE_DIR, bits, plane

o3d = pytest.importorskip("open3d")


def test_point_cloud_round_trip_keeps_order_and_count():
    points = plane(width=30, height=20, dtype=np.float64)
    points[4, 7] = np.nan
    cloud = range_nlm.to_open3d(points)
    assert len(cloud.points) == 30 * 20
    back = range_nlm.from_open3d(cloud)
    assert back.shape == points.shape
    assert np.array_equal(np.isnan(back), np.isnan(points))
    assert np.array_equal(np.nan_to_num(back), np.nan_to_num(points))


def test_foreign_cloud_needs_width_and_height():
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(plane(width=6, height=4).reshape(-1, 3).astype(float)))
    with pytest.raises(ValueError, match="give width and height"):
        range_nlm.from_open3d(cloud)
    assert range_nlm.from_open3d(cloud, width=6, height=4).shape == (4, 6, 3)
    with pytest.raises(ValueError, match="24 points, not width x height = 5 x 4"):
        range_nlm.from_open3d(cloud, width=5, height=4)


def test_filtered_open3d_cloud_equals_the_filtered_array():
    points = plane(width=40, height=30)
    cloud = range_nlm.to_open3d(points)
    filtered = range_nlm.denoise(range_nlm.from_open3d(cloud), **SMALL)
    assert filtered.dtype == np.float64
    assert np.array_equal(filtered.astype(np.float32), range_nlm.denoise(points, **SMALL))


@pytest.mark.parametrize("tensor", [False, True])
def test_depth_image_round_trip(tensor):
    depth = (np.arange(48 * 64, dtype=np.uint16) % 4000 + 3000).reshape(48, 64)
    image = range_nlm.to_open3d_depth(depth, tensor=tensor)
    assert isinstance(image, o3d.t.geometry.Image if tensor else o3d.geometry.Image)
    back = range_nlm.from_open3d_depth(image)
    assert back.dtype == np.uint16 and np.array_equal(back, depth)


def test_rgbd_depth_is_filtered_and_colour_kept():
    points = plane(width=64, height=48)
    depth = np.round(points[:, :, 2] * 1000).astype(np.uint16)
    colour = np.full((48, 64, 3), 90, np.uint8)
    rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
        o3d.geometry.Image(colour), o3d.geometry.Image(depth), depth_scale=1000.0, convert_rgb_to_intensity=False)
    intrinsics = o3d.camera.PinholeCameraIntrinsic(64, 48, 60.0, 60.0, 32.0, 24.0)
    result = range_nlm.denoise_rgbd(rgbd, intrinsics, **SMALL)
    metres = range_nlm.from_rgbd(rgbd)
    filtered = range_nlm.from_rgbd(result)
    assert filtered.shape == metres.shape and filtered.dtype == np.float32
    assert np.array_equal(filtered, range_nlm.denoise_depth(metres, intrinsics, **SMALL))
    assert np.std(filtered) < np.std(metres)
    assert np.array_equal(np.asarray(result.color), np.asarray(rgbd.color))


def _coloured_cloud(width=40, height=30, tensor=False):
    """An Open3D cloud of an organized plane, with colours and normals, not from to_open3d."""
    points = plane(width=width, height=height, dtype=np.float64)
    points[3, 4] = np.nan
    rng = np.random.default_rng(5)
    colours = rng.random((width * height, 3))
    normals = np.tile([0.0, 0.0, -1.0], (width * height, 1))
    if tensor:
        cloud = o3d.t.geometry.PointCloud(o3d.core.Tensor(points.reshape(-1, 3).astype(np.float32)))
        cloud.point["colors"] = o3d.core.Tensor(colours.astype(np.float32))
        cloud.point["normals"] = o3d.core.Tensor(normals.astype(np.float32))
    else:
        cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points.reshape(-1, 3)))
        cloud.colors = o3d.utility.Vector3dVector(colours)
        cloud.normals = o3d.utility.Vector3dVector(normals)
    return cloud, points


def test_denoise_takes_an_open3d_cloud_and_keeps_its_colours_and_normals():
    cloud, points = _coloured_cloud()
    result = range_nlm.denoise(cloud, width=40, height=30, **SMALL)
    assert isinstance(result, o3d.geometry.PointCloud) and result is not cloud
    filtered = np.asarray(result.points).reshape(30, 40, 3)
    assert np.array_equal(bits(filtered), bits(range_nlm.denoise(points, **SMALL)))
    assert np.array_equal(np.asarray(result.colors), np.asarray(cloud.colors))
    assert np.array_equal(np.asarray(result.normals), np.asarray(cloud.normals))
    assert np.array_equal(bits(np.asarray(cloud.points)), bits(points.reshape(-1, 3)))  # the input is untouched
    # One side is enough; the result remembers its size, as to_open3d's clouds do.
    assert np.array_equal(bits(np.asarray(range_nlm.denoise(cloud, width=40, **SMALL).points)),
                          bits(np.asarray(result.points)))
    assert range_nlm.from_open3d(result).shape == (30, 40, 3)
    # With return_info, the record comes too.
    again, info = range_nlm.denoise(cloud, height=30, return_info=True, **SMALL)
    assert info["filtered"] and isinstance(again, o3d.geometry.PointCloud)


def test_denoise_takes_a_tensor_cloud_and_keeps_its_attributes():
    cloud, points = _coloured_cloud(tensor=True)
    result = range_nlm.denoise(cloud, width=40, height=30, **SMALL)
    assert isinstance(result, o3d.t.geometry.PointCloud)
    positions = result.point["positions"].numpy()
    assert positions.dtype == np.float32
    expected = range_nlm.denoise(points.astype(np.float32), **SMALL)
    assert np.array_equal(bits(positions.reshape(30, 40, 3)), bits(expected))
    assert np.array_equal(result.point["colors"].numpy(), cloud.point["colors"].numpy())
    assert np.array_equal(result.point["normals"].numpy(), cloud.point["normals"].numpy())


def test_a_cloud_of_unknown_or_wrong_size_is_refused_naming_the_problem():
    cloud, _ = _coloured_cloud()
    with pytest.raises(ValueError, match="organized size is not known.*give width and height"):
        range_nlm.denoise(cloud, **SMALL)
    with pytest.raises(ValueError, match="1200 points, not width x height = 40 x 20 = 800"):
        range_nlm.denoise(cloud, width=40, height=20, **SMALL)
    with pytest.raises(ValueError, match="1200 points, not a multiple of the width 7"):
        range_nlm.denoise(cloud, width=7, **SMALL)
    with pytest.raises(ValueError, match="width must be a positive integer, got 0"):
        range_nlm.denoise(cloud, width=0, height=30, **SMALL)
    with pytest.raises(TypeError, match="width and height are the organized size of an Open3D PointCloud"):
        range_nlm.denoise(plane(), width=64, **SMALL)


@pytest.mark.parametrize("tensor", [False, True])
@pytest.mark.parametrize("dtype", [np.uint16, np.float32])
def test_denoise_depth_takes_an_open3d_image(tensor, dtype):
    points = plane(width=64, height=48)
    depth = np.round(points[:, :, 2] * 5000).astype(np.uint16) if dtype == np.uint16 else points[:, :, 2].copy()
    intrinsics = range_nlm.Intrinsics(fx=60, fy=60, cx=32, cy=24)
    image = range_nlm.to_open3d_depth(depth, tensor=tensor)
    result = range_nlm.denoise_depth(image, intrinsics, **SMALL)
    assert isinstance(result, o3d.t.geometry.Image if tensor else o3d.geometry.Image)
    expected = range_nlm.denoise_depth(depth, intrinsics, **SMALL)
    assert np.array_equal(bits(range_nlm.from_open3d_depth(result)), bits(expected))
    filtered_points = range_nlm.denoise_depth(image, intrinsics, output="points", **SMALL)
    assert np.array_equal(bits(filtered_points), bits(range_nlm.denoise_depth(depth, intrinsics, output="points", **SMALL)))


def test_from_open3d_knows_the_size_of_an_image():
    depth = (np.arange(48 * 64, dtype=np.uint16) % 4000 + 3000).reshape(48, 64)
    for tensor in (False, True):
        back = range_nlm.from_open3d(range_nlm.to_open3d_depth(depth, tensor=tensor))
        assert back.dtype == np.uint16 and np.array_equal(back, depth)


def test_to_open3d_keeps_the_colours_of_a_pcd(tmp_path):
    path = SOURCE_DIR + "/data/milk_cartoon_all_small_clorox.pcd"
    points, colours = range_nlm.read_pcd(path, return_colors=True)
    assert colours.shape == points.shape and colours.dtype == np.uint8
    assert len(np.unique(colours.reshape(-1, 3), axis=0)) > 100  # a real picture, not one colour
    cloud = range_nlm.to_open3d(points, colors=colours)
    # Open3D's own reader of the same file gives the same colours, pixel by pixel.
    theirs = o3d.io.read_point_cloud(path, remove_nan_points=False, remove_infinite_points=False)
    assert len(theirs.colors) == len(cloud.colors) == points.shape[0] * points.shape[1]
    assert np.allclose(np.asarray(cloud.colors), np.asarray(theirs.colors), atol=1e-6)
    # And denoise keeps them.
    small = range_nlm.to_open3d(points[:60, :80], colors=colours[:60, :80])
    assert np.array_equal(np.asarray(range_nlm.denoise(small, **SMALL).colors), np.asarray(small.colors))
    # A frame without colours gives None; a viewpoint and colours come in that order.
    assert range_nlm.read_pcd(path, return_viewpoint=True, return_colors=True)[1] == (0.0, 0.0, 0.0)
    range_nlm.write_pcd(tmp_path / "xyz.pcd", points[:10, :10])
    assert range_nlm.read_pcd(tmp_path / "xyz.pcd", return_colors=True)[1] is None
    with pytest.raises(ValueError, match="colors must be H x W x 3 for a 480 x 640 frame"):
        range_nlm.to_open3d(points, colors=colours[:10])
