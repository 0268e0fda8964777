"""The drom Python module (issue 25): cases, the offline job, the reduction, the predictor from numpy,
the closed loop driven from Python, file-format versions. Run by ctest (Python.pytest) with
PYTHONPATH on the build's python/ folder; DROM_BINARY is the drom command, DROM_TEST_DIR a scratch
folder."""
import os
import pathlib
import shutil
import signal
import subprocess
import threading
import time

import numpy as np
import pytest

import drom
from test_api import assert_readable_repr

BINARY = os.environ["DROM_BINARY"]
SCRATCH = pathlib.Path(os.environ["DROM_TEST_DIR"])
# The coarse flat plate of the end-to-end tests (tests/apps/run_command_test.cpp).
COARSE = ["mesh.nx=10", "mesh.ny=10", "path.station_spacing=300", "removal.voxel_size=1.0",
          "clamps.0.box=[0,100,0,100]", "clamps.1.box=[900,1000,0,100]",
          "clamps.2.box=[0,100,900,1000]", "clamps.3.box=[900,1000,900,1000]"]


def fresh(name):
    path = SCRATCH / name
    shutil.rmtree(path, ignore_errors=True)
    return path


def test_a_bad_case_raises_with_its_file_line_and_key():
    path = fresh("cases") / "typo.toml"
    path.parent.mkdir(parents=True)
    text = drom.load_case().resolved_toml.replace("[material]", "[material]\nyoung_modulu = 7e4")
    path.write_text(text)
    with pytest.raises(drom.InputError) as error:
        drom.load_case(str(path))
    message = str(error.value)
    assert str(path) in message and "material.young_modulu" in message
    line = text.splitlines().index("young_modulu = 7e4") + 1
    assert f":{line}:" in message
    with pytest.raises(ValueError):  # InputError is a ValueError
        drom.load_case(None, ["mesh.nx=-3"])


@pytest.fixture(scope="module")
def coarse_job():
    """The coarse flat plate's offline job, run once through Python."""
    out = fresh("offline_python")
    return out, drom.run_offline(drom.load_case(None, COARSE), str(out))


def test_the_offline_job_writes_the_bytes_drom_offline_writes(coarse_job):
    out, result = coarse_job
    assert result["finished"] and result["stations"] == result["stations_saved"] > 0
    assert result["summary"]["command"] == "offline"
    reference = fresh("offline_command")
    subprocess.run([BINARY, "offline", "--quiet", "--out", str(reference)] + sum((["--set", s] for s in COARSE), []), check=True)
    assert (out / "database.h5").read_bytes() == (reference / "database.h5").read_bytes()


def test_progress_stops_a_job_that_then_resumes_and_the_gil_is_free_meanwhile():
    case = drom.load_case(None, COARSE)
    out = fresh("offline_stopped")
    seen = []
    ticks = [0]
    running = [True]

    def tick():
        while running[0]:
            ticks[0] += 1
            time.sleep(0.001)

    side = threading.Thread(target=tick)
    side.start()
    result = drom.run_offline(case, str(out), threads=1, progress=lambda saved, total: seen.append(saved) or saved < 4)
    running[0] = False
    side.join()
    assert not result["finished"] and result["stations_saved"] == 4 and seen[-1] == 4
    assert ticks[0] > 100, "the job held the GIL: the other Python thread barely ran"
    assert drom.run_offline(case, str(out), resume=True)["finished"]

    def failing(saved, total):
        raise RuntimeError("stop from Python")

    with pytest.raises(RuntimeError, match="stop from Python"):
        drom.run_offline(case, str(fresh("offline_raising")), progress=failing)


def test_ctrl_c_stops_the_offline_job_within_a_second_and_resume_finishes_it_to_the_same_bytes(coarse_job):
    """Issue 44: a KeyboardInterrupt (SIGINT, as Ctrl-C sends it) ends drom.run_offline after the
    stations in progress, and resume=True then writes the bytes an uninterrupted job writes."""
    case = drom.load_case(None, COARSE)
    out = fresh("offline_interrupted")
    sent = []

    def progress(saved, total):
        if saved == 2 and not sent:
            sent.append(time.monotonic())
            os.kill(os.getpid(), signal.SIGINT)
        return True

    with pytest.raises(KeyboardInterrupt):
        drom.run_offline(case, str(out), threads=1, progress=progress)
    stopped_after = time.monotonic() - sent[0]
    assert stopped_after < 1.0, f"the job went on for {stopped_after:.2f} s after Ctrl-C"
    stations = coarse_job[1]["stations"]
    saved = len(list((out / ".checkpoint").glob("station_*.bin")))
    assert 2 <= saved < stations, f"{saved} of {stations} stations saved: the interrupt did not stop the job midway"
    assert not (out / "database.h5").exists() and not (out / "summary.json").exists()
    with pytest.raises(drom.InputError, match="pass --resume"):
        drom.run_offline(case, str(out))  # a plain rerun does not take the interrupted job's stations
    result = drom.run_offline(case, str(out), resume=True)
    assert result["finished"] and result["stations_saved"] == stations
    assert (out / "database.h5").read_bytes() == (coarse_job[0] / "database.h5").read_bytes()


def test_ctrl_c_stops_a_closed_loop_run_within_a_second():
    """The same for drom.run_closed_loop, wherever the signal lands: its stages, the reduction or
    the loop (from another thread, as a terminal's Ctrl-C comes from outside). The loop is found by
    its start, not by a delay: the reduced model's summary is written, and the loop runs some 10 s."""
    case = drom.load_run_case(None, COARSE)
    for where in ("stages", "loop"):
        out = fresh(f"loop_interrupted_{where}")
        sent = []
        cancelled = threading.Event()

        def interrupt():
            if where == "loop":
                while not (out / "model" / "summary.json").exists():
                    if cancelled.wait(0.01):
                        return
                if cancelled.wait(1.0):
                    return
            elif cancelled.wait(0.3):
                return
            sent.append(time.monotonic())
            os.kill(os.getpid(), signal.SIGINT)

        watcher = threading.Thread(target=interrupt, daemon=True)
        watcher.start()
        try:
            with pytest.raises(KeyboardInterrupt):
                drom.run_closed_loop(case, str(out))
        finally:
            cancelled.set()
            watcher.join()
        assert sent, "the run ended before the signal"
        stopped_after = time.monotonic() - sent[0]
        assert stopped_after < 1.0, f"drom run went on for {stopped_after:.2f} s after Ctrl-C in its {where}"
        assert not (out / "summary.json").exists()
        if where == "loop":
            assert not (out / "passes.csv").exists(), "the signal was meant to land in the loop"


@pytest.fixture(scope="module")
def coarse_loop():
    """drom run on the coarse flat plate, once: its case, folder and summary."""
    case = drom.load_run_case(None, COARSE)
    out = fresh("loop")
    return case, out, drom.run_closed_loop(case, str(out))


def test_a_predictor_fed_from_numpy_reproduces_drom_runs_corrected_path_error(coarse_loop):
    case, out, summary = coarse_loop
    inputs = drom.prepare_closed_loop(case, str(out))  # the stages drom run left under out
    model = inputs.model
    predictor = drom.Predictor(model, drom.predictor_settings(case, model))
    machine = drom.LoopMachine(inputs, case)
    assert_readable_repr(inputs)
    assert_readable_repr(machine, steps=machine.steps, applied=0.0)
    assert_readable_repr(predictor, learned=False)
    worst = 0.0
    for k in range(machine.steps + 1):
        step = machine.advance(k)
        if step.on_target and step.pass_ >= 3:
            worst = max(worst, abs(step.error))
        if step.refresh:
            offset = predictor.tool_offset(step.setpoint_time)
            machine.command(offset)
            predictor.record_offset(step.believed_time, offset)
        if step.scan:
            points = machine.scan()
            assert points.shape[1] == 3 and points.dtype == np.float64
            report = predictor.add_profile(step.believed_time, step.believed_tip, machine.applied, points)
    assert_readable_repr(step, index=step.index, pass_=step.pass_, refresh=step.refresh, scan=step.scan)
    assert_readable_repr(report, used=report.used, rejected=report.rejected)
    expected = summary["headline"]["path_error_corrected_max_from_pass3_mm"]
    assert worst == pytest.approx(expected, rel=1e-9, abs=1e-15)
    assert predictor.learned
    estimate = predictor.estimate()
    assert estimate["alpha"].shape == (model.rank,)


def test_points_must_be_n_by_3(coarse_job):
    model = drom.reduce_database(str(coarse_job[0] / "database.h5"))
    predictor = drom.Predictor(model)
    with pytest.raises(drom.InputError, match=r"\(N, 3\) array"):
        predictor.add_profile(1.0, [0.0, 0.0, 0.0], 0.0, np.zeros((10, 2)))
    report = predictor.add_profile(1.0, [0.0, 0.0, 0.0], 0.0, np.full((5, 3), np.nan))
    assert report.invalid + report.outside == 5
    assert_readable_repr(report, used=0, invalid=report.invalid, outside=report.outside)
    text = assert_readable_repr(model, rank=model.rank, error_bound=model.error_bound, has_top=model.has_top)
    assert f"path=<array of shape {model.path.shape!r}>" in text


def test_a_model_of_another_format_version_or_truncated_is_refused(coarse_job):
    folder = fresh("models")
    model = drom.reduce_database(str(coarse_job[0] / "database.h5"), out=str(folder / "model.h5"))
    assert model.rank > 0 and model.error_bound > 0
    reread = drom.LightModel.read(str(folder / "model.h5"))
    assert reread.rank == model.rank
    truncated = folder / "truncated.h5"
    truncated.write_bytes((folder / "model.h5").read_bytes()[:4096])
    with pytest.raises(drom.InputError, match=str(truncated)):
        drom.LightModel.read(str(truncated))
    # h5py reads the sealed file (the seal is HDF5's user block), but a file changed outside drom is
    # refused before libhdf5 reads it (docs/robustness.md); another format version's refusal is
    # tests/reduce/light_model_test.cpp's.
    h5py = pytest.importorskip("h5py")
    with h5py.File(folder / "model.h5", "r") as f:
        assert f.attrs["format_version"] == 3.0
    edited = folder / "edited.h5"
    shutil.copy(folder / "model.h5", edited)
    with h5py.File(edited, "r+") as f:
        f.attrs["format_version"] = 4.0
    # h5py may rewrite the attribute in place or append it: either way the seal refuses the file.
    with pytest.raises(drom.InputError, match="differ from what drom wrote|were added after it was written"):
        drom.LightModel.read(str(edited))


@pytest.mark.heavy
def test_a_study_sweeps_a_loop_parameter(coarse_loop):
    case, run_folder, _ = coarse_loop
    out = fresh("study")
    study = drom.run_study(case, "noise", [0.0, 0.05], str(out))
    assert [row["value"] for row in study["rows"]] == [0.0, 0.05]
    with pytest.raises(drom.InputError, match="--param: expected one of"):
        drom.run_study(case, "colour", [1.0], str(out))
    # A folder holds one command's outputs: a study into the run's folder is refused, the run's kept.
    with pytest.raises(drom.InputError, match="it holds the outputs of drom run"):
        drom.run_study(case, "noise", [0.0], str(run_folder))
    assert (run_folder / "passes.csv").exists() and (run_folder / "summary.json").exists()


@pytest.mark.heavy
def test_the_notebook_example_runs_and_plots(coarse_loop):
    out = coarse_loop[1]  # drom run's stages there are reused
    script = pathlib.Path(__file__).resolve().parents[2] / "examples" / "python" / "flat_plate.py"
    run = subprocess.run([os.environ.get("PYTHON", "/usr/bin/python3"), str(script), "--coarse", "--out", str(out)], capture_output=True, text=True,
                         env=dict(os.environ), check=True)
    assert "path error with correction, max from pass 3" in run.stdout
    assert (out / "python_flat_plate.png").stat().st_size > 10000
