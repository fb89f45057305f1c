#!/usr/bin/env python3
"""Overhead of the DDS runtime over the in-process engine, side by side, on the paper graphs
(default: the 10 of the paper's 12 Table I graphs that ../shared holds as g2o; rim and grid3D are
METIS structure only and are skipped with a message).

For each graph: N agents (default 5), `highest` partition, IRBCD, both runs starting from the
same initial poses (`--init file`: the file's VERTEX poses; graphs without VERTEX lines get
their rounded chordal initialisation written to a temporary copy first, by
`tessera solve --max-rounds 0 --out`). Measured, as the user sees it (process start to exit; DDS: to the summary):
  in-process  `tessera solve G --algorithm irbcd --agents N --partition highest --init file`
  DDS         `tessera launch G --agents N --partition highest` (coordinator + N agents)
and printed: rounds of each (they differ only when the coordinator's partition differs: it
partitions the structure in the agents' announcement order, not file order), relative cost
difference, wall times and their ratio (target <= 1.5), median ms per round of the DDS run
(from the arrival times of its progress lines and their round numbers: the coordinator
prints at most ~10 lines a second, so each gap is divided by the rounds it spans), bytes per round (all agents' DDS bytes / rounds),
and where the DDS run's wall time went (the coordinator's timeline: start = launch to the
coordinator's session, discovery, partition, ready = assignment + barrier, handoff = to the first
round status, rounds, rounding = to the final estimates, merge, summary = to launch printing the
summary; then teardown = summary to launch's exit, not in the ratio; phases in the order their
ends came: when the coordinator partitions launch's file while the agents start, fork = launch
to the partition's start comes first and discovery, after the partition, is only the wait the
partition did not hide), and the partition's own duration on both sides (`partition_ms`: in the
DDS run it shares the 2 cores with the agents' start-up; CSV partition_inprocess_ms,
partition_dds_ms). The DDS wall time is the
issue's "from launch to summary": launch prints the summary as soon as the coordinator has written
it, and the processes leave after that (FINISHED, participant deletion; CSV: wall_dds_to_exit_s).
Also printed (and in the CSV): CPU seconds (user + system over all processes of each run) and the
DDS run's voluntary context switches, which stay meaningful on a loaded machine where wall times
do not.

launch starts its processes through tessera-fork-server by default (Fast DDS loaded once, the
coordinator and the agents forked from it); `--launch-args=--no-fork-server` execs each one, for
an A/B of the start-up cost (docs/dds-runtime.md, "Fork server").

`--repeat K` runs K alternated pairs (in process, then DDS) per graph and adds a line with the
median ratio and its range: on a shared or virtual machine one pair's in-process wall alone can
move by 20-40 % between passes, so a single pair of a short
graph says little. The final median is then over the graphs' medians; the CSV has a row per pair.

usage: dds_overhead.py [--bin build/bin] [--graphs CSAIL,intel] [--agents 5] [--domain 210]
                       [--out FILE.csv] [--limit S] [--launch-args="--no-fork-server"] [--repeat 1]
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
SHARED = os.path.abspath(os.path.join(ROOT, "..", "shared"))
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402


# The 12 graphs of the paper's Table I. rim and grid3D exist in ../shared only as METIS
# structure (no poses, no measurement values), so they cannot run; the default is the other 10.
PAPER_GRAPHS = ["CSAIL", "intel", "sphere2500", "torus3D", "parking-garage", "cubicle",
                "manhattan3500", "city10000", "kitti_02", "ais2klinik", "rim", "grid3D"]


def paper_graphs():
    names = []
    for name in PAPER_GRAPHS:
        if os.path.exists(os.path.join(SHARED, "datasets", name + ".g2o")):
            names.append(name)
        else:
            print("%s: skipped (no g2o in %s; the paper's rim and grid3D are METIS structure only)"
                  % (name, os.path.join(SHARED, "datasets")), flush=True)
    return names


def has_vertices(path):
    with open(path) as f:
        for line in f:
            if line.startswith("VERTEX"):
                return True
    return False


def run_in_process(tessera, graph, agents, tmp, limit):
    js = os.path.join(tmp, "inprocess.json")
    u0 = bc.children_usage()
    t0 = time.monotonic()
    try:
        p = subprocess.run([tessera, "solve", graph, "--algorithm", "irbcd", "--agents", str(agents),
                            "--partition", "highest", "--init", "file", "--json", js],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=limit)
    except subprocess.TimeoutExpired:
        print("in-process run over the %g s limit" % limit, file=sys.stderr)
        return None
    wall = time.monotonic() - t0
    if p.returncode != 0:
        print(p.stdout, file=sys.stderr)
        return None
    with open(js) as f:
        s = json.load(f)
    s["cpu_s"], s["csw"] = bc.usage_since(u0)
    return s, wall


ROUND_LINE = re.compile(r"round (\d+)( \(restart\))?:")


def run_dds(tessera, graph, agents, domain, tmp, limit, extra=()):
    js = os.path.join(tmp, "dds.json")
    u0 = bc.children_usage()
    t0 = time.monotonic()
    t0_ms = time.monotonic_ns() / 1e6
    p = subprocess.Popen([tessera, "launch", graph, "--agents", str(agents), "--partition",
                          "highest", "--domain", str(domain), "--json", js, "--timeout", str(limit),
                          # the same start as the in-process run (launch's own default is the
                          # distributed chordal stage), and no certificate (the in-process run has none)
                          "--init", "file", "--no-certify"] + list(extra),
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1)
    stamps = []
    log = []
    summary_at = None
    for line in p.stdout:
        log.append(line)
        m = ROUND_LINE.match(line)
        if m:
            stamps.append((time.monotonic(), int(m.group(1))))
        elif line.startswith("summary:") and summary_at is None:
            summary_at = time.monotonic()
    p.wait()
    exit_wall = time.monotonic() - t0
    # The wall time: from launch to the summary (launch prints it as soon as the
    # coordinator has written it; the processes' teardown follows, reported as "teardown").
    wall = summary_at - t0 if summary_at is not None else exit_wall
    if p.returncode != 0:
        print("".join(log[-20:]), file=sys.stderr)
        return None
    with open(js) as f:
        s = json.load(f)
    s["cpu_s"], s["csw"] = bc.usage_since(u0)
    # ms per round between consecutive progress lines (rate-limited: a line spans many rounds)
    gaps = [1000 * (tb - ta) / (kb - ka) for (ta, ka), (tb, kb) in zip(stamps, stamps[1:])
            if kb > ka]
    s["phases_s"] = phases(s, t0_ms, wall)
    s["phases_s"]["teardown"] = exit_wall - wall
    s["exit_wall_s"] = exit_wall
    return s, wall, (statistics.median(gaps) if gaps else float("nan"))


# Phases of the DDS run from the coordinator's timeline (milliseconds since its start, and
# that start on CLOCK_MONOTONIC, which time.monotonic() also reads): seconds per phase.
# Each phase ends at its mark; phases are taken in the order of their marks' times. With the
# graph file (launch's default) the coordinator partitions while the agents start:
# fork = launch to the coordinator's partition start (fork server, coordinator's main), start =
# to its participant, partition = to the partition's end, discovery = what the agents'
# announcements took beyond the partition (0 when they were all in by then).
PHASES = [("start", "session"), ("fork", "partition_start"), ("discovery", "announced"),
          ("partition", "partitioned"), ("ready", "ready"), ("handoff", "first_status"),
          ("rounds", "last_status"), ("rounding", "finals"), ("merge", "merged")]


def phases(summary, t0_ms, wall):
    tl = summary.get("timeline_ms")
    if not tl or "started_monotonic_ms" not in summary:
        return {}
    base = summary["started_monotonic_ms"] - t0_ms  # coordinator start after launch, ms
    out, prev = {}, 0.0
    for at, name in sorted((base + tl[mark], name) for name, mark in PHASES if mark in tl):
        out[name] = (at - prev) / 1000
        prev = at
    out["summary"] = wall - prev / 1000  # summary file written and printed by launch
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin"))
    ap.add_argument("--graphs", default="")
    ap.add_argument("--agents", type=int, default=5)
    ap.add_argument("--domain", type=int, default=210)
    ap.add_argument("--out", default="")
    ap.add_argument("--limit", type=float, default=600, help="seconds per run (each side)")
    ap.add_argument("--launch-args", default="",
                    help="extra options of the DDS run, e.g. --no-fork-server (exec each process)")
    ap.add_argument("--repeat", type=int, default=1,
                    help="alternated pairs (in process, DDS) per graph; K > 1 adds the median ratio")
    a = ap.parse_args()
    if a.repeat < 1:
        ap.error("--repeat must be at least 1")
    tessera = os.path.join(a.bin, "tessera")
    names = a.graphs.split(",") if a.graphs else paper_graphs()
    head = ("graph", "rounds ip", "rounds dds", "rel cost diff", "wall ip s", "wall dds s",
            "ratio", "dds ms/round", "bytes/round")
    print("DDS runs: tessera launch ... %s" % (a.launch_args or "(fork server)"))
    print("%-18s %9s %10s %13s %9s %10s %6s %12s %11s" % head)
    rows = []
    medians = []
    for name in names:
        graph_rows = []
        with tempfile.TemporaryDirectory() as tmp:
            graph = prepared_graph(tessera, name, tmp)  # once: every pair starts from it
            for pair in range(a.repeat):
                row = measure_pair(a, tessera, name, graph, tmp, pair)
                if row:
                    graph_rows.append(row)
        rows += graph_rows
        if graph_rows:
            ratios = [r["ratio"] for r in graph_rows]
            medians.append(statistics.median(ratios))
            if a.repeat > 1:
                print("    %s ratio over %d pairs: median %.2f, range %.2f..%.2f" % (
                    name, len(ratios), medians[-1], min(ratios), max(ratios)), flush=True)
    if medians:
        print("median ratio %.2f over %d graphs" % (statistics.median(medians), len(medians)))
    if a.out:
        bc.write_csv(a.out, rows, announce=False)


def prepared_graph(tessera, name, tmp):
    """The paper graph `name` with VERTEX poses: the file itself, or (no VERTEX lines) a copy in
    `tmp` with its rounded chordal initialisation, which both runs then start from."""
    src = os.path.join(SHARED, "datasets", name + ".g2o")
    if has_vertices(src):
        return src
    graph = os.path.join(tmp, name + ".g2o")
    subprocess.run([tessera, "solve", src, "--algorithm", "irbcd", "--agents", "1",
                    "--partition", "sequential", "--max-rounds", "0", "--out", graph],
                   check=True, stdout=subprocess.DEVNULL)
    return graph


def measure_pair(a, tessera, name, graph, tmp, pair):
    """One in-process run and one DDS run of `graph` (paper graph `name`, summaries written in
    `tmp`); prints them and returns the CSV row (None when either failed)."""
    ip = run_in_process(tessera, graph, a.agents, tmp, a.limit)
    dds = (run_dds(tessera, graph, a.agents, a.domain, tmp, a.limit, a.launch_args.split())
           if ip else None)
    if ip is None or dds is None:
        print("%-18s failed (%s)" % (name, "in-process" if ip is None else "dds"))
        return None
    (si, wi), (sd, wd, med) = ip, dds
    row = {"graph": name, "pair": pair + 1, "rounds_inprocess": si["rounds"],
           "rounds_dds": sd["rounds"],
           "rel_cost_diff": abs(sd["cost"] - si["cost"]) / abs(si["cost"]),
           "wall_inprocess_s": wi, "wall_dds_s": wd, "ratio": wd / wi,
           "wall_dds_to_exit_s": sd["exit_wall_s"],
           "dds_median_ms_per_round": med,
           "bytes_per_round": sd["bytes_exchanged"] / max(1, sd["rounds"])}
    for k, v in sd.get("phases_s", {}).items():
        row["dds_" + k + "_s"] = v
    print("%-18s %9d %10d %13.2e %9.2f %10.2f %6.2f %12.2f %11.0f" % (
        name, row["rounds_inprocess"], row["rounds_dds"], row["rel_cost_diff"],
        wi, wd, row["ratio"], med, row["bytes_per_round"]), flush=True)
    row.update({"cpu_inprocess_s": si["cpu_s"], "cpu_dds_s": sd["cpu_s"],
                "dds_voluntary_csw": sd["csw"]})
    print("    cpu s (user+sys, all processes): in-process %.2f, dds %.2f; dds voluntary context "
          "switches %d (%.0f per round)" % (si["cpu_s"], sd["cpu_s"], sd["csw"],
                                             sd["csw"] / max(1, sd["rounds"])), flush=True)
    if sd.get("phases_s"):
        print("    dds phases s: " + ", ".join("%s %.3f" % kv for kv in sd["phases_s"].items()) +
              "; in-process solve %.3f" % si.get("solve_s", float("nan")), flush=True)
    # The partition on both sides (the same call on the same structure): in the DDS run it
    # shares the cores with the agents' start-up, so its excess is what that start-up cost
    # the wall. In process, everything else (start, reading, set-up, output, exit) as "other".
    pi, pd = si.get("partition_ms"), sd.get("partition_ms")
    if pi is not None and pd is not None:
        row.update({"partition_inprocess_ms": pi, "partition_dds_ms": pd})
        print("    partition ms: in-process %.0f, dds %.0f (%+.0f); in-process other %.3f s"
              % (pi, pd, pd - pi, wi - pi / 1000 - si.get("solve_s", 0.0)), flush=True)
    return row


if __name__ == "__main__":
    main()
