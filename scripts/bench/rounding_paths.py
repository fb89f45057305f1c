#!/usr/bin/env python3
"""The distributed rounding's translations by the CG against the exact interface solve: message
steps (each a wait for every peer), CG iterations, and how far the rounded cost ends above core's
direct solve (round_solution), on each graph given (default: ais2klinik, city10000, kitti_02).

The rounding runs in process (one thread per agent over an in-memory channel, the code the DDS
agents run) on the in-process solver's iterate after launch's solve (`eco` partition, IRBCD,
gradient 0.01, certificate, `--refine auto` and `none` unless --refine says otherwise):
build/bin/rounding_paths_bench (tests/rounding_paths_bench.cpp). Counts and costs do not depend
on the load (the CPU milliseconds, all agents' threads, do a little). With --callgrind, each path
also runs alone under callgrind from the saved solve, counting only inside
DistributedRounding::run (every agent's thread; not the harness's set-up of the agents), and
its instruction count is added.

Prints a table and writes docs/benchmarks/rounding_paths.csv.

usage: rounding_paths.py [--bench build/bin/rounding_paths_bench] [--graphs a,b,c]
                         [--refine auto,none] [--agents N] [--callgrind] [--solved DIR]
                         [--csv FILE]
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_common as bc  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DATA = os.path.join(os.path.dirname(ROOT), "shared", "datasets")


def parse(out):
    rows = []
    for line in out.splitlines():
        if not line.startswith("ROUNDING_PATH "):
            continue
        (_, graph, poses, agents, cut, rounds, path, team, iters, steps, above, rel,
         cpu_ms) = line.split()
        rows.append({"graph": graph, "poses": int(poses), "agents": int(agents), "cut": int(cut),
                     "rounds": int(rounds), "path": path, "interface_poses": int(team),
                     "cg_iterations": int(iters), "message_steps": int(steps),
                     "cost_above_direct": float(above), "relative": float(rel),
                     "cpu_ms": float(cpu_ms)})
    return rows


def inclusive(callgrind_out, function):
    """Inclusive instructions of `function` (a name's start) in a callgrind output, 0 if absent."""
    text = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100",
                           callgrind_out], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                          text=True).stdout
    for line in text.splitlines():
        if ":" + function in line:
            return int(line.split()[0].replace(",", ""))
    return 0


def instructions(bench, graph, path, agents, solved_dir):
    """Instructions of one path's rounding (every agent's thread), from the saved solve: the
    whole DistributedRounding::run and its translation solve alone (run minus the rotations and
    the cost's share, plus the interface share, which is sent from within the rotations' step)."""
    out = os.path.join(solved_dir, path + ".callgrind")
    subprocess.run(["valgrind", "--tool=callgrind", "--instr-atstart=no", "--collect-atstart=no",
                    "--toggle-collect=tessera::agent::DistributedRounding::run(*",
                    "--callgrind-out-file=" + out, bench, "--agents", str(agents), "--path", path,
                    "--load", solved_dir, graph],
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    with open(out) as f:
        counts = [int(m.group(1)) for m in
                  (re.match(r"(?:summary|totals):\s+(\d+)", line) for line in f) if m]
    total = max(counts) if counts else 0
    ns = "tessera::agent::DistributedRounding::"
    solve = (total - inclusive(out, ns + "rotations()") - inclusive(out, ns + "cost_share()") +
             inclusive(out, ns + "send_interface_share()"))
    return total, solve


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bench", default=os.path.join(ROOT, "build", "bin", "rounding_paths_bench"))
    ap.add_argument("--graphs", default="ais2klinik,city10000,kitti_02")
    ap.add_argument("--refine", default="auto,none", help="launch's --refine values, in turn")
    ap.add_argument("--agents", type=int, default=5)
    ap.add_argument("--callgrind", action="store_true")
    ap.add_argument("--solved", default="",
                    help="keep the solves in DIR/REFINE/NAME.solved and reuse them when there")
    ap.add_argument("--csv", default=os.path.join(bc.OUT_DIR, "rounding_paths.csv"))
    args = ap.parse_args()
    rows = []
    for refine, g in [(f, g) for f in args.refine.split(",") for g in args.graphs.split(",")]:
        path = os.path.join(DATA, g + ".g2o")
        with tempfile.TemporaryDirectory() as tmp:
            solved = os.path.join(args.solved, refine) if args.solved else tmp
            os.makedirs(solved, exist_ok=True)
            keep = ["--load" if os.path.exists(os.path.join(solved, g + ".solved")) else "--save",
                    solved]
            out = subprocess.run([args.bench, "--agents", str(args.agents), "--refine", refine] +
                                 keep + [path], stdout=subprocess.PIPE,
                                 stderr=subprocess.STDOUT, text=True, check=True).stdout
            got = parse(out)
            for r in got:
                r["refine"] = refine
                if args.callgrind:
                    r["instructions"], r["solve_instructions"] = instructions(
                        args.bench, path, r["path"], args.agents, solved)
                print("ROW", r, flush=True)  # as it comes: a long run keeps what it measured
        rows += got
    print("| graph | poses | cut | refine | path | interface poses | CG iterations | message steps "
          "| rounded cost above the direct solve's (relative) | CPU ms |" +
          (" instructions: rounding / translation solve |" if args.callgrind else ""))
    print("|---|---|---|---|---|---|---|---|---|---|" + ("---|" if args.callgrind else ""))
    for r in rows:
        print(f"| {r['graph']} | {r['poses']} | {r['cut']} | {r['refine']} | {r['path']} | "
              f"{r['interface_poses']} | {r['cg_iterations']} | {r['message_steps']} | "
              f"{r['relative']:.1e} | {r['cpu_ms']:.0f} |" +
              (f" {r['instructions'] / 1e6:.1f} M / {r['solve_instructions'] / 1e6:.1f} M |"
               if args.callgrind else ""))
    bc.write_csv(args.csv, rows)


if __name__ == "__main__":
    main()
