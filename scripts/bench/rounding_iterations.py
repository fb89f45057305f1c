#!/usr/bin/env python3
"""All-agent steps of the distributed rounding's translation solve: from zero to a residual of
1e-12 (the rounding before the warm start) against the default (the iterate's translations as
the start, stop once the cost has settled to 1e-10 of f(X)).

Each CG iteration of the rounding (core/runtime/distributed_rounding.cpp) is one all-agent sum,
a barrier step of every agent; at a million poses over 25 processes that is seconds. The
counts come from the rounding run in process (one thread per agent over an in-memory channel,
the code the DDS agents run) on the in-process solver's iterate: build/bin/rounding_iterations_bench
(tests/rounding_iterations_bench.cpp), on each shared paper graph with 5 contiguous blocks, after
30 rounds and at the default tolerance (0.01). Counts and costs do not depend on the load.

Prints a table and writes docs/benchmarks/rounding_iterations.csv.

usage: rounding_iterations.py [--bench build/bin/rounding_iterations_bench] [--csv FILE]
                              [--from-output SAVED_BENCH_OUTPUT]
(15 min at load 40 on 2 cores; most of it the in-process solves.)
"""
import argparse
import csv
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_common as bc  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bench", default=os.path.join(ROOT, "build", "bin", "rounding_iterations_bench"))
    ap.add_argument("--csv", default=os.path.join(bc.OUT_DIR, "rounding_iterations.csv"))
    ap.add_argument("--from-output", help="read a saved output of the bench instead of running it")
    args = ap.parse_args()
    if args.from_output:
        with open(args.from_output) as f:
            out = f.read()
    else:
        out = subprocess.run([args.bench], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                             text=True, check=True).stdout
    rows = []
    for line in out.splitlines():
        if not line.startswith("ROUNDING "):
            continue
        _, graph, rounds, cold, warm, excess, bound = line.split()
        rows.append({"graph": graph, "rounds": int(rounds), "cg_from_zero_1e-12": int(cold),
                     "cg_warm_settled": int(warm), "cost_above_exact": float(excess),
                     "stop_target": float(bound),
                     "above_over_target": round(float(excess) / float(bound), 3)})
    print("| graph | solver rounds | CG iterations, from zero to 1e-12 | warm start, cost stop | "
          "rounded cost above the exact solve's | stop target (1e-10 f(X)) | above / target |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['graph']} | {r['rounds']} | {r['cg_from_zero_1e-12']} | {r['cg_warm_settled']} | "
              f"{r['cost_above_exact']:.1e} | {r['stop_target']:.1e} | {r['above_over_target']} |")
    with open(args.csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()) if rows else ["graph"])
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {os.path.relpath(args.csv)}")


if __name__ == "__main__":
    main()
