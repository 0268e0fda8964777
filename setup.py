"""pip install . for the drom Python module (docs/python.md): Debian's setuptools runs CMake on this tree
and builds only the module's target, drom_python, and the libraries it links; the module it builds
(python/drom*.so) becomes the wheel's only file.

    /usr/bin/python3 -m pip install --no-build-isolation --no-index --target DIR .

Where the build goes (pip builds in the source tree):
  DROM_PIP_BUILD   setuptools' build folder, with the CMake build in its cmake/ (default: build-pip/,
                   which .gitignore ignores as every build*/); a second install rebuilds incrementally
  DROM_BUILD_DIR   a CMake build folder to build the module in instead, new or configured already
                   (build/ of scripts/build reuses its compiled libraries)
  DROM_CMAKE_ARGS  more arguments for CMake's configure step (a new build folder only)
The module is built for the Python running pip (Python3_EXECUTABLE); use Debian's /usr/bin/python3, whose
numpy the module uses (python3-numpy; not a declared dependency, so pip never tries to download it).
"""
import os
import pathlib
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent
BUILD_BASE = pathlib.Path(os.environ.get("DROM_PIP_BUILD") or ROOT / "build-pip").resolve()


def project_version():
    match = re.search(r"project\(drom VERSION ([0-9.]+)", (ROOT / "CMakeLists.txt").read_text(encoding="utf-8"))
    if not match:
        raise RuntimeError("CMakeLists.txt: no 'project(drom VERSION x.y.z'")
    return match.group(1)


class CMakeBuild(build_ext):
    """Builds the extension with the project's CMake (python/CMakeLists.txt) instead of setuptools' compiler."""

    def build_extension(self, ext):
        build_dir = pathlib.Path(os.environ.get("DROM_BUILD_DIR") or BUILD_BASE / "cmake").resolve()
        if not (build_dir / "CMakeCache.txt").exists():
            configure = ["cmake", "-S", str(ROOT), "-B", str(build_dir), "-DCMAKE_BUILD_TYPE=Release", "-DDROM_BUILD_TESTS=OFF",
                         "-DDROM_BUILD_BENCH=OFF", f"-DPython3_EXECUTABLE={sys.executable}"]
            if shutil.which("ninja"):
                configure += ["-G", "Ninja"]
            configure += shlex.split(os.environ.get("DROM_CMAKE_ARGS", ""))
            self.announce(" ".join(configure), level=2)
            subprocess.run(configure, check=True)
        build = ["cmake", "--build", str(build_dir), "--target", "drom_python"]
        if not os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL"):
            build += ["-j", str(os.cpu_count() or 1)]
        self.announce(" ".join(build), level=2)
        subprocess.run(build, check=True)

        built = build_dir / "python" / ("drom" + sysconfig.get_config_var("EXT_SUFFIX"))
        if not built.exists():
            raise RuntimeError(f"{built} was not built: {build_dir} builds the module for another Python than {sys.executable} "
                               "(its CMakeCache.txt's Python3_EXECUTABLE)")
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built, target)


BUILD_BASE.mkdir(parents=True, exist_ok=True)
setup(
    version=project_version(),
    packages=[],
    py_modules=[],
    ext_modules=[Extension("drom", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": str(BUILD_BASE)}, "egg_info": {"egg_base": str(BUILD_BASE)}},
    zip_safe=False,
)
