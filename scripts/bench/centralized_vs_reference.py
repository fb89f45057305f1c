#!/usr/bin/env python3
"""Centralized solver vs the reference solver (SE-Sync) on every shared graph, at equal accuracy.

For each g2o file in the datasets folder: runs `tessera solve --algorithm centralized` as a whole
process (loading included) and reads its JSON summary. The bar is the reference timed side by side
with Tessera on this machine kind, `../shared/reference/sesync_times.csv` (its 2-thread column; its
stock 4 threads oversubscribe 2 cores), together with how far the reference's answer is above f*
(its stopping rule's accuracy). With `--reference-bin PATH` (the reference's example driver, for a
user who has it built) the reference also runs here, alternately with Tessera, and its wall is
measured in the same run instead of read from the CSV.

Printed per graph: our median wall and CPU (user + system) time, the reference's wall, the ratio,
our relative gap to f* (optima.csv, _qnorm rows for 3D) beside the reference's, `acc` = ours is at
least as accurate as the reference's (gap <= max(reference gap, 1e-8): below 1e-8 both are
round-off and stopping-rule noise), the stop reason, steps, certificate, the preconditioner that ran. Writes
docs/benchmarks/centralized.csv. Wall times depend on the machine's load: the load average is
printed at the start and the end; CPU time is the steadier figure on a shared machine.

  scripts/bench/centralized_vs_reference.py [--shared ../shared] [--bin build/bin/tessera]
      [--only NAME,...] [--repeat K] [--reference-bin PATH [--reference-threads T]]
      [-- extra tessera solve flags, e.g. --stop gradient]
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402

# Below this relative gap both answers are f* as far as the stopping rules resolve it.
GAP_FLOOR = 1e-8


def median(xs):
    xs = sorted(xs)
    return xs[len(xs) // 2]


def run_ours(a, graph):
    with tempfile.NamedTemporaryFile(suffix=".json") as js:
        t0 = time.perf_counter()
        c0 = bc.children_usage()
        p = subprocess.run([a.bin, "solve", graph, "--algorithm", "centralized", "--json", js.name] + a.extra,
                           capture_output=True, text=True)
        wall = time.perf_counter() - t0
        cpu = bc.cpu_since(c0)
        if p.returncode != 0:
            raise RuntimeError(p.stderr.strip())
        return wall, cpu, json.load(open(js.name))


def run_reference(a, graph):
    """Wall and CPU of the reference driver on `graph`, and the objective it prints (if found)."""
    env = dict(os.environ, OMP_NUM_THREADS=str(a.reference_threads))
    t0 = time.perf_counter()
    c0 = bc.children_usage()
    p = subprocess.run([a.reference_bin, graph], capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    cpu = bc.cpu_since(c0)
    if p.returncode != 0:
        raise RuntimeError(f"reference: exit {p.returncode}: {p.stderr.strip()[-300:]}")
    # The example driver prints the rounded estimate's objective last; take the last number on a
    # line that names an objective value.
    value = None
    for line in p.stdout.splitlines():
        if re.search(r"objective", line, re.I):
            nums = re.findall(r"[-+]?\d+\.\d*(?:[eE][-+]?\d+)?", line)
            if nums:
                value = float(nums[-1])
    return wall, cpu, value


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--shared", default=os.path.join(ROOT, "..", "shared"))
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin", "tessera"))
    ap.add_argument("--only", default="")
    ap.add_argument("--repeat", type=int, default=1, help="runs per graph; the median time is reported")
    ap.add_argument("--reference-bin", default="",
                    help="the reference solver's example driver (run as PATH GRAPH.g2o); timed here")
    ap.add_argument("--reference-threads", type=int, default=2,
                    help="OMP_NUM_THREADS for --reference-bin (default 2, the CSV's bar)")
    ap.add_argument("--csv", default=os.path.join(ROOT, "docs", "benchmarks", "centralized.csv"))
    ap.add_argument("extra", nargs="*", help="extra flags for tessera solve (after --)")
    a = ap.parse_args()
    datasets = os.path.join(a.shared, "datasets")
    if not os.path.isdir(datasets):
        sys.exit(f"datasets folder not found: {datasets} (pass --shared)")
    if a.reference_bin and not os.access(a.reference_bin, os.X_OK):
        sys.exit(f"--reference-bin: not an executable file: {a.reference_bin}")
    optima = bc.read_reference(a.shared, "optima.csv", "dataset")
    times_csv = bc.read_reference(a.shared, "sesync_times.csv", "dataset")
    names = sorted(f[:-4] for f in os.listdir(datasets) if f.endswith(".g2o"))
    if a.only:
        names = [n for n in names if n in a.only.split(",")]
    print(f"machine at start: {bc.machine()}")
    print(f"tessera: {a.bin} {' '.join(a.extra)}".rstrip())
    ref_source = (f"{a.reference_bin}, OMP_NUM_THREADS={a.reference_threads}, timed in this run" if a.reference_bin
                  else "sesync_times.csv, reference_wall_s_2threads")
    print(f"reference: {ref_source}")
    head = (f"{'dataset':24s} {'poses':>6s} {'ours_s':>7s} {'cpu_s':>6s} {'ref_s':>6s} {'ratio':>6s} "
            f"{'rel_gap':>9s} {'ref_gap':>9s} {'acc':>4s} {'steps':>5s} {'stop':>24s} {'cert':>5s} precon")
    print(head)
    rows = []
    for name in names:
        graph = os.path.join(datasets, name + ".g2o")
        opt = optima.get(name + "_qnorm") or optima.get(name)
        tref = times_csv.get(name)
        walls, cpus, ref_walls, ref_values = [], [], [], []
        try:
            for _ in range(a.repeat):
                wall, cpu, summary = run_ours(a, graph)
                walls.append(wall)
                cpus.append(cpu)
                if a.reference_bin:
                    rw, _, rv = run_reference(a, graph)
                    ref_walls.append(rw)
                    ref_values.append(rv)
        except RuntimeError as e:
            print(f"{name}: failed: {e}")
            continue
        wall, cpu = median(walls), median(cpus)
        fstar = float(opt["f_star"]) if opt else None
        gap = (summary["cost"] - fstar) / fstar if fstar else None
        if a.reference_bin:
            ref_s = median(ref_walls)
            rv = ref_values[-1]
            ref_gap = (rv - fstar) / fstar if (rv is not None and fstar) else None
        else:
            ref_s = float(tref["reference_wall_s_2threads"]) if tref else None
            g = tref.get("reference_rel_gap_to_fstar", "") if tref else ""
            ref_gap = float(g) if g else None
        ratio = wall / ref_s if ref_s else None
        acc = None
        if gap is not None and ref_gap is not None:
            acc = gap <= max(ref_gap, GAP_FLOOR)
        row = dict(dataset=name, poses=summary["poses"], edges=summary["edges"], wall_s=round(wall, 3),
                   cpu_s=round(cpu, 3), reference_wall_s=ref_s, reference_source=ref_source,
                   ratio=round(ratio, 3) if ratio else "", cost=summary["cost"], f_star=fstar if fstar else "",
                   rel_gap=gap if gap is not None else "", reference_rel_gap=ref_gap if ref_gap is not None else "",
                   at_least_as_accurate="" if acc is None else acc, iterations=summary["iterations"],
                   stop_reason=summary.get("stop_reason", ""), certified=summary["certified"],
                   preconditioner=summary.get("preconditioner", ""),
                   inner_iterations=summary.get("inner_iterations", ""),
                   min_eigenvalue=summary["min_eigenvalue"], rank=summary["final_rank"],
                   load_avg_1min=round(os.getloadavg()[0], 2))
        rows.append(row)
        print(f"{name:24s} {row['poses']:6d} {wall:7.3f} {cpu:6.3f} {bc.fmt(ref_s, '{:6.3f}'):>6s} "
              f"{bc.fmt(ratio, '{:6.2f}'):>6s} {bc.fmt(gap, '{:9.2e}'):>9s} {bc.fmt(ref_gap, '{:9.2e}'):>9s} "
              f"{bc.fmt('' if acc is None else ('yes' if acc else 'NO')):>4s} {row['iterations']:5d} "
              f"{row['stop_reason']:>24s} {str(row['certified']):>5s} {row['preconditioner']}", flush=True)
    print(f"machine at end: {bc.machine()}")
    if rows:
        os.makedirs(os.path.dirname(a.csv), exist_ok=True)
        bc.write_csv(a.csv, rows, announce=False)
        timed = [r for r in rows if r["ratio"] != ""]
        if timed:
            worst = max(timed, key=lambda r: r["ratio"])
            slower = [r["dataset"] for r in timed if r["ratio"] > 1]
            print(f"\nworst wall ratio (ours / reference): {worst['ratio']:.2f} ({worst['dataset']}); "
                  f"slower than the reference: {', '.join(slower) if slower else 'none'}")
        print(f"all certified: {all(r['certified'] for r in rows)}; at least as accurate as the reference "
              f"(gap <= max(reference gap, {GAP_FLOOR:g})): "
              f"{sum(1 for r in rows if r['at_least_as_accurate'] is True)} of "
              f"{sum(1 for r in rows if r['at_least_as_accurate'] != '')}")


if __name__ == "__main__":
    main()
