#!/usr/bin/env python3
"""Mean and spread of evaluation figures over several runs (training seeds).

Usage: scripts/seed-spread.py LABEL=EVAL_JSON [LABEL=EVAL_JSON ...]

Each EVAL_JSON is an eval-<scenario>.json written by `comorph eval` (copy it
away before the next eval of the same run overwrites it). Prints one Markdown
table: a row per run, then the mean, the standard deviation (n - 1) and the
range of every column: success per stair height and on average (%), F(H), the
mean number of modules at the first decision per height, and the share of the
episodes that reach the flat area and shed to 2 or 3 modules (%).
"""
import json
import statistics
import sys

HEIGHTS = ("0.04", "0.06", "0.08")


def row_of(path):
    try:
        with open(path) as f:
            e = json.load(f)
        success = e["success_rate"]
        first = e["first_modules"]
        return ([100 * success[h] for h in HEIGHTS] + [100 * success["avg"], e["F"]] +
                [first[h] for h in HEIGHTS] + [100 * e["shed_after_stairs"]])
    except (OSError, ValueError, KeyError, TypeError) as err:
        sys.exit(f"{path}: not an eval-<scenario>.json of comorph eval ({err!r})")


def main(argv):
    if not argv or any("=" not in a for a in argv):
        sys.exit(__doc__.strip())
    header = (["run"] + [f"success {h} m (%)" for h in HEIGHTS] + ["avg (%)", "F(H)"] +
              [f"first {h} m (modules)" for h in HEIGHTS] + ["shed to 2-3 (%)"])
    digits = [0, 0, 0, 1, 3, 2, 2, 2, 0]
    rows = [(label, row_of(path)) for label, path in (a.split("=", 1) for a in argv)]

    def line(cells):
        return "| " + " | ".join(cells) + " |"

    def fmt(values):
        return [f"{v:.{d}f}" for v, d in zip(values, digits)]

    print(line(header))
    print(line(["---"] * len(header)))
    for label, values in rows:
        print(line([label] + fmt(values)))
    columns = list(zip(*(values for _, values in rows)))
    print(line(["**mean**"] + fmt([statistics.mean(c) for c in columns])))
    if len(rows) > 1:
        print(line(["std"] + fmt([statistics.stdev(c) for c in columns])))
        print(line(["range"] + [f"{a}-{b}" for a, b in zip(fmt([min(c) for c in columns]),
                                                           fmt([max(c) for c in columns]))]))


if __name__ == "__main__":
    main(sys.argv[1:])
