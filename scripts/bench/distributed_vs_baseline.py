#!/usr/bin/env python3
"""Distributed solvers (RBCD, RBCD++, IRBCD) on the benchmark graphs, beside the public
RBCD/RBCD++ baseline of ../shared/reference/dpgo_baseline.csv.

For each graph and algorithm: N = 5 agents, `highest` partition, chordal initialisation; rounds
to ||grad f|| <= 0.2 (= the baseline's 0.1, whose gradient is of half the cost), 0.1 and 0.01,
final relative gap to f*, milliseconds per round. Prints one table and writes it as CSV.

usage: distributed_vs_baseline.py [--bin build/bin/tessera] [--graphs CSAIL,intel] [--max-rounds 5000]
                                  [--algorithms rbcd,rbcd++,irbcd] [--extra "--parallel"] [--out FILE.csv]
                                  [--timeout SECONDS] [--repeat-short K] [--short-s SECONDS]

Rounds are those of the solver's defaults: a round updates a whole colour class
of blocks (an independent set, `--parallel`, the default); `--extra=--sequential` gives one block
per round, as the baseline counts them (docs/irbcd.md section 4).

`ms/round` is wall time per round of the in-process solve (all N agents in one process, like the
baseline's runs); `cpu ms/r` is the process CPU time per round, the figure to trust on a loaded
machine; `crit ms/r` the CPU time per round of the slowest agent of each exchange (what a round
costs when every agent has its own machine, latency excluded); `cpu/base` = cpu ms/r over the
baseline's ms/round (the issue's target: <= 0.1).
A run that exceeds --timeout (wall seconds) is reported as such and skipped.

Short solves are timed several times: when a run's in-process solve takes less than --short-s
wall seconds (default 0.3; e.g. parking-garage's 20 rounds take ~0.04 s), the same command is run
--repeat-short times in all (default 5) and `ms/round`, `cpu ms/r`, `crit ms/r` (and so
`cpu/base`) are the medians over those runs; the `runs` column says how many. A single sample of
such a run moved by +-50 % between identical runs (0.111, 0.171, 0.112 on parking-garage). The
solves are deterministic, so rounds, restarts and gaps are the same in every repetition (a
mismatch is reported on stderr). Longer solves are timed once.
"""
import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
SHARED = os.path.abspath(os.path.join(ROOT, "..", "shared"))
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402


def run(binary, graph, algorithm, fstar, max_rounds, extra, timeout):
    with tempfile.TemporaryDirectory() as tmp:
        js, tr = os.path.join(tmp, "r.json"), os.path.join(tmp, "t.csv")
        cmd = [binary, "solve", graph, "--algorithm", algorithm, "--agents", "5", "--partition", "highest",
               "--init", "chordal", "--grad-tol", "0.01", "--max-rounds", str(max_rounds),
               "--reference-cost", repr(fstar), "--json", js, "--trace", tr] + extra
        try:
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            sys.stderr.write("%s %s: over the %s s time limit\n" % (graph, algorithm, timeout))
            return None
        if p.returncode != 0:
            sys.stderr.write(p.stdout + p.stderr)
            return None
        with open(js) as f:
            summary = json.load(f)
        with open(tr) as f:
            trace = [{"round": int(r["round"]), "grad_norm": float(r["grad_norm"])} for r in csv.DictReader(f)]
    return summary, trace


def timed_runs(binary, graph, algorithm, fstar, max_rounds, extra, timeout, repeat, short_s):
    """One run, or `repeat` runs when the solve is shorter than short_s: the summary of the
    first with the timing fields replaced by their medians, its trace, and the number of runs."""
    res = run(binary, graph, algorithm, fstar, max_rounds, extra, timeout)
    if res is None:
        return None
    summary, trace = res
    samples = [summary]
    if summary.get("solve_s", 0.0) < short_s:
        for _ in range(repeat - 1):
            more = run(binary, graph, algorithm, fstar, max_rounds, extra, timeout)
            if more is None:
                break
            if (more[0]["rounds"], more[0]["restarts"]) != (summary["rounds"], summary["restarts"]):
                sys.stderr.write("%s %s: rounds differ between repetitions (%s vs %s)\n" % (
                    graph, algorithm, more[0]["rounds"], summary["rounds"]))
            samples.append(more[0])
    for key in ("ms_per_round", "cpu_ms_per_round", "critical_path_cpu_s", "solve_s", "solve_cpu_s"):
        values = [x[key] for x in samples if x.get(key) is not None]
        if values:
            summary[key] = statistics.median(values)
    return summary, trace, len(samples)


def fmt(x, spec="{}"):
    return "-" if x is None or x == "" else spec.format(x)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin", "tessera"))
    ap.add_argument("--graphs", default="")
    ap.add_argument("--algorithms", default="rbcd,rbcd++,irbcd")
    ap.add_argument("--max-rounds", type=int, default=5000)
    ap.add_argument("--extra", default="")
    ap.add_argument("--out", default="")
    ap.add_argument("--timeout", type=float, default=None, help="wall seconds per run")
    ap.add_argument("--repeat-short", type=int, default=5,
                    help="runs whose median is reported when a solve is shorter than --short-s")
    ap.add_argument("--short-s", type=float, default=0.3,
                    help="wall seconds of the solve below which a run is repeated")
    a = ap.parse_args()
    fs = {k: float(r["f_star"]) for k, r in bc.read_reference(SHARED, "optima.csv", "dataset").items()}
    base = bc.read_reference(SHARED, "dpgo_baseline.csv", "dataset", "partition", "algorithm")
    names = a.graphs.split(",") if a.graphs else sorted(
        k for k in fs if not k.endswith("_qnorm"))
    rows = []
    if a.repeat_short < 1:
        ap.error("--repeat-short must be >= 1")
    head = ("graph", "alg", "r@0.2", "r@0.1", "r@0.01", "rounds", "restarts", "rel_gap", "ms/round",
            "cpu ms/r", "crit ms/r", "runs", "base r@0.2", "base ms/round", "cpu/base")
    print("# times per round: median of %d runs when the solve takes < %.2f s, else one run" % (
        a.repeat_short, a.short_s))
    print("%-24s %-6s %6s %6s %6s %6s %5s %9s %8s %8s %9s %4s | %10s %13s %8s" % head)
    for name in names:
        graph = os.path.join(SHARED, "datasets", name + ".g2o")
        # The reader normalises edge quaternions, so the unit-quaternion optimum applies.
        fstar = fs.get(name + "_qnorm", fs[name])
        for alg in a.algorithms.split(","):
            res = timed_runs(a.bin, graph, alg, fstar, a.max_rounds, a.extra.split(), a.timeout,
                             a.repeat_short, a.short_s)
            if res is None:
                print("%-24s %-6s failed or over the time limit" % (name, alg), flush=True)
                continue
            s, trace, runs = res
            b = base.get((name, "highest", {"rbcd": "RBCD", "rbcd++": "RBCD++"}.get(alg, "RBCD++")), {})
            row = {"graph": name, "algorithm": alg, "rounds_to_0.2": bc.first_round(trace, 0.2),
                   "rounds_to_0.1": bc.first_round(trace, 0.1), "rounds_to_0.01": bc.first_round(trace, 0.01),
                   "rounds": s["rounds"], "restarts": s["restarts"], "rel_gap": s["rel_gap"],
                   "ms_per_round": s["ms_per_round"], "cpu_ms_per_round": s.get("cpu_ms_per_round"),
                   "critical_ms_per_round": (1e3 * s["critical_path_cpu_s"] / s["rounds"]
                                             if s.get("critical_path_cpu_s") is not None and s["rounds"] else None),
                   "parallel": s.get("parallel"), "stop": s["stop_reason"], "timing_runs": runs,
                   "baseline_rounds_to_0.2": b.get("rounds_to_grad_0.1"),
                   "baseline_ms_per_round": b.get("ms_per_round")}
            bms = float(b["ms_per_round"]) if b.get("ms_per_round") else None
            row["cpu_over_baseline"] = (row["cpu_ms_per_round"] / bms
                                        if bms and row["cpu_ms_per_round"] is not None else None)
            rows.append(row)
            print("%-24s %-6s %6s %6s %6s %6d %5d %9s %8.2f %8s %9s %4d | %10s %13s %8s" % (
                name, alg, fmt(row["rounds_to_0.2"]), fmt(row["rounds_to_0.1"]), fmt(row["rounds_to_0.01"]),
                s["rounds"], s["restarts"], fmt(s["rel_gap"], "{:.1e}"), s["ms_per_round"],
                fmt(row["cpu_ms_per_round"], "{:.2f}"), fmt(row["critical_ms_per_round"], "{:.2f}"), runs,
                fmt(row["baseline_rounds_to_0.2"]), fmt(row["baseline_ms_per_round"]),
                fmt(row["cpu_over_baseline"], "{:.3f}")), flush=True)
    if a.out:
        bc.write_csv(a.out, rows, announce=False)


if __name__ == "__main__":
    main()
