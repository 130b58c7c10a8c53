#!/usr/bin/env python3
"""Filters a real depth frame shipped with range_nlm and draws it before and after.

    PYTHONPATH=build/python /usr/bin/python3 python/examples/denoise_depth_frame.py [OUT.png]

Reads data/depth-images/tum-fr2-desk-pair/1_depth.png (Kinect v1, TUM RGB-D fr2/desk) and its
intrinsics.txt, filters the depth image with the default setting, prints the bandwidths the filter
chose, writes the filtered depth image next to OUT.png (1_depth_filtered.png), and draws both
frames side by side, flat-shaded on one scale (the renderer of range_nlm_render). With Open3D
installed it also filters an open3d.geometry.Image directly and shows the round trip through an
open3d.geometry.PointCloud, with the organized order kept.
"""

import os
import sys
import time

import numpy as np

import range_nlm

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
FRAME = os.path.join(ROOT, "data", "depth-images", "tum-fr2-desk-pair")


def main():
    figure = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "docs", "images", "python_before_after.png")
    depth = range_nlm.read_depth_png(os.path.join(FRAME, "1_depth.png"))
    intrinsics = range_nlm.read_intrinsics(os.path.join(FRAME, "intrinsics.txt"))

    start = time.perf_counter()
    filtered, info = range_nlm.denoise_depth(depth, intrinsics, return_info=True)
    print("filtered %d x %d in %.0f ms: d = %.4f m, s = %.4f m, %d outliers moved"
          % (depth.shape[1], depth.shape[0], 1000 * (time.perf_counter() - start), info["distance_bandwidth"],
             info["similarity_bandwidth"], info["outliers_moved"]))
    depth_out = os.path.join(os.path.dirname(os.path.abspath(figure)), "1_depth_filtered.png")
    range_nlm.write_depth_png(depth_out, filtered)  # what range_nlm_denoise 1_depth.png out.png writes
    print("wrote", depth_out)

    # Both frames as points (the library's back-projection) for the renderer.
    before = range_nlm.depth_to_points(depth, intrinsics)
    after = range_nlm.depth_to_points(filtered, intrinsics)
    range_nlm.render_before_after(before, after, figure, mode="shaded")
    print("wrote", figure)

    try:
        import open3d
    except ImportError:
        print("(Open3D not installed: the point-cloud round trip is skipped)")
        return
    image = range_nlm.denoise_depth(open3d.geometry.Image(depth), intrinsics)
    print("Open3D depth image filtered: %s, equal to the array's: %s"
          % (type(image).__name__, np.array_equal(np.asarray(image), filtered)))
    cloud = range_nlm.to_open3d(after)
    back = range_nlm.from_open3d(cloud)
    print("Open3D cloud of %d points (NaN kept); organized again: %s, same points: %s"
          % (len(cloud.points), back.shape, np.array_equal(np.isnan(back), np.isnan(after))))


if __name__ == "__main__":
    main()
