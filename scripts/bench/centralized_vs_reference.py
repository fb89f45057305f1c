#!/usr/bin/env python3
"""Centralized solver vs the reference solver (SE-Sync) on every benchmark graph.

For each g2o file in the datasets folder: runs `tessera solve --algorithm centralized` as a
whole process (loading included), reads its JSON summary, and prints our wall time and CPU time (user + system, the
more reliable figure on a shared machine), the reference wall time from optima.csv, their ratio, the cost's relative gap to f*, and the
certificate. Writes docs/benchmarks/centralized.csv.

  scripts/bench/centralized_vs_reference.py [--shared ../shared] [--bin build/bin/tessera]
      [--only NAME,...] [--repeat K] [extra solver flags after --]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--shared", default=os.path.join(ROOT, "..", "shared"))
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin", "tessera"))
    ap.add_argument("--only", default="")
    ap.add_argument("--repeat", type=int, default=1, help="runs per graph; the median time is reported")
    ap.add_argument("--csv", default=os.path.join(ROOT, "docs", "benchmarks", "centralized.csv"))
    ap.add_argument("extra", nargs="*")
    a = ap.parse_args()
    datasets = os.path.join(a.shared, "datasets")
    if not os.path.isdir(datasets):
        sys.exit(f"datasets folder not found: {datasets} (pass --shared)")
    optima = bc.read_reference(a.shared, "optima.csv", "dataset")
    names = sorted(f[:-4] for f in os.listdir(datasets) if f.endswith(".g2o"))
    if a.only:
        names = [n for n in names if n in a.only.split(",")]
    rows = []
    print(f"{'dataset':28s} {'poses':>6s} {'ours_s':>8s} {'cpu_s':>8s} {'ref_s':>7s} {'ratio':>6s} {'cpu_r':>6s} {'rel_gap':>10s} {'cert':>5s} {'lam_min':>10s} {'rank':>4s}")
    for name in names:
        ref = optima.get(name + "_qnorm") or optima.get(name)
        times, cpus = [], []
        for _ in range(a.repeat):
            with tempfile.NamedTemporaryFile(suffix=".json") as js:
                t0 = time.perf_counter()
                c0 = bc.children_usage()
                p = subprocess.run([a.bin, "solve", os.path.join(datasets, name + ".g2o"), "--algorithm",
                                    "centralized", "--json", js.name] + a.extra, capture_output=True, text=True)
                times.append(time.perf_counter() - t0)
                cpus.append(bc.cpu_since(c0))
                if p.returncode != 0:
                    print(f"{name}: failed: {p.stderr.strip()}")
                    break
                summary = json.load(open(js.name))
        else:
            times.sort()
            cpus.sort()
            wall = times[len(times) // 2]
            cpu = cpus[len(cpus) // 2]
            ref_s = float(ref["reference_solver_wall_s"]) if ref else float("nan")
            fstar = float(ref["f_star"]) if ref else float("nan")
            gap = (summary["cost"] - fstar) / fstar if ref else float("nan")
            row = dict(dataset=name, poses=summary["poses"], edges=summary["edges"], wall_s=round(wall, 3),
                       cpu_s=round(cpu, 3), reference_s=ref_s, ratio=round(wall / ref_s, 3) if ref else "",
                       cpu_ratio=round(cpu / ref_s, 3) if ref else "", cost=summary["cost"],
                       f_star=fstar, rel_gap=gap, certified=summary["certified"],
                       min_eigenvalue=summary["min_eigenvalue"], rank=summary["final_rank"],
                       iterations=summary["iterations"])
            rows.append(row)
            print(f"{name:28s} {row['poses']:6d} {wall:8.3f} {cpu:8.3f} {ref_s:7.2f} {wall / ref_s:6.2f} {cpu / ref_s:6.2f} {gap:10.2e} "
                  f"{str(row['certified']):>5s} {row['min_eigenvalue']:10.2e} {row['rank']:4d}", flush=True)
    if rows:
        os.makedirs(os.path.dirname(a.csv), exist_ok=True)
        bc.write_csv(a.csv, rows, announce=False)
        worst = max(r["ratio"] for r in rows if r["ratio"] != "")
        worst_cpu = max(r["cpu_ratio"] for r in rows if r["cpu_ratio"] != "")
        print(f"\nworst time ratio (ours / reference): wall {worst:.2f}, cpu {worst_cpu:.2f}; all certified: "
              f"{all(r['certified'] for r in rows)}; max |rel gap|: {max(abs(r['rel_gap']) for r in rows):.2e}")


if __name__ == "__main__":
    main()
