"""The module as Python sees it (issue 43): every class has a repr that shows its key values, and no
signature or docstring shows a C++ type (std::, drom::, Eigen::) or a default without a readable repr.
Objects that need a model or a run are checked where test_drom.py makes them (assert_readable_repr)."""
import inspect
import os
import pathlib
import pydoc
import re
import shutil
import subprocess
import sys

import pytest

import drom

CPP_NAMES = re.compile(r"std::|drom::|Eigen::|nlohmann::|pybind11::|object at 0x")


def classes():
    for module in (drom, drom.machine):
        for name, value in vars(module).items():
            if inspect.isclass(value) and not issubclass(value, BaseException):
                yield f"{module.__name__}.{name}", value


def assert_readable_repr(obj, **shown):
    """repr(obj) is Class(key=value, ...), with each of `shown` as repr shows it."""
    text = repr(obj)
    assert re.fullmatch(rf"{type(obj).__name__}\(\w+=.*\)", text, re.DOTALL), text
    assert "object at 0x" not in text, text
    for key, value in shown.items():
        assert f"{key}={value!r}" in text, (key, text)
    return text


def documented():
    """(where, text) for every docstring the module has: functions, classes, methods, properties."""
    for module in (drom, drom.machine):
        yield module.__name__, module.__doc__ or ""
        for name, value in vars(module).items():
            if callable(value) and not inspect.isclass(value):
                yield f"{module.__name__}.{name}", value.__doc__ or ""
    for where, cls in classes():
        yield where, cls.__doc__ or ""
        for name, value in vars(cls).items():
            if isinstance(value, property):
                for accessor in (value.fget, value.fset):
                    if accessor is not None:
                        yield f"{where}.{name}", accessor.__doc__ or ""
            elif callable(value) or isinstance(value, staticmethod):
                yield f"{where}.{name}", getattr(cls, name).__doc__ or ""


def test_every_class_defines_its_repr():
    found = dict(classes())
    assert {"drom.Case", "drom.LightModel", "drom.Predictor", "drom.PredictorSettings", "drom.ProfileReport", "drom.ClosedLoopInputs",
            "drom.LoopStep", "drom.LoopMachine", "drom.machine.Machine"} <= set(found)
    missing = [where for where, cls in found.items() if "__repr__" not in vars(cls)]
    assert not missing, f"classes with the default <... object at 0x...> repr: {missing}"


def test_reprs_show_the_key_values():
    case = drom.load_case(None, ["mesh.nx=12"])
    assert_readable_repr(case, name=case.name, origin=case.origin, nx=12, ny=case.ny, run_scale=case.run_scale)
    settings = drom.PredictorSettings()
    settings.noise_sd = 0.02
    text = assert_readable_repr(settings, noise_sd=0.02, learning_window=5, use_stock_top=True, max_offset=-1.0)
    assert text.count("=") == 12
    machine = drom.machine.load("ucp710_like", ["setup.tool_length=80"])
    assert_readable_repr(machine, name="ucp710_like", kinematics="table_table", rotary_axes="AC", tool_length=80.0)


def test_no_cpp_type_in_a_signature_or_docstring():
    bad = [(where, CPP_NAMES.findall(text)) for where, text in documented() if CPP_NAMES.search(text)]
    assert not bad, bad
    for module in (drom, drom.machine):  # what help() shows, the same texts laid out by pydoc
        text = pydoc.render_doc(module, renderer=pydoc.plaintext)
        assert not CPP_NAMES.search(text), sorted(set(CPP_NAMES.findall(text)))


def test_every_function_has_named_arguments():
    """help() shows arg0, arg1 for arguments bound without py::arg. Properties aside: their accessors' one
    argument is the object (pybind11 calls a lambda getter's arg0, a setter's value arg0)."""
    unnamed = [where for where, text in documented() if re.search(r"\barg\d\b", text) and not isinstance(attribute(where), property)]
    assert not unnamed, unnamed


def attribute(where):
    """drom.X.y -> the class attribute (a property stays a property), drom.f -> the function."""
    value, names = drom, where.split(".")[1:]
    for i, name in enumerate(names):
        value = vars(value)[name] if inspect.isclass(value) and i == len(names) - 1 else getattr(value, name)
    return value


def test_cmake_install_puts_the_module_where_docs_python_md_says():
    """cmake --install <build> --prefix P --component python: P/lib/python3.X/dist-packages, importable with PYTHONPATH."""
    build = pathlib.Path(drom.__file__).resolve().parents[1]  # ctest's PYTHONPATH is <build>/python
    if not (build / "CMakeCache.txt").exists():
        pytest.skip(f"drom is not imported from a CMake build's python/ folder: {drom.__file__}")
    prefix = pathlib.Path(os.environ["DROM_TEST_DIR"]) / "install_prefix"
    shutil.rmtree(prefix, ignore_errors=True)
    subprocess.run(["cmake", "--install", str(build), "--prefix", str(prefix), "--component", "python"], check=True, capture_output=True)
    site = prefix / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}" / "dist-packages"
    assert [p.name for p in prefix.rglob("*") if p.is_file()] == [pathlib.Path(drom.__file__).name]
    env = dict(os.environ, PYTHONPATH=str(site))
    run = subprocess.run([sys.executable, "-c", "import drom; print(drom.__file__, drom.__version__)"], env=env, capture_output=True, text=True, check=True)
    assert run.stdout.split() == [str(site / pathlib.Path(drom.__file__).name), drom.__version__]
