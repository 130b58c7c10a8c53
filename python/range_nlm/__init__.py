"""range_nlm: non-local denoising of organized range data (depth images, organized point clouds).

The filter is the C++ library's (the one range_nlm_denoise runs), called on numpy arrays:

* ``denoise(points, **params)``: an organized H x W x 3 float32/float64 array, NaN = invalid;
* ``denoise_depth(depth, intrinsics, **params)``: a uint16 or float depth image;
* ``Stream(radius, mode, **params)``: sequences, frame by frame (the temporal filter).

Every parameter of the filter is a keyword argument, named as in the parameter registry (and
``Parameters``): ``search_window``, ``patch_size``, ``iterations``, ... (the command-line option's
name with ``_`` for ``-`` works too: ``patch``, ``patch_gate``, ``cross_frame``). The defaults are
range_nlm_denoise's. See docs/python.md.
"""

import operator as _operator
import os as _os
import warnings as _warnings

import numpy as _np

from . import _interop, _range_nlm
from ._range_nlm import (
    InputError,
    Intrinsics,
    Parameters,
    prefer_huge_pages,
    read_depth_png,
    read_pcd,
    render_before_after,
    write_depth_png,
    write_pcd,
)
from ._interop import (
    denoise_rgbd,
    from_open3d,
    from_open3d_depth,
    from_rgbd,
    to_open3d,
    to_open3d_depth,
)


def _package_version():
    """The installed distribution's version (importlib.metadata) if this package is the installed
    one, else the version the native module was built with (the project's VERSION)."""
    try:
        import importlib.metadata as metadata
        dist = metadata.distribution("range_nlm")
        installed = _os.path.realpath(str(dist.locate_file("range_nlm")))
    except Exception:  # not installed (e.g. imported from a build tree), or no importlib.metadata
        return _range_nlm.__version__
    # Another range_nlm installed elsewhere says nothing about this one (a build tree on PYTHONPATH).
    if installed != _os.path.realpath(_os.path.dirname(__file__)):
        return _range_nlm.__version__
    return dist.version


__version__ = _package_version()

__all__ = [
    "denoise",
    "denoise_depth",
    "depth_to_points",
    "Stream",
    "Parameters",
    "Intrinsics",
    "InputError",
    "read_intrinsics",
    "read_pcd",
    "write_pcd",
    "read_depth_png",
    "write_depth_png",
    "render_before_after",
    "prefer_huge_pages",
    "to_open3d",
    "from_open3d",
    "to_open3d_depth",
    "from_open3d_depth",
    "from_rgbd",
    "denoise_rgbd",
]


def _parameters(parameters, params):
    """Parameters from a Parameters object, a preset name or None, with the keywords applied."""
    return _range_nlm.parameters_from(parameters, **params)


def _intrinsics(intrinsics):
    """An Intrinsics from an Intrinsics, a dict with fx, fy, cx, cy (depth_scale, width, height),
    or any object with those attributes."""
    if isinstance(intrinsics, Intrinsics):
        return intrinsics
    if hasattr(intrinsics, "intrinsic_matrix"):  # open3d.camera.PinholeCameraIntrinsic
        k = intrinsics.intrinsic_matrix
        return Intrinsics(fx=k[0][0], fy=k[1][1], cx=k[0][2], cy=k[1][2], width=intrinsics.width,
                          height=intrinsics.height)
    keys = ("fx", "fy", "cx", "cy", "depth_scale", "width", "height")
    if isinstance(intrinsics, dict):
        unknown = sorted(set(intrinsics) - set(keys))
        if unknown:
            raise TypeError("range_nlm: unknown intrinsics key(s) %s; known: %s" % (", ".join(unknown), ", ".join(keys)))
        return Intrinsics(**intrinsics)
    values = {k: getattr(intrinsics, k) for k in keys if hasattr(intrinsics, k)}
    if not all(k in values for k in keys[:4]):
        raise TypeError("range_nlm: intrinsics must be a range_nlm.Intrinsics, a dict or an object with fx, fy, cx, "
                        "cy; got %s" % type(intrinsics).__name__)
    return Intrinsics(**values)


_default_intrinsics_warned = False


def _default_intrinsics(caller, depth, depth_scale):
    """Intrinsics() for a depth image given without intrinsics, with a UserWarning, once per process,
    as range_nlm_denoise warns about depth PNGs read with default intrinsics."""
    global _default_intrinsics_warned
    intrinsics = Intrinsics()
    dtype = getattr(depth, "dtype", None)
    if dtype is None:  # an array-like, such as a list: as the call will read it
        try:
            dtype = _np.asarray(depth).dtype
        except Exception:  # refused by the call, with its own error
            dtype = None
    # Only for a depth image the call takes (uint16 or float); any other is refused with its own error.
    is_depth = dtype is not None and ((dtype.kind == "u" and dtype.itemsize == 2) or dtype.kind == "f")
    if is_depth and not _default_intrinsics_warned:
        _default_intrinsics_warned = True
        defaults = "fx %g, fy %g, cx %g, cy %g" % (intrinsics.fx, intrinsics.fy, intrinsics.cx, intrinsics.cy)
        if depth_scale is None and dtype.kind == "u":
            defaults += ", depth-scale %g" % intrinsics.depth_scale
        _warnings.warn("range_nlm: %s: this and any other depth image without intrinsics are read with default "
                       "intrinsics (%s: a 640 x 480 Kinect v1 / TUM RGB-D camera); give intrinsics= for your camera, "
                       "or the depths and positions are wrong" % (caller, defaults), UserWarning, stacklevel=3)
    return intrinsics


def read_intrinsics(path):
    """Reads an intrinsics.txt file (``key value`` lines: fx, fy, cx, cy, depth_scale, width,
    height; docs/usage.md). Errors name the file and line (ValueError)."""
    return _range_nlm.read_intrinsics(path)


def depth_to_points(depth, intrinsics=None, depth_scale=None):
    """The H x W x 3 float32 points of a depth image (uint16 or float, as denoise_depth takes it),
    back-projected as range_nlm_denoise reads a depth PNG; NaN where there is no measurement.
    Without intrinsics, the defaults (as denoise_depth) with a UserWarning, once per process."""
    if intrinsics is None:
        intrinsics = _default_intrinsics("depth_to_points", depth, depth_scale)
    else:
        intrinsics = _intrinsics(intrinsics)
    return _range_nlm._depth_to_points(depth, intrinsics, depth_scale)


def denoise(points, parameters=None, *, return_info=False, viewpoint=None, width=None, height=None, **params):
    """Filters an organized frame of points.

    points: H x W x 3 float32 or float64 array; NaN (in any coordinate) marks an invalid point,
        which stays NaN in x, y and z. An infinite coordinate is refused. A C-contiguous array is
        read in place; a strided view or an array-like (nested lists) is copied first. Or an
        open3d.geometry.PointCloud (or open3d.t.geometry.PointCloud) whose points are an
        organized frame in row-major order: the result is a new cloud of that kind, the points
        filtered in the same order, colours and normals kept.
    width, height: for an Open3D cloud, its organized size (one is enough; not needed for a
        cloud from to_open3d or from denoise). A size that does not match the point count raises
        ValueError.
    parameters: a Parameters object, a preset name ('default', 'live' for a live camera's frame
        rate, or 'paper'), or None (the recommended setting, 'default');
        the keyword arguments override it (see Parameters.registry() for every one).
    viewpoint: the sensor position (x, y, z), default the origin (as a PCD without VIEWPOINT);
        finite (a non-finite coordinate raises ValueError).
    return_info: also return a dict with the bandwidths the filter chose
        (distance_bandwidth, similarity_bandwidth, mu_d, sigma_s), outliers_moved, ms, and
        filtered / reason (a frame that cannot be filtered, e.g. all NaN, comes back unchanged).

    Returns an array of the input's shape and dtype (and the dict with return_info). The GIL is
    released while the frame is filtered; Ctrl-C stops the call (KeyboardInterrupt) at the
    filter's next stage.
    """
    if _interop._is_open3d(points):
        return _interop.denoise_open3d_cloud(denoise, points, width, height, parameters=parameters,
                                             return_info=return_info, viewpoint=viewpoint, **params)
    if width is not None or height is not None:
        raise TypeError("range_nlm: width and height are the organized size of an Open3D PointCloud; an array's "
                        "size is its shape (got %s)" % type(points).__name__)
    result, info = _range_nlm._denoise(points, _parameters(parameters, params), viewpoint)
    return (result, info) if return_info else result


def denoise_depth(depth, intrinsics=None, parameters=None, *, depth_scale=None, output="depth", return_info=False,
                  **params):
    """Filters a depth image.

    depth: H x W uint16 image (value / depth_scale = metres, 0 = no measurement), or float32 /
        float64 (value / depth_scale metres; 0, negative or NaN = no measurement). A strided view
        or an array-like (nested lists of floats) is copied first. Or an open3d.geometry.Image (or
        open3d.t.geometry.Image) of one channel: with output='depth' the result is an Image of
        that kind.
    intrinsics: Intrinsics, dict or object with fx, fy, cx, cy (pixels); None: the defaults of
        range_nlm_denoise (525, 525, 319.5, 239.5, depth scale 5000), with a UserWarning (once per
        process) that they are a Kinect v1's, not necessarily the camera's.
    depth_scale: stored values per metre; default the intrinsics' for uint16 images, 1 for float.
    output: 'depth' gives a depth image of the input's dtype (uint16 exactly as range_nlm_denoise
        writes a PNG: the library's cloudToDepthImage, depths filtered past 16 bits clamped with a
        RuntimeWarning; float: the same depths unrounded, invalid pixels as in the input, 0 or
        NaN); 'points' gives the filtered H x W x 3 float32 points.
    Other arguments as denoise().
    """
    if _interop._is_open3d(depth):
        return _interop.denoise_open3d_image(denoise_depth, depth, intrinsics=intrinsics, parameters=parameters,
                                             depth_scale=depth_scale, output=output, return_info=return_info,
                                             **params)
    if intrinsics is None:
        intrinsics = _default_intrinsics("denoise_depth", depth, depth_scale)
    else:
        intrinsics = _intrinsics(intrinsics)
    result, info = _range_nlm._denoise_depth(depth, intrinsics, depth_scale, output, _parameters(parameters, params))
    return (result, info) if return_info else result


class Stream:
    """Temporal filtering of a sequence, one frame at a time (the library's TemporalStream, as
    range_nlm_denoise --input-dir --temporal-radius R runs it).

    radius: temporal radius r (0: every frame alone).
    mode: 'centred' (frames t - r .. t + r; output lags input by r frames), 'causal'
        (t - r .. t, no delay; --causal) or 'recursive' (a running-average history; --recursive).
        None (the default): 'recursive' with the 'live' preset (a camera's stream), else 'centred'.
    intrinsics, depth_scale, output: for depth-image frames, as denoise_depth(); frames are then
        H x W images, otherwise H x W x 3 points.
    Keyword arguments: the filter's parameters, as denoise().

    push(frame) returns the list of frames that became ready (none or one); finish() (or
    flush()) returns the rest. Every frame pushed comes out once, in order, in its own dtype.
    filter(frames) does both for an iterable, as a generator. info holds the records of the last
    frames returned (see denoise's return_info).
    """

    def __init__(self, radius=1, mode=None, parameters=None, *, intrinsics=None, depth_scale=None,
                 output="depth", **params):
        if isinstance(radius, bool) or not hasattr(radius, "__index__"):
            raise TypeError("range_nlm: radius must be an integer, got %r" % (radius,))
        radius = _operator.index(radius)
        if radius < 0:
            raise ValueError("range_nlm: radius must be >= 0, got %d" % radius)
        if mode is None:
            mode = "recursive" if isinstance(parameters, str) and parameters == "live" else "centred"
        self.radius = radius
        self.mode = mode
        self._stream = _range_nlm._Stream(radius, mode, None if intrinsics is None else _intrinsics(intrinsics),
                                          depth_scale, output, _parameters(parameters, params))
        self.info = []

    def push(self, frame):
        """Adds the next frame; returns the frames that became ready. A refused frame (wrong size
        or dtype, an infinite coordinate) raises and leaves the stream as it was. Interrupted
        (KeyboardInterrupt), the push keeps its frame: its result comes with the next call."""
        out = self._stream.push(frame)
        self.info = self._stream.last_info()
        return out

    def finish(self):
        """Ends the sequence: the frames still waiting for future neighbours, filtered."""
        out = self._stream.flush()
        self.info = self._stream.last_info()
        return out

    flush = finish

    def filter(self, frames):
        """Yields the filtered frames of an iterable, in order, then the tail."""
        for frame in frames:
            yield from self.push(frame)
        yield from self.finish()

    @property
    def held_frames(self):
        """Frames held in memory (at most 2r + 1, causal r + 1)."""
        return self._stream.held_frames

    def __repr__(self):
        return "range_nlm.Stream(radius=%d, mode=%r, held_frames=%d)" % (self.radius, self.mode, self.held_frames)


def _parameter_docs():
    lines = ["", "Parameters (keyword arguments; Parameters.registry() lists them):"]
    for entry in Parameters.registry():
        lines.append("    %s: %s" % (entry["name"], entry["doc"]))
    return "\n".join(lines)


denoise.__doc__ += _parameter_docs()
denoise_depth.__doc__ += _parameter_docs()
Stream.__doc__ += _parameter_docs()
