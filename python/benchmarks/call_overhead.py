#!/usr/bin/env python3
"""What calling the filter from Python costs over the C++ library, in one process.

    PYTHONPATH=build/python /usr/bin/python3 python/benchmarks/call_overhead.py [--rounds 15] [--threads 0]

On a VGA frame (data/milk_cartoon_all_small_clorox.pcd, 640 x 480), interleaved round by round:
  - C++ filter(): one NonLocalMeansFilter<pcl::PointXYZ>::filter() call on a cloud held in C++,
    timed in C++ (range_nlm._range_nlm._LibraryTimer), as a C++ program calls the library;
  - C++ stream: one TemporalStream::push() of radius 0 on that cloud, timed in C++: the library
    call denoise() makes (and range_nlm_denoise makes for one frame);
  - Python: range_nlm.denoise(points) on the numpy array, timed around the call: parameters
    from keywords, the array read in, the filter, the result array made.
Prints the medians and the overhead of the Python call, in per cent of each C++ median.
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
    timers = {path: _range_nlm._LibraryTimer(points, range_nlm.Parameters(**params), path)
              for path in ("filter", "stream")}
    times = {"filter": [], "stream": [], "python": []}
    for round_ in range(args.rounds + 1):
        measured = {path: timer.run() for path, timer in timers.items()}
        start = time.perf_counter()
        result = range_nlm.denoise(points, **params)
        measured["python"] = 1000.0 * (time.perf_counter() - start)
        if round_ > 0:  # the first round takes the buffers
            for key, ms in measured.items():
                times[key].append(ms)
    same = all(np.array_equal(result.view(np.uint32), timer.output().view(np.uint32)) for timer in timers.values())
    median = {key: statistics.median(values) for key, values in times.items()}
    print("frame %s, %d x %d, threads=%d, %d rounds, medians:" % (os.path.basename(args.frame), points.shape[1],
                                                                 points.shape[0], args.threads, args.rounds))
    print("  C++ NonLocalMeansFilter::filter()  %7.1f ms" % median["filter"])
    print("  C++ TemporalStream::push()         %7.1f ms" % median["stream"])
    print("  Python range_nlm.denoise()         %7.1f ms" % median["python"])
    for key, name in (("filter", "filter()"), ("stream", "TemporalStream::push()")):
        print("overhead of the Python call over %s: %+.1f %%"
              % (name, 100.0 * (median["python"] - median[key]) / median[key]))
    print("results bit-identical: %s" % same)


if __name__ == "__main__":
    main()
