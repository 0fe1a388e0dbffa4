"""Shared fixtures: the command-line program (for equality with its JSON) and the source tree's paths."""

import json
import os
import subprocess

import pytest

SOURCE = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


@pytest.fixture(scope="module")
def cli():
    """Runs `ident ARGS` and returns its parsed --json output."""
    program = os.environ.get("IDENT_CLI", os.path.join(SOURCE, "build", "bin", "ident"))
    if not os.path.exists(program):
        pytest.skip("the ident program is not built (set IDENT_CLI)")

    def run(*args):
        done = subprocess.run([program, *args], capture_output=True, text=True, check=True)
        return json.loads(done.stdout)

    return run


@pytest.fixture(scope="module")
def source_dir():
    return SOURCE
