#!/usr/bin/python3
"""Draws the reliability diagram of the per-point uncertainty from range_nlm_bench
--uncertainty-calibration's JSON: per decile of the predicted standard deviation, the RMS of the
prediction (x) against the RMS of the actual error (y), log-log, one colour per noise model,
filled markers for a frame alone and open ones for the temporal run, the diagonal (calibrated)
with a band of +-25 %.

  range_nlm_bench --uncertainty-calibration --threads 2 --json-file docs/data/uncertainty-calibration.json
  /usr/bin/python3 scripts/plot_reliability.py docs/data/uncertainty-calibration.json docs/images/uncertainty-reliability.png

Needs matplotlib (Debian: python3-matplotlib).
"""
import argparse
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.ticker import FuncFormatter  # noqa: E402

COLOURS = ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown", "tab:pink", "tab:grey"]
SCENE_MARKERS = ["o", "s", "D", "^"]


def load(path):
    try:
        with open(path) as f:
            data = json.load(f)
    except (OSError, json.JSONDecodeError) as e:
        sys.exit(f"plot_reliability.py: cannot read {path}: {e}")
    if "uncertainty_calibration" not in data:
        sys.exit(f"plot_reliability.py: {path} holds no 'uncertainty_calibration' list "
                 "(write it with range_nlm_bench --uncertainty-calibration --json-file)")
    return data["uncertainty_calibration"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("json", help="range_nlm_bench --uncertainty-calibration --json-file output")
    parser.add_argument("png", help="the plot to write")
    args = parser.parse_args()
    rows = load(args.json)
    models = list(dict.fromkeys(r["model"] for r in rows))
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    colour = {m: COLOURS[i % len(COLOURS)] for i, m in enumerate(models)}
    marker = {s: SCENE_MARKERS[i % len(SCENE_MARKERS)] for i, s in enumerate(scenes)}

    fig, ax = plt.subplots(figsize=(9.5, 6.5))
    values = []
    for r in rows:
        bins = [b for b in r["all"] if b["points"] > 0 and b["predicted_mm"] > 0 and b["actual_mm"] > 0]
        xs = [b["predicted_mm"] for b in bins]
        ys = [b["actual_mm"] for b in bins]
        values += xs + ys
        alone = r["run"] == "alone"
        ax.plot(xs, ys, color=colour[r["model"]], marker=marker[r["scene"]], markersize=5,
                linewidth=1.4 if alone else 0.8, linestyle="-" if alone else "--",
                markerfacecolor=colour[r["model"]] if alone else "white", alpha=0.9)
    lo, hi = min(values) / 1.5, max(values) * 1.5
    diagonal = [lo, hi]
    ax.fill_between(diagonal, [v * 0.75 for v in diagonal], [v * 1.25 for v in diagonal], color="0.85",
                    zorder=0)
    ax.plot(diagonal, diagonal, color="black", linewidth=1, zorder=1)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(lo, hi)
    ax.set_ylim(lo, hi)
    ax.set_aspect("equal")
    fmt = FuncFormatter(lambda v, _: f"{v:g}")
    ax.xaxis.set_major_formatter(fmt)
    ax.yaxis.set_major_formatter(fmt)
    ax.set_xlabel("predicted RMS standard deviation per decile (mm)")
    ax.set_ylabel("actual RMS error per decile (mm)")
    ax.set_title("Per-point uncertainty: reliability (on the diagonal = calibrated)", fontsize=11)
    ax.grid(True, which="major", color="0.9")

    handles = [Line2D([], [], color=colour[m], linewidth=2, label=f"noise model {m}") for m in models]
    handles += [Line2D([], [], color="black", marker=marker[s], linestyle="none", label=f"scene {s}") for s in scenes]
    handles += [Line2D([], [], color="black", marker="o", linestyle="-", label="a frame alone"),
                Line2D([], [], color="black", marker="o", markerfacecolor="white", linestyle="--",
                       linewidth=0.8, label="temporal (middle of 3)"),
                Line2D([], [], color="black", linewidth=1, label="calibrated (actual = predicted)"),
                plt.Rectangle((0, 0), 1, 1, color="0.85", label="within 25 %")]
    ax.legend(handles=handles, fontsize=8, loc="upper left", bbox_to_anchor=(1.03, 1.0), borderaxespad=0)
    fig.tight_layout()
    fig.savefig(args.png, dpi=110)


if __name__ == "__main__":
    main()
