#!/usr/bin/python3
"""The documentation's checks, run by CTest (project.docs):

  links      every relative link in README.md and docs/**/*.md names an existing file, and a #anchor
             names a heading of the target Markdown file (GitHub's anchor rule);
  options    every option `ident SUBCOMMAND --help` lists appears in docs/reference/cli.md, and every
             option the reference names is an option of the program;
  spans      every inline code span of README.md and docs/ that reads `ident SUBCOMMAND …` names a
             subcommand of the program and only options that subcommand lists in its --help;
  words      no tracked file outside CHANGELOG.md holds a dated or personal note (the patterns below);
             skipped outside a git checkout.

Usage: docs_check.py SOURCE_DIR IDENT_BINARY
"""
import glob
import os
import re
import subprocess
import sys

# Options the bad-input table passes on purpose to show the usage error.
UNKNOWN_ON_PURPOSE = {"--bogus", "--no-such-option"}
# Each word ends in a bracket expression so that this file does not match its own pattern.
FORBIDDEN = (r"sessio[n]| UT[C]|load [≈]|load averag[e]|\(wa[s]|issu[e] [0-9]|hotpat[h]|this branc[h]|after the merg[e]"
             r"|/wor[k]/|/roo[t]/")


def anchor(heading):
    text = re.sub(r"[`*_]|\[|\]\([^)]*\)", "", heading.strip().lower())
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(path):
    result, in_code = set(), False
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.startswith("```"):
                in_code = not in_code
            elif not in_code and line.startswith("#"):
                result.add(anchor(line.lstrip("#")))
    return result


def check_links(root):
    errors = []
    files = [os.path.join(root, "README.md")] + sorted(glob.glob(os.path.join(root, "docs", "**", "*.md"),
                                                                 recursive=True))
    link = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
    for path in files:
        with open(path, encoding="utf-8") as f:
            text = re.sub(r"```.*?```", "", f.read(), flags=re.S)
        for target in link.findall(text):
            if re.match(r"[a-z]+:", target):
                continue
            file_part, _, fragment = target.partition("#")
            resolved = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) if file_part else path
            where = os.path.relpath(path, root)
            if not os.path.exists(resolved):
                errors.append(f"{where}: link to {target}: no such file")
            elif fragment and resolved.endswith(".md") and fragment not in anchors(resolved):
                errors.append(f"{where}: link to {target}: no heading with anchor #{fragment}")
    return errors


def check_options(root, ident):
    errors = []
    with open(os.path.join(root, "docs", "reference", "cli.md"), encoding="utf-8") as f:
        reference = f.read()
    listed = set()
    # Every subcommand `ident --help` lists, each with a section of the reference.
    top = subprocess.run([ident, "--help"], capture_output=True, text=True, check=True).stdout
    subcommands = re.findall(r"^  ([a-z]+) {2,}", top.split("Subcommands:", 1)[1], flags=re.M)
    for sub in subcommands:
        if f"## ident {sub}\n" not in reference:
            errors.append(f"docs/reference/cli.md: no section '## ident {sub}'")
    for sub in subcommands:
        out = subprocess.run([ident, sub, "--help"], capture_output=True, text=True, check=True).stdout
        options = set(re.findall(r"^\s+(?:-\w,)?(--[a-z][a-z0-9-]*)", out, flags=re.M)) - {"--help"}
        listed |= options
        for option in sorted(options):
            if not re.search(re.escape(option) + r"(?![a-z0-9-])", reference):
                errors.append(f"docs/reference/cli.md: `ident {sub} {option}` is not documented")
    code_spans = " ".join(re.findall(r"`([^`]*)`", reference))
    for option in sorted(set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", code_spans))):
        if option not in listed | UNKNOWN_ON_PURPOSE | {"--help", "--version"}:
            errors.append(f"docs/reference/cli.md: {option} is not an option of any subcommand")
    return errors


def help_options(ident):
    """{subcommand: the options its --help lists}."""
    top = subprocess.run([ident, "--help"], capture_output=True, text=True, check=True).stdout
    out = {}
    for sub in re.findall(r"^  ([a-z]+) {2,}", top.split("Subcommands:", 1)[1], flags=re.M):
        text = subprocess.run([ident, sub, "--help"], capture_output=True, text=True, check=True).stdout
        out[sub] = set(re.findall(r"^\s+(?:-\w,)?(--[a-z][a-z0-9-]*)", text, flags=re.M)) | {"--help"}
    return out


def check_spans(root, ident):
    errors = []
    options = help_options(ident)
    pages = [os.path.join(root, "README.md")] + sorted(glob.glob(os.path.join(root, "docs", "**", "*.md"),
                                                                 recursive=True))
    for page in pages:
        with open(page, encoding="utf-8") as f:
            text = f.read()
        text = re.sub(r"^```.*?^```", "", text, flags=re.M | re.S)  # fenced blocks: docs_examples.py runs them
        for span in re.findall(r"`([^`\n]+)`", text):
            m = re.match(r"ident ([a-z]+)\b(.*)", span)
            if not m:
                continue
            sub, rest = m.groups()
            where = os.path.relpath(page, root)
            if sub not in options:
                if sub.isalpha() and not rest.startswith(("/", ".", "::")):
                    errors.append(f"{where}: `{span}`: '{sub}' is not a subcommand")
                continue
            for option in re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", rest):
                if option not in options[sub] | UNKNOWN_ON_PURPOSE:
                    errors.append(f"{where}: `{span}`: {option} is not an option of ident {sub}")
    return errors


def check_words(root):
    if subprocess.run(["git", "-C", root, "rev-parse", "--is-inside-work-tree"],
                      capture_output=True).returncode != 0:
        print("words: not a git checkout, skipped")
        return []
    out = subprocess.run(["git", "-C", root, "grep", "-i", "-n", "-I", "-E", FORBIDDEN, "--", ".",
                          ":!CHANGELOG.md"], capture_output=True, text=True)
    return [f"dated or personal note: {line}" for line in out.stdout.splitlines()]


def main():
    root, ident = sys.argv[1], sys.argv[2]
    errors = check_links(root) + check_options(root, ident) + check_spans(root, ident) + check_words(root)
    for e in errors:
        print(e)
    print(f"{len(errors)} problem(s)")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
