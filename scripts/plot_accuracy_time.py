#!/usr/bin/python3
"""Draws accuracy against time per frame from range_nlm_bench --accuracy-time's JSON.

One panel per frame (the generated one and the real one): x the wall time of one call (ms, log
scale), y the frame's metric (mm, smaller is better); range_nlm's presets, PCL's
FastBilateralFilter and MovingLeastSquares settings, the unfiltered input as a dashed line.

  range_nlm_bench --accuracy-time --runs 3 --threads 2 --json-file docs/data/accuracy-time.json
  /usr/bin/python3 scripts/plot_accuracy_time.py docs/data/accuracy-time.json docs/images/accuracy-time.png

Needs matplotlib (Debian: python3-matplotlib).
"""
import argparse
import json
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import FuncFormatter, LogLocator  # noqa: E402

STYLE = {
    "range_nlm": dict(color="tab:blue", marker="o", label="range_nlm presets"),
    "FastBilateral": dict(color="tab:orange", marker="s", label="PCL FastBilateralFilter (one thread)"),
    "MLS": dict(color="tab:green", marker="^", label="PCL MovingLeastSquares, order 2, radius 2 / 3 / 5 cm"),
}


def short(family, setting):
    if family == "range_nlm":
        return setting
    if family == "FastBilateral":  # "sigma_s 5, sigma_r 0.03"
        s, r = (part.split()[-1] for part in setting.split(","))
        return f"σs {s} px, σr {float(r) * 100:g} cm"
    if family == "MLS":  # "order 2, radius 0.02 m"
        return f"{float(setting.split()[-2]) * 100:g} cm"
    return setting


def milliseconds(v, _):
    return f"{v / 1000:g} s" if v >= 1000 else f"{v:g} ms"


def load(path):
    try:
        with open(path) as f:
            data = json.load(f)
    except (OSError, json.JSONDecodeError) as e:
        sys.exit(f"plot_accuracy_time.py: cannot read {path}: {e}")
    if "accuracy_time" not in data:
        sys.exit(f"plot_accuracy_time.py: {path} holds no 'accuracy_time' object "
                 "(write it with range_nlm_bench --accuracy-time --json-file)")
    return data["accuracy_time"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("json", help="range_nlm_bench --accuracy-time --json-file output")
    parser.add_argument("png", help="the plot to write")
    args = parser.parse_args()
    data = load(args.json)
    frames = []
    for row in data["rows"]:
        if row["frame"] not in frames:
            frames.append(row["frame"])
    fig, axes = plt.subplots(1, len(frames), figsize=(6.2 * len(frames), 4.8), squeeze=False)
    for ax, frame in zip(axes[0], frames):
        rows = [r for r in data["rows"] if r["frame"] == frame]
        metric = rows[0]["metric"]
        for family, style in STYLE.items():
            fam = sorted((r for r in rows if r["family"] == family), key=lambda r: r["median_ms"])
            if not fam:
                continue
            xs = [r["median_ms"] for r in fam]
            ys = [r["accuracy_mm"] for r in fam]
            ax.plot(xs, ys, linestyle=":" if family != "range_nlm" else "none", markersize=8, **style)
            for i, r in enumerate(fam):
                text = short(family, r["setting"])
                if r["points_lost"]:
                    text += f" ({r['points_lost']} points lost)"
                # Close points of one family: their labels alternate (beside and below for range_nlm's
                # presets, above and below for the peers' settings).
                ax.annotate(text, (r["median_ms"], r["accuracy_mm"]), textcoords="offset points",
                            xytext=((8, -3) if i % 2 == 0 else (-8, -15)) if family == "range_nlm"
                            else (7, 4 if i % 2 == 0 else -11),
                            fontsize=8, color=style["color"])
        for r in rows:
            if r["family"] == "input":
                ax.axhline(r["accuracy_mm"], color="grey", linestyle="--", linewidth=1)
                ax.annotate(f"unfiltered {r['accuracy_mm']:.2f} mm", (0.01, r["accuracy_mm"]),
                            xycoords=("axes fraction", "data"), xytext=(0, 3), textcoords="offset points",
                            fontsize=8, color="grey")
        ax.set_xscale("log")
        timed = [r["median_ms"] for r in rows if r["median_ms"] is not None]
        decades = math.log10(max(timed) / min(timed))
        ax.xaxis.set_major_locator(LogLocator(base=10, subs=(1.0,) if decades > 2 else (1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(FuncFormatter(milliseconds))
        ax.xaxis.set_minor_formatter(FuncFormatter(lambda v, _: ""))
        ax.set_xlim(min(timed) / 1.6, max(timed) * 3.5)  # room for the labels right of the points
        ax.set_ylim(0, 1.12 * max(r["accuracy_mm"] for r in rows))
        ax.set_xlabel("time per frame (one call, log scale)")
        unit = "flat RMSE against ground truth (mm)" if "ground truth" in metric else "RMS residual to its planes (mm)"
        ax.set_ylabel(unit)
        title = frame if frame.startswith("generated") else f"real: {frame}"
        ax.set_title(title, fontsize=10)
        ax.grid(True, which="major", color="0.88")
        ax.plot([], [], color="grey", linestyle="--", linewidth=1, label="unfiltered input")
    threads = f"{data['threads']} threads" if data["threads"] else f"all {data.get('cpus', '')} cores"
    fig.suptitle(f"Accuracy against time per frame, lower left is better "
                 f"({threads}, median of {data['runs']} runs, {data.get('cpu_model', 'CPU unknown')})", fontsize=10)
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=9, frameon=False)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    fig.savefig(args.png, dpi=110)


if __name__ == "__main__":
    main()
