"""drom.machine from Python: the same kinematics, feed prediction and post-processor as the C++ library."""
import math
import subprocess

import numpy as np
import pytest

import drom


def saddle_pass(tilt_deg, step=0.1):
    """A pass along x over z = (x^2 - y^2) / 200 at y = 0, tilted across the feed (the seed's oracle)."""
    c, t = 100.0, math.radians(tilt_deg)
    rows = []
    for x in np.arange(-30, 30 + 1e-9, step):
        n = np.array([-x / c, 0, 1]) / math.sqrt(1 + (x / c) ** 2)
        axis = math.cos(t) * n + math.sin(t) * np.array([0, 1, 0])
        rows.append([x, 0, x * x / (2 * c), *(axis / np.linalg.norm(axis)), 3000.0])
    rows[0][6] = 0
    return np.array(rows)


def test_shipped_machines_and_bad_keys():
    assert set(drom.machine.shipped()) == {"vmc_3axis", "bridge_3axis", "ucp710_like", "gantry_head_ac"}
    m = drom.machine.load("ucp710_like")
    assert m.kinematics == "table_table" and m.rotary_axes == "AC"
    with pytest.raises(drom.InputError, match="axes.X.velocity"):
        drom.machine.load("ucp710_like", ["axes.X.velocity=-1"])


def test_inverse_kinematics_from_numpy():
    m = drom.machine.load("ucp710_like")
    poses = saddle_pass(5)[:, :6]
    r = drom.machine.inverse(m, poses)
    assert r["joints"].shape == (len(poses), 5)
    assert not r["violations"]
    assert np.all(np.abs(np.diff(r["joints"][:, 4])) < 10)  # C continuous (degrees)


def test_the_c_limited_feed_rises_with_the_tilt():
    m = drom.machine.load("ucp710_like", ["control.junction=smooth", "control.junction_tolerance_rotary=0.05", "control.interpolation_cycle=0.001"])
    slowest = {}
    for tilt in (1, 5):
        p = drom.machine.predict(m, saddle_pass(tilt))
        s = np.cumsum(p["block_length"])
        middle = (s > 10) & (s < s[-1] - 10)  # away from the pass's ramps
        slowest[tilt] = p["block_min_feed"][middle].min()
        assert p["cycle_time"] > p["programmed_time"]
    assert slowest[5] / slowest[1] == pytest.approx(5.0, rel=0.1)


def test_the_post_processor_writes_what_linuxcnc_reads(tmp_path):
    m = drom.machine.load("ucp710_like")
    program = drom.machine.post(m, saddle_pass(3, step=1.0), "saddle")
    assert "G93" in program and " A" in program and " C" in program
    # Ready to run: the spindle started (300 m/min on a 10 mm tool: 9 500 rev/min), the first move a
    # retract in Z alone, the end M5 M30 %.
    drilled = drom.machine.post(m, saddle_pass(3, step=1.0), "saddle", tool=4, tool_diameter=10.0)
    lines = drilled.splitlines()
    assert "T4 M6" in lines and "S9500 M3" in lines and lines[-3:] == ["M5", "M30", "%"]
    first_move = next(line for line in lines if line.startswith("G0"))
    assert first_move.split()[1:] == [first_move.split()[1]] and first_move.split()[1].startswith("Z")
    path = tmp_path / "saddle.ngc"
    path.write_text(program)
    s = drom.machine.check_program(path, "ucp710_like", tmp_path / "out")
    # The pass's 60 CL points (a rapid to the first, 59 cuts), led in by the safe start (Z up, A and C,
    # X and Y, Z down) and closed by the retract: 65 blocks.
    assert s["blocks"] == 65 and s["travel_violations"] == []
    with pytest.raises(drom.InputError, match="no rotary axis"):
        drom.machine.check_program(path, "vmc_3axis", tmp_path / "out3")
