#!/usr/bin/env python3
"""Python overhead of drom.Predictor.add_profile (issue 25; goal under 5 %).

The same laser profiles (800 points each, read by drom run's simulated sensor on the coarse flat
plate) are fed to two fresh predictors in the same process: one from a Python loop calling
add_profile with an (800, 3) numpy array, one from a C++ loop (drom._add_profiles_in_cpp). Rounds
alternate; the medians are compared. Prints JSON.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_overhead.py [--out DIR] [--rounds N]
"""
import argparse
import json
import platform
import statistics
import time

import drom
import numpy as np

COARSE = ["mesh.nx=10", "mesh.ny=10", "path.station_spacing=300", "removal.voxel_size=1.0",
          "clamps.0.box=[0,100,0,100]", "clamps.1.box=[900,1000,0,100]",
          "clamps.2.box=[0,100,900,1000]", "clamps.3.box=[900,1000,900,1000]"]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", default="out/bench_python", help="drom run's stages (computed once, then reused)")
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    case = drom.load_run_case(None, COARSE)
    inputs = drom.prepare_closed_loop(case, args.out)
    model = inputs.model
    settings = drom.predictor_settings(case, model)

    # The profiles drom run's sensor reads, collected once (no offsets applied).
    machine = drom.LoopMachine(inputs, case)
    times, tips, offsets, profiles = [], [], [], []
    for k in range(machine.steps + 1):
        step = machine.advance(k)
        if step.scan:
            times.append(step.believed_time)
            tips.append(list(step.believed_tip))
            offsets.append(0.0)
            profiles.append(machine.scan())
    points = profiles[0].shape[0]

    python_s, cpp_s = [], []
    for _ in range(args.rounds):
        predictor = drom.Predictor(model, settings)
        start = time.perf_counter()
        for t, tip, offset, profile in zip(times, tips, offsets, profiles):
            predictor.add_profile(t, tip, offset, profile)
        python_s.append(time.perf_counter() - start)
        cpp_s.append(drom._add_profiles_in_cpp(drom.Predictor(model, settings), times, tips, offsets, profiles))
    python_us = 1e6 * statistics.median(python_s) / len(times)
    cpp_us = 1e6 * statistics.median(cpp_s) / len(times)

    # The call's own cost, nearly alone: profiles whose 800 points all read nothing (NaN) are dropped
    # at once, so what is left is the call, the array's mapping and the GIL's release.
    blank = [np.full((points, 3), np.nan)] * len(times)
    python_blank, cpp_blank = [], []
    for _ in range(args.rounds):
        predictor = drom.Predictor(model, settings)
        start = time.perf_counter()
        for t, tip, offset, profile in zip(times, tips, offsets, blank):
            predictor.add_profile(t, tip, offset, profile)
        python_blank.append(time.perf_counter() - start)
        cpp_blank.append(drom._add_profiles_in_cpp(drom.Predictor(model, settings), times, tips, offsets, blank))
    blank_python_us = 1e6 * statistics.median(python_blank) / len(times)
    blank_cpp_us = 1e6 * statistics.median(cpp_blank) / len(times)
    print(json.dumps({
        "benchmark": "Predictor.add_profile from Python against the same calls from C++",
        "profiles": len(times), "points_per_profile": points, "rounds": args.rounds,
        "python_us_per_call": round(python_us, 2), "cpp_us_per_call": round(cpp_us, 2),
        "overhead_percent": round(100 * (python_us / cpp_us - 1), 2), "goal_percent": 5,
        "python_rounds_s": python_s, "cpp_rounds_s": cpp_s,
        "call_alone": {"python_us_per_call": round(blank_python_us, 3), "cpp_us_per_call": round(blank_cpp_us, 3),
                       "python_minus_cpp_us": round(blank_python_us - blank_cpp_us, 3),
                       "as_percent_of_a_real_call": round(100 * (blank_python_us - blank_cpp_us) / cpp_us, 2)},
        "machine": {"cpu": platform.processor() or platform.machine(), "python": platform.python_version()},
    }, indent=2))


if __name__ == "__main__":
    main()
