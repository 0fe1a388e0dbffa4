#!/usr/bin/python3
"""`ident stream` throughput from a pipe: 10^6 rows of a simulated ARX(4,4,1) record (rho = 8, Cauchy noise)
written by `cat` into a pipe, estimated by the Cauchy estimator, the JSON lines read from a pipe by this
script; rows per second of wall time (best of 3), with the output flushed per line (the default) and only
before the program waits for input (--flush-every 0).

    /usr/bin/python3 bench/stream_throughput.py [--rows 1000000] [--json OUT]

Needs a Release build in build/ (build/bin/ident).
"""
import argparse
import json
import os
import subprocess
import tempfile
import time

import numpy as np
from scipy.signal import lfilter

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
IDENT = os.path.join(ROOT, "build", "bin", "ident")
MODEL = ["--output", "y", "--input", "u", "--na", "4", "--nb", "4", "--nk", "1", "--estimator", "cauchy"]


def one_run(path, flush_every):
    """Wall seconds of `cat path | ident stream ... | (this process)`, the lines read and the last one."""
    start = time.perf_counter()
    cat = subprocess.Popen(["cat", path], stdout=subprocess.PIPE)
    ident = subprocess.Popen([IDENT, "stream", *MODEL, "--flush-every", str(flush_every)], stdin=cat.stdout,
                             stdout=subprocess.PIPE)
    cat.stdout.close()
    lines, tail = 0, b""
    while True:
        chunk = ident.stdout.read1(1 << 16)
        if not chunk:
            break
        lines += chunk.count(b"\n")
        tail = (tail + chunk)[-4096:]
    if ident.wait() != 0 or cat.wait() != 0:
        raise RuntimeError("ident stream failed")
    seconds = time.perf_counter() - start
    return seconds, lines, json.loads(tail.rstrip(b"\n").rsplit(b"\n", 1)[-1])


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--rows", type=int, default=1_000_000)
    p.add_argument("--json", help="write the figures to this file")
    args = p.parse_args()
    rng = np.random.default_rng(5)
    u = rng.normal(size=args.rows)
    e = 0.1 * rng.standard_cauchy(size=args.rows)
    a, b = [-0.5, 0.2, -0.1, 0.05], [1.0, 0.5, 0.25, 0.1]
    y = lfilter([0] + b, [1] + a, u) + lfilter([1], [1] + a, e)
    figures = {"rows": args.rows, "structure": "ARX(4,4,1)", "rho": 8, "estimator": "cauchy"}
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "record.csv")
        np.savetxt(path, np.column_stack([u, y]), delimiter=",", header="u,y", comments="", fmt="%.17g")
        figures["input_bytes"] = os.path.getsize(path)
        for label, flush_every in (("flush_every_line", 1), ("flush_before_wait", 0)):
            runs = [one_run(path, flush_every) for _ in range(3)]
            seconds, lines, last = min(runs, key=lambda r: r[0])
            figures[label] = {"seconds": round(seconds, 3), "rows_per_second": round(args.rows / seconds),
                              "lines": lines}
        figures["last_theta"] = last["theta"]
        figures["true_theta"] = a + b
    print(json.dumps(figures, indent=1))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(figures, f, indent=1)


if __name__ == "__main__":
    main()
