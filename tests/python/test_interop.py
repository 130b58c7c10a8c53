"""Open3D interop: organized order and count kept, depth images in both Image types, RGBD."""

import numpy as np
import pytest

import range_nlm
from conftest import SMALL, plane

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
