"""pytest's settings for drom's Python tests: the heavy marker, which ctest runs under its heavy label,
and pip_install, the heavy test that builds the module with pip, which ctest runs on its own
(tests/python/CMakeLists.txt)."""


def pytest_configure(config):
    config.addinivalue_line("markers", "heavy: a long run, left out of the default suite (ctest -L heavy)")
    config.addinivalue_line("markers", "pip_install: pip install . builds the module from scratch (ctest -R Python.pip_install, label heavy)")
