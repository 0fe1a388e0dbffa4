#!/usr/bin/python3
"""The C++ sources are formatted: every tracked .h and .cc file is what `clang-format` (the root's
.clang-format) makes of it, checked with `clang-format --dry-run --Werror`. Run by CTest (project.format).

Usage: format_check.py SOURCE_DIR CLANG_FORMAT

Outside a git checkout (no list of tracked files) the check is skipped. Fix what it reports with
`clang-format -i FILE` (the whole file: `git clang-format` formats only changed lines, and can align
trailing comments differently from a whole-file pass).
"""
import subprocess
import sys


def main():
    root, clang_format = sys.argv[1], sys.argv[2]
    listed = subprocess.run(["git", "-C", root, "ls-files", "-z", "--", "*.h", "*.cc"], capture_output=True)
    if listed.returncode != 0:
        print("not a git checkout, skipped")
        return 0
    files = [f for f in listed.stdout.decode().split("\0") if f]
    unformatted = []
    for start in range(0, len(files), 64):
        batch = files[start:start + 64]
        run = subprocess.run([clang_format, "--dry-run", "--Werror", "--style=file"] + batch, cwd=root,
                             capture_output=True, text=True)
        if run.returncode != 0:
            # --Werror reports each unformatted place as "FILE:LINE:COL: error: code should be clang-formatted".
            found = {line.split(":", 1)[0] for line in run.stderr.splitlines() if "error:" in line} & set(batch)
            unformatted += sorted(found)
            if not found:  # clang-format itself failed (a file it cannot read, an unknown option)
                print(run.stderr.strip() or f"{clang_format} failed (exit {run.returncode})")
                return 1
    for name in unformatted:
        print(f"{name}: not formatted (clang-format -i {name})")
    print(f"{len(files)} files, {len(unformatted)} not formatted")
    return 1 if unformatted else 0


if __name__ == "__main__":
    sys.exit(main())
