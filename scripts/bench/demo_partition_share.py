#!/usr/bin/env python3
"""The partition's share of the demo launch's wall time, over many consecutive launches.

Issue 27's bar: default `tessera launch` on the demo graph (`tessera generate --kind grid3d
--poses 1000 --robots 5 --seed 1`), partition at most 10 % of the run's wall time. Runs
`tessera launch demo.g2o --agents 5 --json F` (launch's defaults) `--runs` times in a row and
prints, per run, the summary's `partition_ms` (the partition's own wall), `partition_cpu_ms` (its
thread's CPU), `partition_wait_ms` (its share of the critical path), `discovery_ms` and
`wall_s` (the coordinator's, from its DDS session to the merged result), the share
partition_ms / wall_s, and the launch process's own wall from start to exit (`launch_s`); then
min / median / max and how many runs were over 10 %. `--busy K` keeps K busy-loop processes
(nice 0, in this script's session) running during the launches (K = 1: one of a 2-core host's
cores busy). `--compare="FLAGS"` alternates runs without and with FLAGS (`--runs` of each), so
that both meet the same load, and prints the paired differences. The load average is printed
before and after: wall figures depend on it.

usage: demo_partition_share.py [--bin build/bin] [--runs 20] [--busy 0] [--domains D1,D2]
                               [--compare="FLAGS"] [--csv FILE] [-- extra launch flags]
"""
import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))

FIELDS = ["partition_ms", "partition_cpu_ms", "partition_wait_ms", "discovery_ms", "wall_s"]


def load():
    with open("/proc/loadavg") as f:
        return f.read().split()[0]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin"))
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--busy", type=int, default=0, help="busy-loop processes during the runs")
    ap.add_argument("--domains", default="",
                    help="DDS domains, used in turn (default: launch derives one per run)")
    ap.add_argument("--compare", help="launch flags of every other run (--compare=\"FLAGS\")")
    ap.add_argument("--csv", help="write the runs' figures to this CSV")
    ap.add_argument("extra", nargs="*", help="extra launch flags (after --)")
    a = ap.parse_args()
    domains = [int(d) for d in a.domains.split(",") if d]
    tessera = os.path.join(a.bin, "tessera")
    rows = []
    busy = []
    with tempfile.TemporaryDirectory() as tmp:
        demo = os.path.join(tmp, "demo.g2o")
        subprocess.run([tessera, "generate", "--kind", "grid3d", "--poses", "1000", "--robots", "5",
                        "--seed", "1", "--out", demo], check=True, stdout=subprocess.DEVNULL)
        try:
            for _ in range(a.busy):
                busy.append(subprocess.Popen(["sh", "-c", "while :; do :; done"]))
            load_before = load()
            variants = [[]] + ([a.compare.split()] if a.compare else [])
            for r in range(a.runs * len(variants)):
                variant = variants[r % len(variants)]
                js = os.path.join(tmp, "run.json")
                if os.path.exists(js):
                    os.remove(js)
                t0 = time.monotonic()
                domain = ["--domain", str(domains[r % len(domains)])] if domains else []
                p = subprocess.run([tessera, "launch", demo, "--agents", "5", "--json", js] +
                                   domain + a.extra + variant,
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
                launch_s = time.monotonic() - t0
                if p.returncode != 0 or not os.path.exists(js):
                    print(p.stdout[-2000:], file=sys.stderr)
                    sys.exit("launch %d failed (exit %d)" % (r + 1, p.returncode))
                s = json.load(open(js))
                row = {f: s[f] for f in FIELDS}
                row["launch_s"] = launch_s
                row["share"] = s["partition_ms"] / (1000.0 * s["wall_s"])
                # The coordinator's clock from its start: its participant ready, every agent
                # announced (discovery_ms is the second minus the first).
                row["session_at_ms"] = s["timeline_ms"]["session"]
                row["announced_at_ms"] = s["timeline_ms"]["announced"]
                row["rounds"] = s["rounds"]
                row["certified"] = s["certified"]
                row["flags"] = " ".join(variant)
                rows.append(row)
                print("run %2d%s: partition_ms %6.2f  cpu %5.2f  wait %5.2f  discovery %6.1f  wall %.3f s"
                      "  launch %.3f s  share %5.1f %%" % (r // len(variants) + 1,
                                             " (%s)" % row["flags"] if row["flags"] else "",
                                             row["partition_ms"], row["partition_cpu_ms"],
                                             row["partition_wait_ms"], row["discovery_ms"],
                                             row["wall_s"], launch_s, 100 * row["share"]),
                      flush=True)
            load_after = load()
        finally:
            for b in busy:
                b.kill()
                b.wait()
    print("load average %s before, %s after; busy loops %d" % (load_before, load_after, a.busy))
    for variant in variants:
        flags = " ".join(variant)
        mine = [r for r in rows if r["flags"] == flags]
        print("launch defaults%s:" % (" + " + flags if flags else ""))
        for f in FIELDS + ["launch_s", "session_at_ms", "announced_at_ms", "share"]:
            v = [r[f] for r in mine]
            print("  %-18s min %8.3f  median %8.3f  max %8.3f" % (f, min(v), statistics.median(v),
                                                                  max(v)))
        over = sum(r["share"] > 0.10 for r in mine)
        print("  runs over 10 %%: %d of %d" % (over, len(mine)))
    if len(variants) == 2:  # runs side by side: paired differences, same load
        base = [r for r in rows if not r["flags"]]
        other = [r for r in rows if r["flags"]]
        for f in ("launch_s", "wall_s", "partition_ms"):
            d = [o[f] - b[f] for b, o in zip(base, other)]
            print("paired %s (+ %s) minus defaults: median %+.4f, lower in %d of %d" % (
                f, a.compare, statistics.median(d), sum(x < 0 for x in d), len(d)))
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)


if __name__ == "__main__":
    main()
