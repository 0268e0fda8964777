# Renders a drom line plot to PNG with matplotlib (Debian's python3-matplotlib). Compiled into drom
# (support/png_plot.cpp) and run as /usr/bin/python3 - SPEC OUT; reads the JSON spec, writes OUT.
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

spec = json.load(open(sys.argv[1]))
fig, ax = plt.subplots(figsize=(8, 4.8) if "map" not in spec else (7, 6), dpi=110)
if "map" in spec:
    m = spec["map"]
    values = [[v if v is not None else float("nan") for v in row] for row in m["values"]]
    image = ax.imshow(values, origin="lower", extent=(m["x0"], m["x1"], m["y0"], m["y1"]), cmap=m.get("cmap", "viridis"), aspect="equal")
    fig.colorbar(image, ax=ax, label=m.get("label", ""))
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
if "map" not in spec:
    ax.grid(True, alpha=0.3)
if len(spec["series"]) > 1 or (spec.get("hlines") and spec["series"]):
    ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(sys.argv[2], format="png")
