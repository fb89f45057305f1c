#!/usr/bin/env python3
"""Where the wall time of `tessera launch G --agents N` goes, beside the centralized solver's wall in
the same run, on the paper graphs.

For each graph (default: the 10 of the paper's Table I that ../shared holds as g2o): runs
  launch       `tessera launch G --agents N` with launch's defaults (partition auto, IRBCD,
               chordal start, certificate on), whole process, and
  centralized  `tessera solve G --algorithm centralized`, whole process,
alternately, and prints the launch run's phases on its critical path, in seconds:
  startup      launch to the coordinator's DDS session (fork server, processes, participant)
  discovery    to every agent's announcement
  partition    what the partition took beyond the announcements (it runs on a thread of the
               coordinator while the agents start: 0 when hidden); its own duration is `part_s`
  assign       to every agent holding its assignment (the barrier)
  init         to the first round's status: the agents' initialisation (chordal start) and
               hand-off, their blocks' set-up
  rounds       first to last round status
  certificate  after the last round, the distributed certificate (and escapes): the time to the
               final estimates minus agent 0's rounding time (summary's rounding_ms)
  rounding     agent 0's distributed rounding (plus the final estimates' transfer)
  merge        to the merged summary printed by launch
  shutdown     summary to launch's exit (processes leave, participants are deleted)
agent 0's own clock for two parts of init, in the CSV: its initialisation stage (`init_own_s`;
with the chordal start solved while the run started, `init_early`, little more than the wait for
the others' values) and its hand-off (`handoff_own_s`); and the total, the centralized wall, their
ratio (launch to exit / centralized), the relative gap of each to f* (optima.csv), certification,
rounds and the load; the heaps' page size each side ran on (`heap_pages`, `centralized_heap_pages`,
and the probe's `fresh_page_us`: `--heap-pages auto` chooses per host, docs/dds-runtime.md).
Writes docs/benchmarks/launch_phases.csv.
Wall times depend on the machine's load: it is printed per graph; phases are the coordinator's
timeline (CLOCK_MONOTONIC, shared by the processes of the host) and agent 0's clock.

usage: launch_phases.py [--bin build/bin] [--graphs CSAIL,intel] [--agents 5] [--domain 65]
                        [--domains 5] [--repeat 1] [--csv FILE] [--limit S] [-- extra launch flags]
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402

PAPER_GRAPHS = ["CSAIL", "intel", "sphere2500", "torus3D", "parking-garage", "cubicle",
                "manhattan3500", "city10000", "kitti_02", "ais2klinik"]
PHASES = ["startup", "discovery", "partition", "assign", "init", "rounds", "certificate", "rounding",
          "merge", "shutdown"]


def run_launch(a, graph, domain, tmp):
    js = os.path.join(tmp, "launch.json")
    if os.path.exists(js):
        os.remove(js)
    u0 = bc.children_usage()
    t0 = time.monotonic()
    t0_ms = time.monotonic_ns() / 1e6
    p = subprocess.Popen([os.path.join(a.bin, "tessera"), "launch", graph, "--agents", str(a.agents),
                          "--domain", str(domain), "--json", js, "--timeout", str(a.limit)] + a.extra,
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1)
    summary_at, log = None, []
    for line in p.stdout:
        log.append(line)
        if line.startswith("summary:") and summary_at is None:
            summary_at = time.monotonic()
    p.wait()
    exit_wall = time.monotonic() - t0
    if p.returncode != 0 or not os.path.exists(js):
        print("".join(log[-15:]), file=sys.stderr)
        return None
    s = json.load(open(js))
    s["cpu_s"] = bc.cpu_since(u0)
    s["exit_wall_s"] = exit_wall
    s["summary_wall_s"] = (summary_at - t0) if summary_at else exit_wall
    s["phases_s"] = phases(s, t0_ms, s["summary_wall_s"], exit_wall)
    return s


def phases(s, t0_ms, summary_wall, exit_wall):
    tl = s.get("timeline_ms") or {}
    base = s["started_monotonic_ms"] - t0_ms  # coordinator start after launch, ms

    def at(mark):
        return (base + tl[mark]) / 1000 if mark in tl else None

    session, announced, partitioned = at("session"), at("announced"), at("partitioned")
    ready, first, last, finals = at("ready"), at("first_status"), at("last_status"), at("finals")
    gate = max(announced, partitioned)  # the assignment needs both
    # The round marks come from agent 0's progress digests (its clock, and the first digest's
    # arrival): under load they can stray past their neighbours; keep them in order.
    if first is not None and last is not None:
        first = min(max(first, ready), finals)
        last = min(max(last, first), finals)
    out = {"startup": session, "discovery": announced - session,
           "partition": max(0.0, partitioned - announced), "assign": ready - gate}
    rounding = (s.get("rounding_ms") or 0) / 1000
    if first is not None and last is not None:
        out["init"] = first - ready
        out["rounds"] = last - first
        after = finals - last
    else:  # no round status (a run without rounds)
        out["init"], out["rounds"] = finals - ready, 0.0
        after = 0.0
    out["certificate"] = max(0.0, after - rounding)
    out["rounding"] = min(after, rounding)
    out["merge"] = summary_wall - finals
    out["shutdown"] = exit_wall - summary_wall
    return out


def ms_to_s(ms):
    return round(ms / 1000, 4) if ms is not None else None


def run_centralized(a, graph, tmp):
    js = os.path.join(tmp, "central.json")
    u0 = bc.children_usage()
    t0 = time.monotonic()
    p = subprocess.run([os.path.join(a.bin, "tessera"), "solve", graph, "--algorithm", "centralized",
                        "--json", js], capture_output=True, text=True, timeout=a.limit)
    wall = time.monotonic() - t0
    if p.returncode != 0:
        print(p.stderr[-500:], file=sys.stderr)
        return None
    s = json.load(open(js))
    s["wall_s_process"] = wall
    s["cpu_s"] = bc.cpu_since(u0)
    return s


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin"))
    ap.add_argument("--shared", default=os.path.join(ROOT, "..", "shared"))
    ap.add_argument("--graphs", default="", help="comma-separated names (default: the paper graphs)")
    ap.add_argument("--agents", type=int, default=5)
    ap.add_argument("--domain", type=int, default=65, help="first DDS domain id of the runs")
    ap.add_argument("--domains", type=int, default=5, help="domain ids used in turn from --domain")
    ap.add_argument("--repeat", type=int, default=1, help="pairs per graph; medians are printed")
    ap.add_argument("--limit", type=float, default=600, help="seconds per run")
    ap.add_argument("--csv", default=os.path.join(ROOT, "docs", "benchmarks", "launch_phases.csv"))
    ap.add_argument("extra", nargs="*", help="extra tessera launch flags (after --)")
    a = ap.parse_args()
    names = [g for g in a.graphs.split(",") if g] or PAPER_GRAPHS
    optima = bc.read_reference(a.shared, "optima.csv", "dataset")
    print(f"machine at start: {bc.machine()}")
    print(f"launch: tessera launch G --agents {a.agents} {' '.join(a.extra)}".rstrip())
    head = ["graph", "poses"] + PHASES + ["total", "part_s", "central", "ratio", "gap", "c_gap", "cert",
                                          "rounds", "load"]
    print(" ".join(f"{h:>9s}" if i else f"{h:15s}" for i, h in enumerate(head)))
    rows, k = [], 0
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            graph = os.path.join(a.shared, "datasets", name + ".g2o")
            if not os.path.exists(graph):
                print(f"{name}: skipped (no {graph})")
                continue
            opt = optima.get(name + "_qnorm") or optima.get(name)
            fstar = float(opt["f_star"]) if opt else None
            runs = []
            for _ in range(a.repeat):
                c = run_centralized(a, graph, tmp)
                s = run_launch(a, graph, a.domain + k % max(1, a.domains), tmp)
                k += 1
                if c is None or s is None:
                    print(f"{name}: a run failed")
                    continue
                runs.append((s, c, os.getloadavg()[0]))
            if not runs:
                continue
            for s, c, load in runs:
                gap = (s["cost"] - fstar) / fstar if (fstar and s.get("cost") is not None) else None
                cgap = (c["cost"] - fstar) / fstar if fstar else None
                row = dict(graph=name, poses=s["num_poses"], agents=a.agents, partition=s["partition"],
                           cut_edges=s["cut_edges"], rounds=s["rounds"], certified=s["certified"],
                           **{p + "_s": round(s["phases_s"][p], 4) for p in PHASES},
                           total_s=round(s["exit_wall_s"], 4), to_summary_s=round(s["summary_wall_s"], 4),
                           partition_own_s=round(s["partition_ms"] / 1000, 4),
                           init_own_s=ms_to_s(s.get("init_ms")), handoff_own_s=ms_to_s(s.get("handoff_ms")),
                           init_early=s.get("init_early"),
                           launch_cpu_s=round(s["cpu_s"], 3), centralized_s=round(c["wall_s_process"], 4),
                           centralized_cpu_s=round(c["cpu_s"], 3),
                           ratio=round(s["exit_wall_s"] / c["wall_s_process"], 3),
                           rel_gap=gap, centralized_rel_gap=cgap, centralized_certified=c["certified"],
                           peak_rss_mb_agent_max=s.get("peak_rss_mb_agent_max"),
                           heap_pages=s.get("heap_pages"), centralized_heap_pages=c.get("heap_pages"),
                           fresh_page_us=s.get("fresh_page_us"), load_avg_1min=round(load, 2))
                rows.append(row)
            # the median pair by ratio
            med = sorted(rows[-len(runs):], key=lambda r: r["ratio"])[len(runs) // 2]
            cells = [name, str(med["poses"])] + [f"{med[p + '_s']:.3f}" for p in PHASES] + [
                f"{med['total_s']:.3f}", f"{med['partition_own_s']:.3f}", f"{med['centralized_s']:.3f}",
                f"{med['ratio']:.2f}", bc.fmt(med["rel_gap"], "{:.1e}"), bc.fmt(med["centralized_rel_gap"], "{:.1e}"),
                str(med["certified"]), str(med["rounds"]), f"{med['load_avg_1min']:.1f}"]
            print(" ".join(f"{c:>9s}" if i else f"{c:15s}" for i, c in enumerate(cells)), flush=True)
    print(f"machine at end: {bc.machine()}")
    if rows:
        # --heap-pages auto picks the heaps' page size per host (docs/dds-runtime.md): say which ran.
        probes = [r["fresh_page_us"] for r in rows if r["fresh_page_us"] is not None]
        print("heap pages: launch %s, centralized %s%s" % (
            "/".join(sorted({str(r["heap_pages"]) for r in rows})),
            "/".join(sorted({str(r["centralized_heap_pages"]) for r in rows})),
            f" (a fresh 4 KB page {min(probes):.1f}-{max(probes):.1f} us)" if probes else ""))
        os.makedirs(os.path.dirname(a.csv), exist_ok=True)
        bc.write_csv(a.csv, rows)
        big = [r for r in rows if r["poses"] >= 5000]
        if big:
            print("ratio launch / centralized on graphs with >= 5000 poses: median %.2f, max %.2f (goal <= 2)"
                  % (statistics.median(r["ratio"] for r in big), max(r["ratio"] for r in big)))
        share = {p: sum(r[p + "_s"] for r in rows) / sum(r["total_s"] for r in rows) for p in PHASES}
        top = max(share, key=share.get)
        print("share of the summed launch walls: " + ", ".join(f"{p} {100 * v:.0f}%" for p, v in share.items())
              + f"; largest: {top}")


if __name__ == "__main__":
    main()
