#!/usr/bin/python3
"""The library's size limits, run by CTest (project.code_size): no source file in the library folders
(common/, models/, approx/, ident/) over 500 lines, and no function body there over 80 lines.

A function is found as a definition line at namespace or class level (at most two spaces of indent)
that names a call and whose statement ends in `{`; its length runs to the matching `}` (strings,
character literals and // comments left out of the brace count). Lambdas and local classes count
towards the function that holds them.

Usage: code_size_check.py SOURCE_DIR
"""
import glob
import os
import re
import sys

LIBRARY = ("common", "models", "approx", "ident")
MAX_FILE_LINES = 500
MAX_FUNCTION_LINES = 80
NOT_A_DEFINITION = ("if", "for", "while", "switch", "return", "namespace", "class", "struct", "//", "using",
                    "template", "} ", "case", "else", "do")


def braces(line):
    line = re.sub(r'"([^"\\]|\\.)*"', "", line)
    line = re.sub(r"'([^'\\]|\\.)*'", "", line)
    line = line.split("//")[0]
    return line.count("{") - line.count("}"), "{" in line


def long_functions(path, lines):
    found, i = [], 0
    while i < len(lines):
        line = lines[i]
        if re.match(r"^(  )?[A-Za-z~].*\(", line) and not line.lstrip().startswith(NOT_A_DEFINITION):
            j, statement = i, line
            while not statement.rstrip().endswith(("{", ";", "}")) and j < i + 6 and j + 1 < len(lines):
                j += 1
                statement += lines[j]
            if statement.rstrip().endswith("{") and ")" in statement:
                depth, started, k = 0, False, i
                while k < len(lines):
                    change, opens = braces(lines[k])
                    depth += change
                    started = started or opens
                    if started and depth <= 0:
                        break
                    k += 1
                if k - i + 1 > MAX_FUNCTION_LINES:
                    found.append(f"{path}:{i + 1}: a function of {k - i + 1} lines (at most {MAX_FUNCTION_LINES}): "
                                 f"{line.strip()[:80]}")
                i = k + 1
                continue
        i += 1
    return found


def main():
    root = sys.argv[1]
    problems, files = [], 0
    for folder in LIBRARY:
        for path in sorted(glob.glob(os.path.join(root, folder, "**", "*.*"), recursive=True)):
            if not path.endswith((".h", ".cc")):
                continue
            files += 1
            with open(path, encoding="utf-8") as f:
                lines = f.read().split("\n")
            relative = os.path.relpath(path, root)
            if len(lines) - 1 > MAX_FILE_LINES:
                problems.append(f"{relative}: {len(lines) - 1} lines (at most {MAX_FILE_LINES})")
            problems += long_functions(relative, lines)
    for p in problems:
        print(p)
    print(f"{files} files, {len(problems)} problem(s)")
    return 1 if problems or files < 50 else 0


if __name__ == "__main__":
    sys.exit(main())
