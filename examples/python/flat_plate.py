#!/usr/bin/env python3
# %% [markdown]
# # The flat plate's closed loop, from Python
#
# drom's main job (`drom run`) on the seed's flat plate (§3.5.2), driven from Python: the offline
# snapshots, the light model, the truth, then the loop with and without correction. The headline
# figures come back as a dict; the per-pass errors are plotted with matplotlib.
#
#     PYTHONPATH=build/python /usr/bin/python3 examples/python/flat_plate.py            # quick scale, ~2 min
#     PYTHONPATH=build/python /usr/bin/python3 examples/python/flat_plate.py --coarse   # a 10 x 10 mesh, ~30 s
#
# Cells are marked `# %%`: open the file in Jupyter (jupytext) or VS Code to run them one by one.

# %%
import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import drom

parser = argparse.ArgumentParser()
parser.add_argument("--coarse", action="store_true", help="a 10 x 10 mesh and 300 mm between stations")
parser.add_argument("--out", default="out/python_flat_plate")
args = parser.parse_args()
out = pathlib.Path(args.out)

# %% [markdown]
# ## 1. The case
# The embedded flat plate (cases/flat_plate.toml) at its quick scale; `--set` overrides go in the list.

# %%
overrides = []
if args.coarse:
    overrides = ["mesh.nx=10", "mesh.ny=10", "path.station_spacing=300", "removal.voxel_size=1.0",
                 "clamps.0.box=[0,100,0,100]", "clamps.1.box=[900,1000,0,100]",
                 "clamps.2.box=[0,100,900,1000]", "clamps.3.box=[900,1000,900,1000]"]
case = drom.load_run_case(None, overrides)
print(case)

# %% [markdown]
# ## 2. The closed loop
# Stages already under `out` are reused while their case is unchanged, so a second run costs the loop
# alone.

# %%
summary = drom.run_closed_loop(case, str(out))
h = summary["headline"]
print(f"path error without correction, max        {h['path_error_uncorrected_max_mm']:.4f} mm")
print(f"learned during pass                         {h['learned_during_pass']}")
print(f"path error with correction, max from pass 3 {h['path_error_corrected_max_from_pass3_mm']:.2e} mm (target {case.path_tolerance:g})")
print(f"final-shape max error, end of pass {case.shape_pass}      {h['final_shape_max_error_end_of_target_pass_mm']:.4f} mm (target {case.shape_tolerance:g})")
print(f"final-shape max error, end                  {h['final_shape_max_error_end_mm']:.4f} mm")

# %% [markdown]
# ## 3. Per pass: the path error with and without correction, and the final-shape prediction

# %%
with_c = summary["corrected"]["passes"]
without = summary["uncorrected"]["passes"]
passes = [p["pass"] for p in with_c]
fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
a.semilogy(passes, [p["max_abs_error_mm"] for p in without], "x--", label="without correction")
a.semilogy(passes, [max(p["max_abs_error_mm"], 1e-7) for p in with_c], "o-", label="with correction")
a.axhline(case.path_tolerance, color="gray", lw=0.8, label="path tolerance")
a.set(xlabel="pass", ylabel="max |path error| (mm)", title="Tool altitude error")
a.legend()
b.semilogy(passes, [p["final_shape_max_error_mm"] for p in with_c], "s-", label="max error")
b.semilogy(passes, [p["final_shape_rms_error_mm"] for p in with_c], "^-", label="RMS error")
b.axhline(case.shape_tolerance, color="gray", lw=0.8, label="shape tolerance")
b.set(xlabel="pass", ylabel="mm", title="Final shape predicted at each pass's end")
b.legend()
fig.suptitle(f"{case.name}: drom run from Python")
fig.tight_layout()
png = out / "python_flat_plate.png"
fig.savefig(png, dpi=110)
print(f"plot: {png}")
