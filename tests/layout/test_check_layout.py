"""scripts/check-layout on small trees made here: a clean one passes, each kind of forbidden include
fails naming its file and line."""
import pathlib
import subprocess

import pytest

SCRIPT = pathlib.Path(__file__).resolve().parents[2] / "scripts" / "check-layout"


def write(root, path, text):
    target = root / path
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(text)


def check(root):
    return subprocess.run(["bash", str(SCRIPT), str(root)], capture_output=True, text=True)


@pytest.fixture
def tree(tmp_path):
    """support <- geometry <- paths (with a wing paths/finish over paths/cutter), apps over all."""
    write(tmp_path, "support/README.md", "# support\n\nMay depend on: no other drom module.\n")
    write(tmp_path, "support/error.hpp", "#pragma once\n")
    write(tmp_path, "geometry/README.md", "# geometry\n\nMay depend on: `support/` only.\n")
    write(tmp_path, "geometry/surface.hpp", '#pragma once\n#include "support/error.hpp"\n#include <vector>\n')
    write(tmp_path, "paths/cutter/README.md", "# cutter\n\nMay depend on: `geometry/`,\n`support/`.\n\nOther text.\n")
    write(tmp_path, "paths/cutter/cutter.hpp", '#pragma once\n#include "geometry/surface.hpp"\n')
    write(tmp_path, "paths/finish/README.md", "# finish\n\nMay depend on: `paths/cutter/`, `geometry/`, `support/`.\n")
    write(tmp_path, "paths/finish/plan.cpp", '#include "paths/finish/plan.hpp"\n#include "paths/cutter/cutter.hpp"\n')
    write(tmp_path, "paths/finish/plan.hpp", "#pragma once\n")
    write(tmp_path, "apps/README.md", "# apps\n\nMay depend on: every module.\n")
    write(tmp_path, "apps/main.cpp", '#include "paths/finish/plan.hpp"\n#include "support/error.hpp"\n')
    write(tmp_path, "tests/geometry/surface_test.cpp", '#include "apps/anything.hpp"\n')  # tests are not checked
    return tmp_path


def test_a_tree_that_keeps_its_rules_passes(tree):
    result = check(tree)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "5 modules" in result.stdout


def test_an_include_upstream_fails_naming_the_file_and_line(tree):
    write(tree, "geometry/surface.cpp", '#include "geometry/surface.hpp"\n\n#include "paths/cutter/cutter.hpp"\n')
    result = check(tree)
    assert result.returncode == 1
    assert "geometry/surface.cpp:3:" in result.stdout
    assert "`paths/cutter/`" in result.stdout
    assert len(result.stdout.strip().splitlines()) == 1


def test_one_wing_including_another_fails(tree):
    write(tree, "paths/cutter/profile.hpp", '#pragma once\n#include "paths/finish/plan.hpp"\n')
    result = check(tree)
    assert result.returncode == 1
    assert "paths/cutter/profile.hpp:2:" in result.stdout and "`paths/finish/`" in result.stdout


def test_a_rule_spread_over_lines_ends_at_the_paragraph(tree):
    # cutter's rule names geometry/ and support/ over two lines; `paths/finish/` after the blank line is not in it.
    write(tree, "paths/cutter/README.md", "# cutter\n\nMay depend on: `geometry/`,\n`support/`.\n\nSee `paths/finish/`.\n")
    write(tree, "paths/cutter/more.cpp", '#include "support/error.hpp"\n#include "paths/finish/plan.hpp"\n')
    result = check(tree)
    assert result.returncode == 1
    assert result.stdout.strip().splitlines() == [line for line in result.stdout.strip().splitlines() if "more.cpp:2:" in line]


def test_a_tree_without_rules_is_an_error_not_a_pass(tmp_path):
    write(tmp_path, "lonely/file.cpp", '#include "other/file.hpp"\n')
    result = check(tmp_path)
    assert result.returncode == 2 and "no module README.md" in result.stderr
