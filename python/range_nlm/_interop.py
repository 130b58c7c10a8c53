"""Open3D interop: organized frames to and from open3d.geometry.PointCloud, depth images to and
from open3d.geometry.Image / open3d.t.geometry.Image, and RGBDImage depth. Open3D is imported
only when one of these is called, so range_nlm works without it.

An Open3D point cloud has no width and height: to_open3d keeps every pixel (NaN points
included, in row-major order) and remembers the frame's H x W for that cloud, so that
from_open3d can give the organized array back; for other clouds give width or height (the
other follows from the point count).
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


def _is_open3d(value):
    """Whether `value` is an Open3D object (told by its type's module: Open3D is not imported)."""
    return type(value).__module__.split(".")[0] == "open3d"


def _colors_array(colors, shape):
    """Colours for an H x W frame as N x 3 float64 in [0, 1]: H x W x 3 (or N x 3) uint8 0-255, or
    floats in [0, 1]."""
    colors = np.asarray(colors)
    if colors.shape not in (shape + (3,), (shape[0] * shape[1], 3)):
        raise ValueError("range_nlm: colors must be H x W x 3 for a %d x %d frame, got shape %s"
                         % (shape[0], shape[1], colors.shape))
    if colors.dtype == np.uint8:
        return colors.reshape(-1, 3).astype(np.float64) / 255.0
    if colors.dtype.kind != "f":
        raise TypeError("range_nlm: colors must be uint8 (0-255) or float (0-1), got %s" % colors.dtype)
    return colors.reshape(-1, 3).astype(np.float64)


def to_open3d(points, colors=None):
    """An open3d.geometry.PointCloud of every pixel of an H x W x 3 array, in row-major order
    (NaN points kept, so the order and count stay those of the frame). The frame's size is
    remembered for from_open3d. colors: the pixels' colours, H x W x 3 uint8 (as
    read_pcd(path, return_colors=True) gives them) or floats in [0, 1]."""
    o3d = _open3d()
    points = np.asarray(points)
    if points.ndim != 3 or points.shape[2] != 3:
        raise ValueError("range_nlm: points must be an H x W x 3 array, got shape %s" % (points.shape,))
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points.reshape(-1, 3).astype(np.float64)))
    if colors is not None:
        cloud.colors = o3d.utility.Vector3dVector(_colors_array(colors, points.shape[:2]))
    _organized_size[cloud] = points.shape[:2]
    return cloud


def _organized_shape(cloud, count, width, height):
    """(height, width) of a cloud of `count` points: as given (one of them is enough), else as
    remembered by to_open3d."""
    for name, value in (("width", width), ("height", height)):
        if value is not None and (isinstance(value, bool) or not hasattr(value, "__index__") or value <= 0):
            raise ValueError("range_nlm: %s must be a positive integer, got %r" % (name, value))
    if width is None and height is None:
        size = _organized_size.get(cloud) if _is_legacy_cloud(cloud) else None
        if size is None:
            raise ValueError("range_nlm: the cloud's organized size is not known (it did not come from to_open3d); "
                             "give width and height (or one of them)")
        height, width = size
    elif width is None or height is None:
        given = width if width is not None else height
        if count % given:
            raise ValueError("range_nlm: the cloud has %d points, not a multiple of the %s %d"
                             % (count, "width" if width is not None else "height", given))
        width, height = (given, count // given) if width is not None else (count // given, given)
    if count != width * height:
        raise ValueError("range_nlm: the cloud has %d points, not width x height = %d x %d = %d"
                         % (count, width, height, width * height))
    return height, width


def _is_legacy_cloud(cloud):
    return isinstance(cloud, _open3d().geometry.PointCloud)


def from_open3d(cloud, width=None, height=None, dtype=np.float64):
    """The organized array of an Open3D object.

    An open3d.geometry.PointCloud or open3d.t.geometry.PointCloud whose points are the pixels of
    an organized frame in row-major order gives its H x W x 3 points: width and height as given
    (one of them is enough: the other follows from the point count), else as remembered by
    to_open3d (and by denoise on an Open3D cloud). An open3d.geometry.Image or
    open3d.t.geometry.Image, whose size it knows, gives its H x W array (as from_open3d_depth)."""
    o3d = _open3d()
    if isinstance(cloud, (o3d.geometry.Image, o3d.t.geometry.Image)):
        return from_open3d_depth(cloud)
    if isinstance(cloud, o3d.t.geometry.PointCloud):
        xyz = cloud.point["positions"].numpy()
    elif isinstance(cloud, o3d.geometry.PointCloud):
        xyz = np.asarray(cloud.points)
    else:
        raise TypeError("range_nlm: expected an open3d PointCloud or Image, got %s" % type(cloud).__name__)
    height, width = _organized_shape(cloud, len(xyz), width, height)
    return np.ascontiguousarray(xyz.reshape(height, width, 3), dtype=dtype)


def denoise_open3d_cloud(denoise, cloud, width, height, **kwargs):
    """denoise() of an Open3D PointCloud (legacy or tensor): a new cloud of the same kind with the
    points filtered, in the same order, and every other attribute (colours, normals) kept."""
    o3d = _open3d()
    points = from_open3d(cloud, width, height)
    filtered = denoise(points, **kwargs)
    info = None
    if isinstance(filtered, tuple):
        filtered, info = filtered
    if isinstance(cloud, o3d.t.geometry.PointCloud):
        result = cloud.clone()
        positions = cloud.point["positions"]
        result.point["positions"] = o3d.core.Tensor(
            filtered.reshape(-1, 3).astype(positions.numpy().dtype), device=positions.device)
    else:
        result = o3d.geometry.PointCloud(cloud)  # a copy: colours, normals, covariances kept
        result.points = o3d.utility.Vector3dVector(filtered.reshape(-1, 3))
        _organized_size[result] = points.shape[:2]
    return (result, info) if info is not None else result


def denoise_open3d_image(denoise_depth, image, **kwargs):
    """denoise_depth() of an Open3D depth Image (legacy or tensor): with output='depth' an Image of
    the same kind holding the filtered depth; with output='points' the points."""
    o3d = _open3d()
    filtered = denoise_depth(from_open3d_depth(image), **kwargs)
    info = None
    if isinstance(filtered, tuple):
        filtered, info = filtered
    if kwargs.get("output", "depth") == "depth":
        filtered = np.ascontiguousarray(filtered)
        if isinstance(image, o3d.t.geometry.Image):
            filtered = o3d.t.geometry.Image(o3d.core.Tensor(filtered))
        else:
            filtered = o3d.geometry.Image(filtered)
    return (filtered, info) if info is not None else filtered


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
