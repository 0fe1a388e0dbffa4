"""The real records bundled with ident (provenance in datasets/README.md of the source tree).

    ident.datasets.names()          # ['dryer', 'gas_furnace', ...]
    df = ident.datasets.load("dryer")
    ident.datasets.info("dryer")    # system, sampling time, suggested structure and split
"""

import json
import os

from ident import _ident


def directory():
    """The folder with the records: $IDENT_DATASETS, the installed package data, or the source tree's."""
    candidates = [os.environ.get("IDENT_DATASETS", ""), os.path.join(os.path.dirname(__file__), "data"),
                  _ident.source_datasets_dir]
    for folder in candidates:
        if folder and os.path.isfile(os.path.join(folder, "index.json")):
            return folder
    raise FileNotFoundError("ident's bundled datasets are not found (set IDENT_DATASETS to the datasets folder)")


def _index():
    with open(os.path.join(directory(), "index.json"), encoding="utf-8") as f:
        return {entry["name"]: entry for entry in json.load(f)["datasets"]}


def names():
    """The bundled records' names."""
    return list(_index())


def info(name):
    """The index entry of a record: name, file, system, ts, structure (suggested model), split."""
    index = _index()
    if name not in index:
        raise ValueError(f"no bundled dataset '{name}' (known: {', '.join(index)})")
    return dict(index[name])


def path(name):
    """The CSV file of a bundled record."""
    return os.path.join(directory(), info(name)["file"])


def load(name):
    """A bundled record as a pandas DataFrame (columns as in its CSV header)."""
    import pandas as pd
    return pd.read_csv(path(name))
