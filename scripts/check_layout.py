"""Checks that every module includes only what its README allows.

    bash scripts/check-layout [ROOT]      (ROOT: the repository, by default this script's parent)

A module is a folder holding C++ sources and a README.md with a paragraph that starts
"May depend on:". The backquoted folders in that paragraph (`support/`, `paths/cutter/`) are the
modules it may include from; "every module" allows them all. A folder inside a module with a README
of its own is a module of its own (a wing), and its parent's files may include it only if the parent's
README names it. Each `#include "a/b/file.hpp"` in a module's .cpp, .hpp or .h files is matched to the
deepest module whose folder is a prefix of the included path; an include of a module that is neither
the includer nor one it may depend on is reported as file:line, and the script exits 1.
Folders without such a README (tests/, bench/, examples/, build trees) are not checked.
"""
import os
import re
import sys

SOURCE_SUFFIXES = (".cpp", ".hpp", ".h")
SKIPPED_FOLDERS = {".git", "tests", "bench", "examples", "docs", "cases", "scripts", "cmake"}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')
RULE_START = re.compile(r"^May depend on:", re.MULTILINE)
MODULE_NAME = re.compile(r"`([A-Za-z0-9_]+(?:/[A-Za-z0-9_]+)*)/`")


def read_rule(readme):
    """The modules a README allows, or None when it states no rule. '*' means every module."""
    with open(readme, encoding="utf-8") as f:
        text = f.read()
    start = RULE_START.search(text)
    if start is None:
        return None
    paragraph = text[start.end():].split("\n\n", 1)[0]
    if re.search(r"\bevery module\b", paragraph):
        return {"*"}
    return set(MODULE_NAME.findall(paragraph))


def find_modules(root):
    """Module folder (relative, with '/' separators) -> allowed set, for every folder with a rule."""
    modules = {}
    for folder, subfolders, files in os.walk(root):
        relative = os.path.relpath(folder, root).replace(os.sep, "/")
        if relative == ".":
            subfolders[:] = [d for d in subfolders if d not in SKIPPED_FOLDERS and not d.startswith("build")]
            continue
        if "README.md" in files:
            rule = read_rule(os.path.join(folder, "README.md"))
            if rule is not None:
                modules[relative] = rule
    return modules


def owner(path, modules):
    """The deepest module whose folder holds `path` (a relative path with '/'), or None."""
    parts = path.split("/")
    for n in range(len(parts) - 1, 0, -1):
        candidate = "/".join(parts[:n])
        if candidate in modules:
            return candidate
    return None


def check(root):
    modules = find_modules(root)
    problems = []
    for module in sorted(modules):
        allowed = modules[module]
        for folder, _, files in os.walk(os.path.join(root, module)):
            for name in sorted(files):
                if not name.endswith(SOURCE_SUFFIXES):
                    continue
                path = os.path.join(folder, name)
                relative = os.path.relpath(path, root).replace(os.sep, "/")
                if owner(relative, modules) != module:
                    continue  # a wing's file: checked against the wing's own README
                with open(path, encoding="utf-8", errors="replace") as f:
                    for number, line in enumerate(f, 1):
                        match = INCLUDE.match(line)
                        if not match:
                            continue
                        target = owner(match.group(1), modules)
                        if target is None or target == module or "*" in allowed or target in allowed:
                            continue
                        problems.append(f"{relative}:{number}: {module}/ includes \"{match.group(1)}\", but "
                                        f"{module}/README.md's 'May depend on:' does not name `{target}/`")
    return modules, problems


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    if not os.path.isdir(root):
        print(f"check-layout: {root}: not a folder", file=sys.stderr)
        return 2
    modules, problems = check(root)
    if not modules:
        print(f"check-layout: {root}: no module README.md with a 'May depend on:' paragraph", file=sys.stderr)
        return 2
    for problem in problems:
        print(problem)
    if problems:
        print(f"check-layout: {len(problems)} include(s) against the modules' rules", file=sys.stderr)
        return 1
    print(f"check-layout: {len(modules)} modules, every include allowed by its README")
    return 0


if __name__ == "__main__":
    sys.exit(main())
