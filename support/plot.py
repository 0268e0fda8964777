# Renders a drom line plot to PNG with matplotlib (Debian's python3-matplotlib). Compiled into drom
# (support/png_plot.cpp) and run as /usr/bin/python3 - SPEC OUT; reads the JSON spec, writes OUT.
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

spec = json.load(open(sys.argv[1]))
fig, ax = plt.subplots(figsize=(8, 4.8), dpi=110)
for s in spec["series"]:
    style = s.get("style", "-")
    ax.plot(s["x"], s["y"], style, label=s["name"], linewidth=1.4, markersize=3)
for h in spec.get("hlines", []):
    ax.axhline(h["y"], color="0.4", linestyle="--", linewidth=1)
    ax.annotate(h["name"], (1.0, h["y"]), xycoords=("axes fraction", "data"), ha="right", va="bottom", fontsize=8, color="0.3")
if spec.get("log_y"):
    ax.set_yscale("log")
ax.set_title(spec.get("title", ""))
ax.set_xlabel(spec.get("x_label", ""))
ax.set_ylabel(spec.get("y_label", ""))
ax.grid(True, alpha=0.3)
if len(spec["series"]) > 1 or spec.get("hlines"):
    ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(sys.argv[2], format="png")
