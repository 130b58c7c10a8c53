"""Open3D interop: organized frames to and from open3d.geometry.PointCloud, depth images to and
from open3d.geometry.Image / open3d.t.geometry.Image, and RGBDImage depth. Open3D is imported
only when one of these is called, so range_nlm works without it.

An Open3D point cloud has no width and height: to_open3d keeps every pixel (NaN points
included, in row-major order) and remembers the frame's H x W for that cloud, so that
from_open3d can give the organized array back; for other clouds pass width and height.
"""

import weakref

import numpy as np

_organized_size = weakref.WeakKeyDictionary()


def _open3d():
    try:
        import open3d
    except ImportError as error:  # pragma: no cover - depends on the machine
        raise ImportError("range_nlm: Open3D is needed for this (Debian: apt-get install python3-open3d)") from error
    return open3d


def to_open3d(points):
    """An open3d.geometry.PointCloud of every pixel of an H x W x 3 array, in row-major order
    (NaN points kept, so the order and count stay those of the frame). The frame's size is
    remembered for from_open3d."""
    o3d = _open3d()
    points = np.asarray(points)
    if points.ndim != 3 or points.shape[2] != 3:
        raise ValueError("range_nlm: points must be an H x W x 3 array, got shape %s" % (points.shape,))
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points.reshape(-1, 3).astype(np.float64)))
    _organized_size[cloud] = points.shape[:2]
    return cloud


def from_open3d(cloud, width=None, height=None, dtype=np.float64):
    """The H x W x 3 array of an open3d.geometry.PointCloud (or open3d.t.geometry.PointCloud)
    whose points are the pixels of an organized frame in row-major order: height and width as
    given, else as remembered by to_open3d."""
    o3d = _open3d()
    if isinstance(cloud, o3d.t.geometry.PointCloud):
        xyz = cloud.point["positions"].numpy()
    elif isinstance(cloud, o3d.geometry.PointCloud):
        xyz = np.asarray(cloud.points)
    else:
        raise TypeError("range_nlm: expected an open3d PointCloud, got %s" % type(cloud).__name__)
    if width is None or height is None:
        size = _organized_size.get(cloud) if isinstance(cloud, o3d.geometry.PointCloud) else None
        if size is None:
            raise ValueError("range_nlm: the cloud's organized size is not known (it did not come from to_open3d); "
                             "give width and height")
        height, width = size
    if len(xyz) != width * height:
        raise ValueError("range_nlm: the cloud has %d points, not width x height = %d x %d = %d"
                         % (len(xyz), width, height, width * height))
    return np.ascontiguousarray(xyz.reshape(height, width, 3), dtype=dtype)


def to_open3d_depth(depth, tensor=False):
    """An open3d.geometry.Image (or with tensor=True an open3d.t.geometry.Image) of an H x W
    uint16 or float32 depth image."""
    o3d = _open3d()
    depth = np.ascontiguousarray(depth)
    if depth.ndim != 2 or depth.dtype not in (np.uint16, np.float32):
        raise ValueError("range_nlm: a depth image is H x W uint16 or float32, got %s %s" % (depth.shape, depth.dtype))
    return o3d.t.geometry.Image(o3d.core.Tensor(depth)) if tensor else o3d.geometry.Image(depth)


def from_open3d_depth(image):
    """The H x W array of a one-channel open3d.geometry.Image or open3d.t.geometry.Image, in
    its own dtype (uint16 or float32)."""
    o3d = _open3d()
    if isinstance(image, o3d.t.geometry.Image):
        array = image.as_tensor().numpy()
    elif isinstance(image, o3d.geometry.Image):
        array = np.asarray(image)
    else:
        raise TypeError("range_nlm: expected an open3d Image, got %s" % type(image).__name__)
    if array.ndim == 3 and array.shape[2] == 1:
        array = array[:, :, 0]
    if array.ndim != 2:
        raise ValueError("range_nlm: a depth image has one channel, this one has shape %s" % (array.shape,))
    return np.ascontiguousarray(array)


def from_rgbd(rgbd):
    """The depth of an open3d.geometry.RGBDImage as an H x W array (float32 metres, as
    RGBDImage.create_from_color_and_depth stores it, unless convert_rgb_to_intensity kept raw
    values)."""
    return from_open3d_depth(rgbd.depth)


def denoise_rgbd(rgbd, intrinsics, parameters=None, **kwargs):
    """A new open3d.geometry.RGBDImage with the depth of `rgbd` filtered by denoise_depth
    (float metres: depth_scale 1); the colour is kept."""
    from . import denoise_depth

    o3d = _open3d()
    depth = from_rgbd(rgbd)
    filtered = denoise_depth(depth, intrinsics, parameters, **kwargs)
    result = o3d.geometry.RGBDImage()
    result.color = o3d.geometry.Image(np.ascontiguousarray(np.asarray(rgbd.color)))
    result.depth = o3d.geometry.Image(np.ascontiguousarray(filtered))
    return result
