"""The house's shape, checked on the repository itself (issue 43): paths/ holds wings only, each a
module with its own rules and library, and every runner is a short driver over named stages."""
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SOURCES = (".cpp", ".hpp", ".h")

# Runners: the functions that run a command or a job from end to end. Each calls named stages.
RUNNER = re.compile(r"^(run|run_\w+|simulate|copy_cloud|reduce_database|plan_cloud_\w+|main)$")
LONGEST_RUNNER = 80  # lines, signature to closing brace

# A function definition at namespace scope: its signature starts in column 0 and its body ends at the
# first "}" in column 0 after it (the code is clang-formatted; namespaces close with a comment).
SIGNATURE = re.compile(r"^(?!namespace|struct|class|enum|union|using|template|static_assert|#|//|\s)[^;{}]*?\b(?:\w+::)*(\w+)\s*\(")


def function_lengths(path):
    lines = path.read_text(encoding="utf-8", errors="replace").split("\n")
    found, i = [], 0
    while i < len(lines):
        match = SIGNATURE.match(lines[i])
        if match:
            j = i
            while j < len(lines) and j < i + 8 and not lines[j].rstrip().endswith("{"):
                if lines[j].rstrip().endswith(";") or "{" in lines[j]:  # a declaration, or a one-line body
                    j = None
                    break
                j += 1
            if j is not None and j < len(lines) and lines[j].rstrip().endswith("{"):
                k = j + 1
                while k < len(lines) and lines[k] != "}":
                    k += 1
                found.append((match.group(1), i + 1, k - i + 1))
                i = k
        i += 1
    return found


def library_sources():
    skipped = {"tests", "bench", "fuzz", "examples", "build", ".git", "docs", "cases", "scripts", "cmake", "python"}
    for path in sorted(ROOT.rglob("*.cpp")):
        parts = path.relative_to(ROOT).parts
        if parts[0] in skipped or parts[0].startswith("build"):
            continue
        yield path


def test_no_source_file_lies_directly_in_paths():
    loose = [p.name for p in (ROOT / "paths").iterdir() if p.is_file() and p.suffix in SOURCES]
    assert loose == [], f"paths/ holds wings only; move {loose} into one"


@pytest.mark.parametrize("wing", sorted(p.name for p in (ROOT / "paths").iterdir() if p.is_dir()))
def test_every_wing_is_a_module_with_its_rules_and_library(wing):
    folder = ROOT / "paths" / wing
    assert "May depend on:" in (folder / "README.md").read_text(encoding="utf-8")
    assert f"drom_library(paths_{wing}" in (folder / "CMakeLists.txt").read_text(encoding="utf-8")


def test_the_scanner_measures_a_function_it_is_given(tmp_path):
    source = tmp_path / "x.cpp"
    source.write_text("namespace a {\n\nint one(int b) { return b; }\nint run_x(int b,\n          int c) {\n  return b + c;\n}\n\nvoid f();\n\n}  // namespace a\n")
    assert function_lengths(source) == [("run_x", 4, 4)]


def test_no_runner_is_longer_than_80_lines():
    runners = [(str(p.relative_to(ROOT)), line, name, length)
               for p in library_sources() for name, line, length in function_lengths(p) if RUNNER.match(name)]
    assert len(runners) >= 10, f"the scanner found too few runners to be trusted: {runners}"
    long = [f"{path}:{line}: {name} is {length} lines" for path, line, name, length in runners if length > LONGEST_RUNNER]
    assert long == [], "runners are short drivers over named stages:\n" + "\n".join(long)
