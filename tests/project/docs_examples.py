#!/usr/bin/python3
"""The command lines and Python examples of README.md and docs/ run as written (CTest project.docs_examples
and docs.python_examples; the C++ blocks compile and run as docs.cpp_example.* in tests/CMakeLists.txt).

  shell      every line of a ```sh block, and every "$ COMMAND" line of any ``` block, runs with bash
             and exits with 0. The lines of one Markdown file run in order in one fresh directory that
             holds the bundled datasets/ (as the repository root does) and finds `ident` on PATH, so that
             a tutorial runs from its first line to its last. DATA, a placeholder for the reader's record,
             stands for `dryer`; my.csv is a copy of datasets/dryer.csv.
  output     the lines shown under a "$ COMMAND" line (up to the next "$ " line or the end of the block)
             are lines of what the command prints to stdout, in that order; "..." skips lines. A compare
             table's last column (ns/update, a timing) is left out on both sides.
  python     with --python, every ```python block of docs/how-to/use-from-python.md and the README runs
             after PRELUDE, which gives values to the names the examples leave to the reader.

Lines that build or install the project, or start programs of the reader's own (NOT_RUN), are listed as
not run. Usage: docs_examples.py SOURCE_DIR IDENT_BINARY [--python]
"""
import glob
import os
import re
import shutil
import subprocess
import sys
import tempfile

# First words of commands that are not run here: the build and install commands (the whole suite runs
# them in .ci/test and tests/package), the benchmarks, and programs standing for the reader's own.
NOT_RUN = {".ci/setup", ".ci/test", "cmake", "ctest", "cpack", "apt", "bench/run-baselines", "mkfifo",
           "logger", "controller", "dask"}
PLACEHOLDERS = {"DATA": "dryer"}
# Python files whose ```python blocks run (the Dask guide needs a cluster and the reader's files).
PYTHON_FILES = ("README.md", "docs/how-to/use-from-python.md")
PRELUDE = """\
import numpy as np
import matplotlib
matplotlib.use("Agg")
import ident
y, z = 1.0, np.array([1.0, 0.5, -0.2, 0.1])
Z = np.random.default_rng(1).normal(size=(200, 4))
Y = Z @ np.array([0.5, -1.0, 0.2, 0.3])
A, Q, c, r = np.array([[1.0, 0.1], [0.0, 1.0]]), 0.01 * np.eye(2), np.array([1.0, 0.0]), 0.04
B, x0, P0 = np.array([[0.0], [0.1]]), np.zeros(2), np.eye(2)
model = open("{root}/examples/duality/tracking_huber.json", encoding="utf-8").read()
measurements = np.loadtxt("{root}/examples/duality/tracking.csv", delimiter=",", skiprows=1, usecols=-1)
x = np.random.default_rng(2).laplace(size=200)
"""


def blocks(path):
    """(language, first line number, lines) of every fenced block."""
    result, current = [], None
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            line = line.rstrip("\n")
            if line.startswith("```"):
                if current is None:
                    current = (line[3:].strip(), number + 1, [])
                else:
                    result.append(current)
                    current = None
            elif current is not None:
                current[2].append(line)
    return result


def commands(path):
    """(line number, command, output lines shown under it) in the order of the file."""
    result = []
    for language, first, lines in blocks(path):
        if language not in ("", "sh", "console"):
            continue
        for i, line in enumerate(lines):
            if line.startswith("$ "):
                shown = []
                for later in lines[i + 1:]:
                    if later.startswith("$ "):
                        break
                    shown.append(later)
                result.append((first + i, line[2:], shown))
            elif language == "sh" and line.strip() and not line.lstrip().startswith("#"):
                result.append((first + i, line, []))
    return result


def programs(command):
    return [segment.split()[0] for segment in re.split(r"&&|\|\||[|;&]", command.split(" #")[0])
            if segment.split()]


def normalised(line):
    if re.search(r" (recursive|batch) |ns/update", line):
        line = line.rstrip().rsplit(" ", 1)[0]
    return line.rstrip()


def check_output(where, command, shown, printed):
    errors, lines, at = [], [normalised(line) for line in printed.splitlines()], 0
    for expected in shown:
        if expected.strip() in ("...", "…", ""):
            continue
        expected = normalised(expected)
        try:
            at = lines.index(expected, at) + 1
        except ValueError:
            errors.append(f"{where}: `{command}` does not print (in this order): {expected!r}")
    return errors


def run_commands(root, ident, files):
    errors, not_run, run = [], [], 0
    bindir = tempfile.mkdtemp(prefix="ident-docs-bin-")
    os.symlink(ident, os.path.join(bindir, "ident"))
    env = dict(os.environ, PATH=bindir + os.pathsep + os.environ.get("PATH", ""))
    for path in files:
        found = commands(path)
        if not found:
            continue
        with tempfile.TemporaryDirectory(prefix="ident-docs-") as work:
            os.symlink(os.path.join(root, "datasets"), os.path.join(work, "datasets"))
            shutil.copy(os.path.join(root, "datasets", "dryer.csv"), os.path.join(work, "my.csv"))
            for number, command, shown in found:
                where = f"{os.path.relpath(path, root)}:{number}"
                skipped = sorted(set(programs(command)) & NOT_RUN)
                if skipped:
                    not_run.append(f"{where}: {command}")
                    continue
                line = " ".join(PLACEHOLDERS.get(word, word) for word in command.split(" "))
                r = subprocess.run(["bash", "-c", "set -o pipefail; " + line], cwd=work, env=env,
                                   capture_output=True, text=True)
                run += 1
                if r.returncode != 0:
                    errors.append(f"{where}: `{command}` exits with {r.returncode}: {r.stderr.strip()}")
                    continue
                errors += check_output(where, command, shown, r.stdout)
    shutil.rmtree(bindir)
    print(f"{run} command line(s) run; not run (build, install or the reader's own programs):")
    for line in not_run:
        print("  " + line)
    return errors, run


def run_python(root, files):
    errors, run = [], 0
    for path in files:
        for language, first, lines in blocks(path):
            if language != "python":
                continue
            where = f"{os.path.relpath(path, root)}:{first}"
            with tempfile.TemporaryDirectory(prefix="ident-docs-py-") as work:
                source = PRELUDE.format(root=root) + "\n".join(lines) + "\n"
                r = subprocess.run([sys.executable, "-c", source], cwd=work, capture_output=True, text=True,
                                   env=dict(os.environ, MPLBACKEND="Agg"))
            run += 1
            if r.returncode != 0:
                errors.append(f"{where}: the Python example fails:\n{r.stderr.strip()}")
    print(f"{run} Python example(s) run")
    return errors, run


def main():
    root, ident = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    if "--python" in sys.argv[3:]:
        errors, run = run_python(root, [os.path.join(root, f) for f in PYTHON_FILES])
    else:
        files = [os.path.join(root, "README.md")] + sorted(glob.glob(os.path.join(root, "docs", "**", "*.md"),
                                                                     recursive=True))
        errors, run = run_commands(root, ident, files)
    for e in errors:
        print(e)
    print(f"{len(errors)} problem(s)")
    return 1 if errors or run == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
