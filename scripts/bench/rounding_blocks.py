#!/usr/bin/env python3
"""The distributed rounding's translation CG against the number of blocks, with and without the
coarse level of its preconditioner (one translation offset per block).

Each CG iteration of the rounding (core/runtime/distributed_rounding.cpp) is one all-agent
message step; at a million poses over 64 processes that was seconds a step, and with block
Jacobi alone the steps grow with the number of blocks. The counts come from the agents' code run
in process (one thread per agent over an in-memory channel): build/bin/rounding_blocks_bench
(tests/rounding_blocks_bench.cpp) on a generated 3D grid (`tessera generate --kind grid3d`,
robots = blocks, seed 1), split by the `fast` partition into N blocks, after a few rounds of the
in-process solver (a far warm start, as a run capped by --max-rounds leaves it). Per N and
preconditioner: CG iterations to the default stop (cost settled to 1e-10 of f(X)) and to the
residual stop alone (1e-12 of b's), and the settled cost above the latter's. Counts and costs do
not depend on the load.

Prints a table and writes docs/benchmarks/rounding_blocks.csv.

usage: rounding_blocks.py [--poses 100000] [--blocks 16,25,64] [--rounds 5]
                          [--bench build/bin/rounding_blocks_bench] [--csv FILE]
                          [--from-output SAVED_BENCH_OUTPUT...]
(100,000 poses, N = 16, 25, 64: ~20 min on 2 cores at load 10-15; most of it the in-process
solves. docs/benchmarks/rounding_blocks.csv holds that run, --poses 200000 --blocks 64 (~20 min) and
--poses 20000 --rounds 100.)
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
    ap.add_argument("--bench", default=os.path.join(ROOT, "build", "bin", "rounding_blocks_bench"))
    ap.add_argument("--poses", type=int, default=100000)
    ap.add_argument("--blocks", default="16,25,64")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--csv", default=os.path.join(bc.OUT_DIR, "rounding_blocks.csv"))
    ap.add_argument("--from-output", nargs="+",
                    help="read saved outputs of the bench (one table) instead of running it")
    args = ap.parse_args()
    if args.from_output:
        out = ""
        for name in args.from_output:
            with open(name) as f:
                out += f.read()
    else:
        out = subprocess.run([args.bench, "--poses", str(args.poses), "--blocks", args.blocks,
                              "--rounds", str(args.rounds)], stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, text=True, check=True).stdout
    rows = []
    for line in out.splitlines():
        if not line.startswith("ROUNDING_BLOCKS "):
            continue
        _, poses, blocks, rounds, cut, coarse, settled, exact, excess, target = line.split()
        rows.append({"poses": int(poses), "blocks": int(blocks), "rounds": int(rounds),
                     "cut": int(cut), "preconditioner": "two-level" if coarse == "1" else "block Jacobi",
                     "cg_settled": int(settled), "cg_to_1e-12": int(exact),
                     "cost_above_1e-12_solve": float(excess), "stop_target": float(target)})
    print("| poses | blocks | cut | solver rounds | preconditioner | CG steps, default stop | "
          "CG steps, residual 1e-12 | settled cost above the 1e-12 solve's | stop target |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['poses']} | {r['blocks']} | {r['cut']} | {r['rounds']} | {r['preconditioner']} | "
              f"{r['cg_settled']} | {r['cg_to_1e-12']} | {r['cost_above_1e-12_solve']:.1e} | "
              f"{r['stop_target']:.1e} |")
    if rows:
        with open(args.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)
        print(f"wrote {os.path.relpath(args.csv)}")


if __name__ == "__main__":
    main()
