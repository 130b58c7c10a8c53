#!/usr/bin/env python3
"""What calling the filter from Python costs over the C++ library, in one process.

    PYTHONPATH=build/python /usr/bin/python3 python/benchmarks/call_overhead.py [--rounds 15] [--threads 0]

On a VGA frame (data/milk_cartoon_all_small_clorox.pcd, 640 x 480), interleaved round by round:
  - C++: one NonLocalMeansFilter<pcl::PointXYZ>::filter() call on a cloud held in C++, timed in
    C++ (range_nlm._range_nlm._LibraryTimer), as a C++ program calls the library;
  - Python: range_nlm.denoise(points) on the numpy array, timed around the call: parameters
    from keywords, the array read in, the filter, the result array made.
Prints the medians and the overhead of the Python call, in per cent of the C++ median.
"""

import argparse
import os
import statistics
import time

import numpy as np

import range_nlm
from range_nlm import _range_nlm

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--threads", type=int, default=0, help="the filter's threads (0 = all)")
    parser.add_argument("--frame", default=os.path.join(ROOT, "data", "milk_cartoon_all_small_clorox.pcd"))
    args = parser.parse_args()
    points = range_nlm.read_pcd(args.frame)
    params = {"threads": args.threads}
    timer = _range_nlm._LibraryTimer(points, range_nlm.Parameters(**params))
    cpp, py = [], []
    for round_ in range(args.rounds + 1):
        cpp_ms = timer.run()
        start = time.perf_counter()
        result = range_nlm.denoise(points, **params)
        py_ms = 1000.0 * (time.perf_counter() - start)
        if round_ > 0:  # the first round takes the buffers
            cpp.append(cpp_ms)
            py.append(py_ms)
    same = np.array_equal(result.view(np.uint32), timer.output().view(np.uint32))
    c, p = statistics.median(cpp), statistics.median(py)
    print("frame %s, %d x %d, threads=%d, %d rounds" % (os.path.basename(args.frame), points.shape[1],
                                                        points.shape[0], args.threads, args.rounds))
    print("C++ filter(): median %.1f ms" % c)
    print("Python denoise(): median %.1f ms" % p)
    print("overhead: %+.1f %% (results bit-identical: %s)" % (100.0 * (p - c) / c, same))


if __name__ == "__main__":
    main()
