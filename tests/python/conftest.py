"""pytest's settings for drom's Python tests: the heavy marker, which ctest runs under its heavy label
(tests/python/CMakeLists.txt)."""


def pytest_configure(config):
    config.addinivalue_line("markers", "heavy: a long run, left out of the default suite (ctest -L heavy)")
