"""pip install . (docs/python.md): Debian's pip and setuptools, no index, build the module with CMake and
install it into a folder, where it imports and runs. Marked pip_install (and heavy). ctest runs it twice:
Python.pip_install (label heavy) builds in the test's own build folder (DROM_PIP_REUSE_BUILD), already
compiled, so it checks pip, setup.py, the wheel and the installed module in seconds;
Python.pip_install_from_scratch (label slow) compiles the module and its libraries from nothing, as a
user's first `pip install .` does (about 20 min on 2 cores)."""
import json
import os
import pathlib
import shutil
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.mark.heavy
@pytest.mark.pip_install
def test_pip_install_builds_a_module_that_imports_and_runs():
    scratch = pathlib.Path(os.environ["DROM_TEST_DIR"]) / "pip_install"
    shutil.rmtree(scratch, ignore_errors=True)
    scratch.mkdir(parents=True)
    target = scratch / "site"
    env = dict(os.environ, DROM_PIP_BUILD=str(scratch / "build"))  # setuptools' folder, outside the source tree
    env.pop("DROM_BUILD_DIR", None)
    env.pop("PYTHONPATH", None)
    reuse = os.environ.get("DROM_PIP_REUSE_BUILD")
    if reuse:
        env["DROM_BUILD_DIR"] = reuse
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-build-isolation", "--no-index", "--target", str(target), str(ROOT)], env=env,
                   check=True, cwd=scratch)
    assert ((pathlib.Path(reuse) if reuse else scratch / "build" / "cmake") / "CMakeCache.txt").exists()
    assert not (ROOT / "drom.egg-info").exists()
    built = list(target.glob("drom*.so"))
    assert len(built) == 1 and list(target.glob("drom-*.dist-info"))

    env = dict(os.environ, PYTHONPATH=str(target))
    script = ("import json, drom, numpy; m = drom.machine.load('vmc_3axis'); "
              "joints = drom.machine.inverse(m, numpy.array([[1.0, 2, 3, 0, 0, 1]]))['joints']; "
              "print(json.dumps({'file': drom.__file__, 'repr': repr(m), 'joints': joints.tolist()}))")
    run = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True, cwd=scratch)
    result = json.loads(run.stdout)
    assert pathlib.Path(result["file"]).parent == target  # the installed module, not the build's
    assert result["repr"].startswith("Machine(name='vmc_3axis'")
    assert len(result["joints"]) == 1 and len(result["joints"][0]) == 3
