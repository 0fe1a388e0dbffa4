#!/usr/bin/python3
"""Regressor cleaning on and off: the validation one-step fit of each estimator over 100 trials.

For each record (dryer, gas_furnace, exchanger, cd_player_arm, with their suggested ARX structures) it
runs `ident compare RECORD --clean-regressors off|on --trials N --json` (5 % outliers of 20σ, seeds
1..N, rls, cauchy and student:3) and prints min / median / max of the one-step fit % over the trials.

Run from the repository root after .ci/setup:
    bench/cleaning_study.py [--ident build/bin/ident] [--trials 100]
"""
import argparse
import json
import subprocess

RECORDS = ["dryer", "gas_furnace", "exchanger", "cd_player_arm"]


def compare(ident, record, cleaning, trials):
    command = [ident, "compare", record, "--clean-regressors", cleaning, "--trials", str(trials), "--json"]
    result = subprocess.run(command, capture_output=True, text=True, check=True)
    return json.loads(result.stdout)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--ident", default="build/bin/ident")
    p.add_argument("--trials", type=int, default=100)
    args = p.parse_args()
    print("| record (suggested structure) | estimator | cleaning off | cleaning on |")
    print("|---|---|---|---|")
    for record in RECORDS:
        runs = {c: compare(args.ident, record, c, args.trials) for c in ("off", "on")}
        clean_fit = runs["on"]["reference"]["fit_percent"]["one_step"]
        label = f"{record} {runs['on']['structure']} (clean LS {clean_fit:.2f})"
        for estimator in ("cauchy", "student:3", "rls"):
            cells = []
            for c in ("off", "on"):
                e = next(e for e in runs[c]["estimators"] if e["estimator"] == estimator)
                s = e["spread"]["fit_one_step"]
                cells.append(f"{s['min']:.2f} / {s['median']:.2f} / {s['max']:.2f}")
            print(f"| {label} | {estimator} | {cells[0]} | {cells[1]} |")


if __name__ == "__main__":
    main()
