"""`cmake --install` puts a package that `import ident` finds, with the bundled records as its data."""

import os
import subprocess
import sys

import pytest


def test_installed_package_imports_and_fits(tmp_path):
    build = os.environ.get("IDENT_BUILD_DIR")
    if not build:
        pytest.skip("IDENT_BUILD_DIR is not set (ctest sets it)")
    prefix = tmp_path / "prefix"
    subprocess.run(["cmake", "--install", build, "--prefix", str(prefix), "--component", "ident_python"], check=True,
                   capture_output=True)
    site = [os.path.join(root) for root, dirs, files in os.walk(prefix) if "__init__.py" in files
            and os.path.basename(root) == "ident"]
    assert len(site) == 1, site
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "IDENT_DATASETS")}
    env["PYTHONPATH"] = os.path.dirname(site[0])
    code = ("import ident, os; r = ident.fit('dryer', estimator='cauchy'); "
            "print(ident.datasets.directory()); print(round(r.fit_one_step, 2))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=tmp_path,
                          check=True)
    directory, fit = done.stdout.split()
    assert directory == os.path.join(site[0], "data")
    assert float(fit) > 90
