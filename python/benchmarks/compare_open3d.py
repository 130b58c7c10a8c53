#!/usr/bin/env python3
"""range_nlm against Open3D's depth-image filters (and OpenCV's, if installed), accuracy and
time in one run, on generated sensor-noise scenes with ground truth and on shipped real frames.

    PYTHONPATH=build/python /usr/bin/python3 python/benchmarks/compare_open3d.py [--tools build/tools]

Generated scenes (range_nlm_synth, 640 x 480): flat / feature RMSE in mm against the ground truth,
as range_nlm_eval reports it. Real frames: the RMS residual in mm to the planar regions found in
the raw frame, in their interior and in a 3 px band along their borders (range_nlm_eval --raw).
Time: median of --repeats calls of each method in this process (the depth filters on the z image,
range_nlm on the points, with --threads threads, default 1), milliseconds.

The image filters smooth the depth z of each pixel; the filtered point stays on its pixel's ray
(p * z' / z), so every method is scored on the same organized points. Invalid pixels (NaN) are
0 in the depth image the image filters see, and NaN again after them.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import range_nlm

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")


def _works(call):
    """Whether an Open3D filter runs on this build (Debian's Open3D is built without IPP, and
    its tensor image filters then raise 'not implemented' on the CPU)."""
    try:
        call(np.ones((8, 8), np.float32))
        return True
    except RuntimeError:
        return False


def open3d_methods():
    """(name, function of the z image in metres -> filtered z) for the Open3D filters that run
    on this build."""
    try:
        import open3d as o3d
    except ImportError:
        print("note: Open3D is not installed (python3-open3d); its filters are left out", file=sys.stderr)
        return []

    def tensor_filter(name, *args):
        def run(z):
            image = o3d.t.geometry.Image(o3d.core.Tensor(z))
            return getattr(image, name)(*args).as_tensor().numpy()[:, :, 0]
        return run

    def legacy_gaussian(kind):
        # Normalized convolution: the holes (0) are left out of the weighted mean, not averaged in
        # as zero depth.
        def run(z):
            valid = (z > 0).astype(np.float32)
            num = np.asarray(o3d.geometry.Image(z).filter(kind))
            den = np.asarray(o3d.geometry.Image(valid).filter(kind))
            with np.errstate(invalid="ignore", divide="ignore"):
                return np.where(valid > 0, num / den, 0.0).astype(np.float32)
        return run

    methods = []
    candidates = [("open3d t.Image.filter_bilateral 5 px, 10 mm", tensor_filter("filter_bilateral", 5, 0.010, 2.0)),
                  ("open3d t.Image.filter_bilateral 7 px, 30 mm", tensor_filter("filter_bilateral", 7, 0.030, 3.0)),
                  ("open3d t.Image.filter_gaussian 5 px", tensor_filter("filter_gaussian", 5, 1.0))]
    for name, run in candidates:
        if _works(run):
            methods.append((name, run))
        else:
            print("note: %s is not implemented on the CPU in this Open3D %s build; left out"
                  % (name.split(" ")[1], o3d.__version__), file=sys.stderr)
    methods += [("open3d Image.filter Gaussian5 (normalized)", legacy_gaussian(o3d.geometry.ImageFilterType.Gaussian5)),
                ("open3d Image.filter Gaussian7 (normalized)", legacy_gaussian(o3d.geometry.ImageFilterType.Gaussian7))]
    return methods


def opencv_methods():
    try:
        import cv2
    except ImportError:
        print("note: OpenCV (python3-opencv) is not installed; its bilateral filter is left out", file=sys.stderr)
        return []
    return [("opencv bilateral 7 px, 30 mm", lambda z: cv2.bilateralFilter(z, 7, 0.030, 3.0))]


def on_rays(depth_filter):
    """A method on points from a filter of the z image: each point moved along its ray."""
    def run(points):
        z = np.nan_to_num(points[:, :, 2], nan=0.0).astype(np.float32)
        filtered = depth_filter(z)
        with np.errstate(invalid="ignore", divide="ignore"):
            scale = np.where(z > 0, filtered / z, np.nan)
        out = points * scale[:, :, None]
        out[~np.isfinite(out).all(axis=2)] = np.nan
        return out.astype(np.float32)
    return run


def timed(method, points, repeats):
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = method(points)
        times.append(1000.0 * (time.perf_counter() - start))
    return result, statistics.median(times)


def eval_json(tools, *args):
    out = subprocess.run([os.path.join(tools, "range_nlm_eval"), *args, "--json"], capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError("range_nlm_eval %s: %s" % (" ".join(args), out.stderr))
    return json.loads(out.stdout)


def score_generated(tools, scene, name, result):
    path = os.path.join(scene, "result_%s.pcd" % name)
    range_nlm.write_pcd(path, result)
    m = eval_json(tools, os.path.join(scene, "truth", "frame_0000.pcd"), path)
    return "%.2f / %.2f" % (m["flat_rmse_mm"], m["feature_rmse_mm"])


def score_real(tools, folder, raw_path, name, result):
    path = os.path.join(folder, "result_%s.pcd" % name)
    range_nlm.write_pcd(path, result)
    m = eval_json(tools, "--raw", raw_path, path)
    frame = m["frames"][-1]
    return "%.2f / %.2f" % (frame["interior_rms_mm"], frame["border_rms_mm"])


def frames(tools, work):
    """(label, points, scorer) of every test frame."""
    out = []
    for noise, extra in (("kinect", []), ("tof", [])):
        scene = os.path.join(work, noise)
        subprocess.run([os.path.join(tools, "range_nlm_synth"), "--output-dir", scene, "--noise", noise, "--quiet",
                        *extra], check=True)
        points = range_nlm.read_pcd(os.path.join(scene, "noisy", "frame_0000.pcd"))
        out.append(("generated boxes, %s noise" % noise, points,
                    lambda name, result, scene=scene: score_generated(tools, scene, name, result)))
    tum = os.path.join(ROOT, "data", "depth-images", "tum-fr2-desk-pair")
    depth = range_nlm.read_depth_png(os.path.join(tum, "1_depth.png"))
    points = range_nlm.depth_to_points(depth, range_nlm.read_intrinsics(os.path.join(tum, "intrinsics.txt")))
    for label, raw in (("TUM fr2/desk depth (Kinect v1)", points),
                       ("milk carton PCD (Kinect)", range_nlm.read_pcd(
                           os.path.join(ROOT, "data", "milk_cartoon_all_small_clorox.pcd")))):
        folder = tempfile.mkdtemp(dir=work)
        raw_path = os.path.join(folder, "raw.pcd")
        range_nlm.write_pcd(raw_path, raw)
        out.append((label, raw, lambda name, result, f=folder, r=raw_path: score_real(tools, f, r, name, result)))
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--tools", default=os.path.join(ROOT, "build", "tools"), help="directory of the built tools")
    parser.add_argument("--repeats", type=int, default=3, help="timed calls per method and frame (median)")
    parser.add_argument("--threads", type=int, default=1, help="range_nlm's threads (0 = all cores)")
    args = parser.parse_args()
    methods = [("raw (unfiltered)", lambda p: p),
               ("range_nlm (default)", lambda p: range_nlm.denoise(p, threads=args.threads))]
    methods += [(name, on_rays(f)) for name, f in open3d_methods() + opencv_methods()]
    print("| frame | method | flat / feature RMSE (generated) or interior / border RMS (real), mm | time, ms |")
    print("|---|---|---|---|")
    with tempfile.TemporaryDirectory() as work:
        for label, points, score in frames(args.tools, work):
            for k, (name, method) in enumerate(methods):
                result, ms = timed(method, points, args.repeats)
                timing = "-" if k == 0 else "%.0f" % ms
                print("| %s | %s | %s | %s |" % (label, name, score("m%d" % k, result), timing), flush=True)


if __name__ == "__main__":
    main()
