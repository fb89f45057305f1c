#!/usr/bin/env python3
"""Partition quality and speed of every preset on the reference paper's 12 benchmark graphs.

For N = 5 (eps 0.03): runs `tessera partition GRAPH --parts 5 --preset P --json -` for P in
sequential, fast, eco, strong, highest and prints, per graph, each preset's cut (sum of cut
measurements), max_block_ratio, Cvolume and partitioning time (time_ms from the JSON, i.e.
without loading) next to the paper's numbers (../shared/datasets/PAPER_PARTITIONS.md, Table 2;
the paper's printed `strong`/`fast` labels are swapped relative to its files, the columns here
follow the printed table). Checks the targets: highest <= paper highest, strong <= 1.05 x paper
highest, fast < 50 ms, highest < 5 s. Then the same for N = 4, 9, 16, 25 on the larger graphs.
Writes docs/benchmarks/partition_quality.csv and docs/benchmarks/partition_quality_k.csv.

  scripts/bench/partition_quality.py [--shared ../shared] [--bin build/bin/tessera]
      [--seeds 1] [--only rim,city10000] [--presets fast,eco,...] [--no-k] [--jobs 1]

--jobs J runs J partitioner processes at a time (default 1): faster on a busy host, but wall
times are then inflated by the sharing; the CPU time column is not.

With --seeds S > 1 every run is repeated with seeds 1..S and the mean cut, the best cut and
the median time are reported.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402

# name, file (under datasets/), paper label, paper cuts as printed in Table I:
# (baseline, strong, eco, fast, highest) -- baseline as printed (mostly 2x the true cut).
GRAPHS = [
    ("rim", "metis/rim.graph", "Rim", (2964, 348, 302, 288, 243)),
    ("city10000", "city10000.g2o", "City", (16724, 201, 156, 135, 129)),
    ("CSAIL", "CSAIL.g2o", "Csail", (232, 13, 11, 10, 9)),
    ("intel", "intel.g2o", "Intel", (444, 43, 39, 40, 34)),
    ("grid3D", "metis/grid3D.graph", "Grid", (3092, 1184, 980, 933, 925)),
    ("torus3D", "torus3D.g2o", "Torus", (798, 284, 261, 252, 240)),
    ("sphere2500", "sphere2500.g2o", "Sphere", (408, 182, 180, 187, 179)),
    ("parking-garage", "parking-garage.g2o", "Garage", (3715, 74, 82, 61, 28)),
    ("cubicle", "cubicle.g2o", "Cubicle", (3276, 202, 184, 180, 166)),
    ("kitti_02", "kitti_02.g2o", "Kitti02", (94, 9, 7, 6, 6)),
    ("manhattan3500", "manhattan3500.g2o", "Manhattan", (1059, 60, 48, 46, 41)),
    ("ais2klinik", "ais2klinik.g2o", "Ais2klinik", (1348, 26, 20, 15, 14)),
]
LARGE = ["rim", "city10000", "grid3D", "torus3D", "cubicle", "ais2klinik"]
PRESETS = ["sequential", "fast", "eco", "strong", "highest"]


def run(binary, path, parts, preset, seed, eps):
    cmd = [binary, "partition", path, "--parts", str(parts), "--preset", preset, "--seed", str(seed),
           "--eps", str(eps), "--json", "-"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"failed: {' '.join(cmd)}\n{p.stdout}{p.stderr}")
    return json.loads(p.stdout)


def measure(binary, path, parts, preset, seeds, eps):
    runs = [run(binary, path, parts, preset, s, eps) for s in range(1, seeds + 1)]
    cuts = [r["cut_edges"] for r in runs]
    return {
        "cut": statistics.mean(cuts),
        "best": min(cuts),
        "ratio": max(r["max_block_ratio"] for r in runs),
        "cvolume": statistics.mean(r["cvolume"] for r in runs),
        "ms": statistics.median(r["time_ms"] for r in runs),
        "cpu": statistics.median(r["cpu_ms"] for r in runs),
        "n": runs[0]["n"],
        "edges": runs[0]["edges"],
    }


def fmt_cut(m, seeds):
    return f"{m['cut']:.1f}/{m['best']}" if seeds > 1 else f"{m['best']}"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--shared", default=os.path.join(ROOT, "..", "shared"))
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin", "tessera"))
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--eps", type=float, default=0.03)
    ap.add_argument("--only", default="")
    ap.add_argument("--presets", default=",".join(PRESETS))
    ap.add_argument("--no-k", action="store_true", help="skip the N = 4, 9, 16, 25 runs")
    ap.add_argument("--jobs", type=int, default=1, help="partitioner processes run at a time")
    ap.add_argument("--csv", default=os.path.join(ROOT, "docs", "benchmarks", "partition_quality.csv"))
    ap.add_argument("--csv-k", default=os.path.join(ROOT, "docs", "benchmarks", "partition_quality_k.csv"))
    a = ap.parse_args()
    datasets = os.path.join(a.shared, "datasets")
    if not os.path.isdir(datasets):
        sys.exit(f"datasets folder not found: {datasets} (pass --shared)")
    presets = [p for p in a.presets.split(",") if p]
    graphs = [g for g in GRAPHS if not a.only or g[0] in a.only.split(",")]

    print(f"N = 5, eps = {a.eps}, seeds 1..{a.seeds}; cut = sum of cut measurements"
          + (" (mean/best)" if a.seeds > 1 else "") + "; ratio = max block / ceil(n/N); ms = partitioning wall time, cpu_ms = its CPU time")
    head = f"{'graph':15s} {'n':>6s} {'paper s/e/f/h':>18s}"
    for p in presets:
        head += f" | {p:>10s} {'ratio':>6s} {'Cvol':>6s} {'ms':>7s} {'cpu_ms':>7s}"
    print(head)
    pool = ThreadPoolExecutor(max(1, a.jobs))
    # Every (graph, N, preset) measurement is submitted up front; the tables print in order.
    pending = {}
    for name, rel, label, paper in graphs:
        for p in presets:
            pending[(name, 5, p)] = pool.submit(measure, a.bin, os.path.join(datasets, rel), 5, p,
                                                a.seeds, a.eps)
    if not a.no_k:
        for name, rel, label, paper in graphs:
            if name in LARGE:
                for parts in (4, 9, 16, 25):
                    for p in presets:
                        pending[(name, parts, p)] = pool.submit(
                            measure, a.bin, os.path.join(datasets, rel), parts, p, a.seeds, a.eps)
    rows, misses = [], []
    for name, rel, label, paper in graphs:
        line = None
        for p in presets:
            m = pending[(name, 5, p)].result()
            if line is None:
                line = f"{name:15s} {m['n']:6d} {'/'.join(map(str, paper[1:])):>18s}"
            line += f" | {fmt_cut(m, a.seeds):>10s} {m['ratio']:6.4f} {m['cvolume']:6.4f} {m['ms']:7.1f} {m['cpu']:7.1f}"
            rows.append({"graph": name, "n": m["n"], "edges": m["edges"], "parts": 5, "preset": p,
                         "seeds": a.seeds, "cut_mean": m["cut"], "cut_best": m["best"],
                         "max_block_ratio": m["ratio"], "cvolume": round(m["cvolume"], 6),
                         "time_ms": round(m["ms"], 2), "cpu_ms": round(m["cpu"], 2), "paper_highest": paper[4],
                         "paper_strong": paper[1], "paper_eco": paper[2], "paper_fast": paper[3]})
            if p == "highest" and m["cut"] > paper[4]:
                misses.append(f"{name}: highest {m['cut']:g} > paper {paper[4]}")
            if p == "strong" and m["cut"] > 1.05 * paper[4]:
                misses.append(f"{name}: strong {m['cut']:g} > 1.05 x paper highest {paper[4]}")
            if p == "fast" and m["ms"] >= 50:
                misses.append(f"{name}: fast {m['ms']:.1f} ms (cpu {m['cpu']:.1f}) >= 50 ms")
            if p == "highest" and m["ms"] >= 5000:
                misses.append(f"{name}: highest {m['ms']:.0f} ms (cpu {m['cpu']:.0f}) >= 5 s")
        print(line, flush=True)
    os.makedirs(os.path.dirname(a.csv), exist_ok=True)
    bc.write_csv(a.csv, rows, announce=False)
    print(f"\ntargets: {'all met' if not misses else str(len(misses)) + ' missed'}")
    for m in misses:
        print("  missed:", m)
    print(f"wrote {a.csv}")

    if a.no_k:
        return
    print(f"\nN = 4, 9, 16, 25 on the larger graphs (eps = {a.eps})")
    rows_k = []
    print(f"{'graph':15s} {'N':>3s}" + "".join(f" | {p:>10s} {'ratio':>6s} {'Cvol':>6s} {'ms':>7s} {'cpu_ms':>7s}" for p in presets))
    for name, rel, label, paper in graphs:
        if name not in LARGE:
            continue
        for parts in (4, 9, 16, 25):
            line = f"{name:15s} {parts:3d}"
            for p in presets:
                m = pending[(name, parts, p)].result()
                line += f" | {fmt_cut(m, a.seeds):>10s} {m['ratio']:6.4f} {m['cvolume']:6.4f} {m['ms']:7.1f} {m['cpu']:7.1f}"
                rows_k.append({"graph": name, "n": m["n"], "parts": parts, "preset": p, "seeds": a.seeds,
                               "cut_mean": m["cut"], "cut_best": m["best"], "max_block_ratio": m["ratio"],
                               "cvolume": round(m["cvolume"], 6), "time_ms": round(m["ms"], 2),
                               "cpu_ms": round(m["cpu"], 2)})
            print(line, flush=True)
    bc.write_csv(a.csv_k, rows_k, announce=False)
    print(f"wrote {a.csv_k}")


if __name__ == "__main__":
    main()
