#!/usr/bin/env python3
"""The frame-cost ledger's model, fitted to a `gabarit bench --suite` run.

Reads DIR/suite-scenes.csv (its per-scene ledger columns: docs/performance.md)
and prints, for the plain loop and the default session, the cost per unit of
each phase (least squares through the origin over the scenes) and how well it
predicts each scene's mean (median and worst relative error).

Usage: tools/scripts/ledger-model.py BENCH_OUT_DIR
"""
import csv
import re
import statistics
import sys

# The suite's tables: 11 x 11 translations x 7 angles x the scene's depths (docs/scene-suite.md).
CELLS_PER_DEPTH = 11 * 11 * 7
DENSE_MAX_CELLS = 1024  # kernel/include/gabarit/dense_voter.hpp, kDenseMaxCells


def fit(ys, xs):
    """k minimising sum (y - k x)^2, with the median and worst |k x - y| / y."""
    k = sum(x * y for x, y in zip(xs, ys)) / sum(x * x for x in xs)
    errors = [abs(k * x - y) / y for x, y in zip(xs, ys) if y > 0.5]
    return k, statistics.median(errors), max(errors), len(errors)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    with open(sys.argv[1] + "/suite-scenes.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r.get("features_us")]
    if not rows:
        sys.exit("no ledger columns in suite-scenes.csv (a bench older than the ledger?)")
    print("| method | phase | cost | per | median error | worst | scenes |\n|---|---|---:|---|---:|---:|---:|")
    for method in ("plain loop (thesis)", "gabarit default session"):
        scenes = [r for r in rows if r["method"] == method]

        def column(name, subset):
            return [float(r[name]) for r in subset]

        def cells(r):
            return CELLS_PER_DEPTH * int(re.search(r"-d(\d+)", r["name"]).group(1))

        terms = [("features", scenes, "features_us", column("features", scenes), "feature that voted")]
        dense = [r for r in scenes if cells(r) <= DENSE_MAX_CELLS]
        csr = [r for r in scenes if cells(r) > DENSE_MAX_CELLS]
        if dense:
            words = [float(r["features"]) * ((cells(r) + 63) // 64) for r in dense]
            terms.append(("vote, dense voter", dense, "vote_us", words, "feature x 64-cell word"))
        if csr:
            terms.append(("vote, CSR voter", csr, "vote_us", column("votes", csr), "vote"))
        for phase in ("verify", "depth", "survey", "recovery"):
            work = column(phase + "_work", scenes)
            if sum(work) > 0:
                terms.append((phase, scenes, phase + "_us", work, "work unit"))
        for phase, subset, target, xs, unit in terms:
            ys = column(target, subset)
            pairs = [(x, y) for x, y in zip(xs, ys) if x > 0]
            if not pairs:
                continue
            k, median, worst, n = fit([y for _, y in pairs], [x for x, _ in pairs])
            print(f"| {method} | {phase} | {k * 1000:.2f} ns | {unit} | {median * 100:.0f}% | {worst * 100:.0f}% | {n} |")


if __name__ == "__main__":
    main()
