#!/usr/bin/env python3
"""Every repository path a top folder's README.md names must exist.

A top folder (fsw/, hal/, sim/, ...) must have a README.md, and each backquoted token in it that
reads as a path is looked for: relative to the README's folder, then to the repository root.
A path is a token without spaces that contains a '/' or is a source file's bare name; '*' is a
glob (`fsw/src/ekf*.cpp`); a header may be named as it is included (`fsw/gps_orbit.hpp` for
fsw/include/fsw/gps_orbit.hpp); a bare source file name (`can_protocol.hpp`) is looked for
anywhere below the README's folder, then the repository. Not checked: output file names
(`summary.json`), placeholders (`<data dir>/config/default.toml`, `DIR/filter.toml`), URLs,
options, build outputs (`build/...`) and paths outside the repository (`../share/sdins`).

usage: check_readme_paths.py REPO_ROOT
"""
import glob
import os
import re
import sys

TOP_FOLDERS = ["fsw", "hal", "sim", "tools", "tests", "cfg", "docs", "bench", "fuzz", "config", "data"]
SOURCE_EXTENSIONS = (".hpp", ".cpp", ".h", ".c", ".py", ".sh", ".lcm", ".dbc", ".alm", ".ld", ".cmake")
HEADERS = (".hpp", ".h")
# Where `<lib>/<name>.hpp` (the include spelling) lives.
INCLUDE_DIRS = ["fsw/include", "hal/include", "sim/include", "cfg/include", "tools/run/include",
                "tools/import/include", "tools/diagnosis/include", "tools/paper/include", "tools/audit/include"]
NOT_IN_TREE = ("build/", "../", "/", "~", "$", "-")


def is_path(token):
    if not token or any(c.isspace() for c in token) or "://" in token or "::" in token:
        return False
    if any(c in token for c in "<>=(){}\"',;|"):
        return False
    if token.startswith(NOT_IN_TREE) or token.split("/")[0].isupper():
        return False
    return "/" in token or token.endswith(SOURCE_EXTENSIONS)


def exists(root, folder, token):
    name = token.rstrip("/")
    for base in (os.path.join(root, folder), root):
        if glob.glob(os.path.join(base, name)):
            return True
    if "*" not in name and name.endswith(HEADERS):  # as included: fsw/gps_orbit.hpp
        if any(os.path.isfile(os.path.join(root, inc, name)) for inc in INCLUDE_DIRS):
            return True
    if "/" not in name:  # a bare file name: somewhere below the folder, else in the repository
        for base in (os.path.join(root, folder), root):
            if glob.glob(os.path.join(base, "**", name), recursive=True):
                return True
    return False


def main():
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    root = sys.argv[1]
    failures = []
    checked = 0
    for folder in TOP_FOLDERS:
        readme = os.path.join(root, folder, "README.md")
        if not os.path.isfile(readme):
            failures.append(f"{folder}/README.md: missing (every top folder says what lives there and what it may include)")
            continue
        with open(readme, encoding="utf-8") as f:
            text = f.read()
        text = re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)  # code blocks are commands, not names
        for lineno, line in enumerate(text.splitlines(), 1):
            for token in re.findall(r"`([^`]+)`", line):
                if not is_path(token):
                    continue
                checked += 1
                if not exists(root, folder, token):
                    failures.append(f"{folder}/README.md: `{token}` names no file or folder of the repository")
    for f in failures:
        print(f)
    print(f"{checked} paths in {len(TOP_FOLDERS)} top-folder READMEs, {len(failures)} wrong")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
