#!/usr/bin/env python3
"""CPU seconds of each process of a `tessera launch` run, cut at the coordinator's timeline
marks: where the DDS run's extra CPU over the in-process run goes, phase by phase.

Each run is `tessera launch G --agents N --partition highest --init file --no-certify` (the
run of scripts/bench/dds_overhead.py; a graph without VERTEX lines first gets its rounded
chordal copy, as there). While it runs, every thread of launch and of its descendants (the
fork server, the coordinator, the agents: launch is their subreaper) is sampled from
/proc/<pid>/task/<tid>/schedstat every few milliseconds; processes of other runs on the machine
(other users' launches) are not counted, since only launch's descendants are. Printed per run:
CPU seconds of launch, the fork server, the coordinator and the agents (summed) up to the marks
`partitioned` (the partition's end: what competed with it on the cores), `first_status` (the
assignment, readiness barrier, hand-off and first round), `finals` and the end of the run
(teardown included), and the in-process run's CPU (`tessera solve ... --init file`, user +
system) for comparison; then, up to `partitioned`, each role's run-queue wait (time its
threads were runnable but not running: what competition for the cores cost them) and time
slices (how often they were scheduled: wake-ups), against the in-process run's, nearly all of
which is its partition. With --ab, runs alternate between two binary folders (or two launch
argument sets) and the medians of both are printed: CPU seconds are what stays meaningful on
a loaded machine, where wall times do not.

Sampling resolution is the sampling period (default 3 ms): a thread's CPU is read at the last
sample before a mark, so each figure may miss up to one period of each busy thread.

usage: dds_cpu_phases.py GRAPH [--bin build/bin] [--ab OTHER_BIN] [--launch-args="..."]
                         [--ab-launch-args="..."] [--ab-env NAME=VALUE] [--runs 5] [--agents 5]
                         [--domain 0]
                         [--period-ms 3] [--csv FILE]
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
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402

MARKS = ["partitioned", "first_status", "finals"]
# --end-to-end: every mark of the coordinator's timeline, in time order.
MARKS_END_TO_END = ["session", "partitioned", "announced", "ready", "first_status", "last_status",
                    "finals", "merged"]
ROLES = ["launch", "fork_server", "coordinator", "agents"]


def has_vertices(path):
    with open(path) as f:
        return any(line.startswith("VERTEX") for line in f)


def prepared_graph(tessera, graph, tmp):
    """The graph itself, or its rounded chordal copy when it has no VERTEX lines."""
    if has_vertices(graph):
        return graph
    out = os.path.join(tmp, os.path.basename(graph))
    subprocess.run([tessera, "solve", graph, "--algorithm", "irbcd", "--agents", "1",
                    "--partition", "sequential", "--max-rounds", "0", "--out", out],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return out


def ppid_of(pid):
    try:
        with open("/proc/%d/stat" % pid) as f:
            return int(f.read().rsplit(")", 1)[1].split()[1])
    except (OSError, ValueError, IndexError):
        return -1


def role_of(pid):
    try:
        with open("/proc/%d/cmdline" % pid, "rb") as f:
            argv = f.read().split(b"\0")
    except OSError:
        return None
    line = b" ".join(argv)
    # The fork server rewrites each child's command line to the executable it stands for.
    if b"tessera-coordinator" in line:
        return "coordinator"
    if b"tessera-agent" in line:
        return "agents"
    if b"tessera-fork-server" in line:
        return "fork_server"
    return None


def sample_threads(pids, roles, launch_pid):
    """{(pid, tid): (role, (cpu ns, run-queue wait ns, time slices))} of launch and its
    descendants right now (/proc/<pid>/task/<tid>/schedstat)."""
    snap = {}
    for pid in list(pids):
        role = "launch" if pid == launch_pid else roles.get(pid)
        if role is None:
            role = role_of(pid)
            if role is None:
                continue
            # A forked child keeps the server's command line until it rewrites it, and may be
            # re-parented to launch before that: a "fork_server" is looked at again every
            # sample, and each thread's CPU counts for the role of its latest sample.
            if role != "fork_server":
                roles[pid] = role
        try:
            tids = os.listdir("/proc/%d/task" % pid)
        except OSError:
            continue
        for tid in tids:
            try:
                with open("/proc/%d/task/%s/schedstat" % (pid, tid)) as f:
                    snap[(pid, int(tid))] = (role, tuple(int(x) for x in f.read().split()[:3]))
            except (OSError, ValueError):
                continue
    return snap


def descendants(root, known):
    """`known` plus every live process whose parent is in it (launch re-parents the fork
    server's children to itself, so one level per sample is enough to follow them)."""
    out = set(known)
    for d in os.listdir("/proc"):
        if d.isdigit():
            pid = int(d)
            if pid not in out and ppid_of(pid) in out:
                out.add(pid)
    return {p for p in out if p == root or os.path.exists("/proc/%d" % p)}


def run_launch(tessera, graph, agents, domain, extra, period_s, tmp, env=None, end_to_end=False):
    js = os.path.join(tmp, "dds.json")
    if os.path.exists(js):
        os.unlink(js)
    fixed = [] if end_to_end else ["--partition", "highest", "--init", "file", "--no-certify"]
    p = subprocess.Popen([tessera, "launch", graph, "--agents", str(agents), "--domain",
                          str(domain), "--json", js] + fixed +
                         ["--quiet"] + extra,
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env)
    samples = []  # (monotonic ms, snapshot)
    pids, roles = {p.pid}, {}
    while p.poll() is None:
        pids = descendants(p.pid, pids)
        samples.append((time.monotonic_ns() / 1e6, sample_threads(pids, roles, p.pid)))
        time.sleep(period_s)
    err = p.stderr.read()
    if p.returncode != 0:
        print(err[-2000:], file=sys.stderr)
        return None
    with open(js) as f:
        s = json.load(f)
    base = s["started_monotonic_ms"]
    names = MARKS_END_TO_END if end_to_end else MARKS
    marks = {m: base + s["timeline_ms"][m] for m in names if m in s["timeline_ms"]}
    row = {"rounds": s["rounds"], "cost": s["cost"], "partition_ms": s["partition_ms"],
           "total_ms": s["total_ms"]}
    for m in names:
        if m in s["timeline_ms"]:
            row["t@%s" % m] = float(s["timeline_ms"][m])
    last = {}
    cut = sorted(marks.items(), key=lambda kv: kv[1])
    at = 0
    for t, snap in samples:
        while at < len(cut) and t > cut[at][1]:
            add_cpu(row, cut[at][0], last)
            at += 1
        last.update(snap)
    while at < len(cut):
        add_cpu(row, cut[at][0], last)
        at += 1
    add_cpu(row, "end", last)
    return row


def add_cpu(row, mark, threads):
    for role in ROLES:
        mine = [v for r, v in threads.values() if r == role]
        row["%s@%s" % (role, mark)] = sum(v[0] for v in mine) / 1e9
        row["%s@%s:wait" % (role, mark)] = sum(v[1] for v in mine) / 1e9
        row["%s@%s:slices" % (role, mark)] = float(sum(v[2] for v in mine))


def run_inprocess(tessera, graph, agents, tmp, period_s, end_to_end=False):
    """(CPU s user + system, run-queue wait s, time slices) of `tessera solve` (the partition
    is nearly all of it), the latter two from its threads' last schedstat samples. With
    end_to_end, the centralized solver's (`tessera solve G --algorithm centralized`)."""
    u0 = bc.children_usage()
    args = ([tessera, "solve", graph, "--algorithm", "centralized"] if end_to_end else
            [tessera, "solve", graph, "--algorithm", "irbcd", "--agents", str(agents),
             "--partition", "highest", "--init", "file"])
    p = subprocess.Popen(args + ["--json", os.path.join(tmp, "ip.json")],
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    last = {}
    while p.poll() is None:
        try:
            for tid in os.listdir("/proc/%d/task" % p.pid):
                with open("/proc/%d/task/%s/schedstat" % (p.pid, tid)) as f:
                    last[tid] = tuple(int(x) for x in f.read().split()[:3])
        except (OSError, ValueError):
            pass
        time.sleep(period_s)
    if p.returncode != 0:
        sys.exit("tessera solve failed")
    return (bc.cpu_since(u0), sum(v[1] for v in last.values()) / 1e9,
            float(sum(v[2] for v in last.values())))


def print_phases(title, row):
    """CPU seconds of each role between consecutive timeline marks (--end-to-end)."""
    marks = [m for m in MARKS_END_TO_END if "t@%s" % m in row]
    marks.sort(key=lambda m: row["t@%s" % m])
    print("%s: CPU s by phase (from launch's start to each mark of the coordinator's timeline, "
          "ms)" % title)
    print("| phase | until ms | " + " | ".join(ROLES) + " | all |")
    print("|---|---|" + "---|" * (len(ROLES) + 1))
    prev = "start"
    for m in marks + ["end"]:
        cells, total = [], 0.0
        for role in ROLES:
            now = row.get("%s@%s" % (role, m), 0.0)
            before = row.get("%s@%s" % (role, prev), 0.0) if prev != "start" else 0.0
            cells.append("%.3f" % (now - before))
            total += now - before
        until = "%.0f" % row["t@%s" % m] if m != "end" else "%.0f" % row["total_ms"]
        print("| %s..%s | %s | %s | %.3f |" % (prev, m, until, " | ".join(cells), total))
        prev = m
    print("| all | | %s | %.3f |" % (" | ".join("%.3f" % row.get("%s@end" % r, 0.0) for r in ROLES),
                                    sum(row.get("%s@end" % r, 0.0) for r in ROLES)))
    print("centralized solver (tessera solve G): %.3f CPU s" % row["cpu_inprocess_s"])


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("graph")
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin"))
    ap.add_argument("--ab", default="", help="second binary folder, alternated with --bin")
    ap.add_argument("--launch-args", default="")
    ap.add_argument("--ab-launch-args", default=None,
                    help="launch arguments of the B runs (default: --launch-args)")
    ap.add_argument("--ab-env", action="append", default=[],
                    help="NAME=VALUE in the environment of the B runs (repeatable)")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--agents", type=int, default=5)
    ap.add_argument("--domain", type=int, default=0)
    ap.add_argument("--period-ms", type=float, default=3.0)
    ap.add_argument("--csv", default="")
    ap.add_argument("--end-to-end", action="store_true",
                    help="launch with its defaults (partition, certified, initialisation) "
                    "instead of --partition highest --init file --no-certify; CPU cut at every timeline mark, printed per "
                    "phase; compared with the centralized solver (tessera solve G)")
    a = ap.parse_args()
    ab = bool(a.ab) or a.ab_launch_args is not None or bool(a.ab_env)
    variants = [("A", a.bin, a.launch_args.split(), None)]
    if ab:
        env = dict(os.environ)
        env.update(kv.split("=", 1) for kv in a.ab_env)
        variants.append(("B", a.ab or a.bin, (a.ab_launch_args if a.ab_launch_args is not None
                                              else a.launch_args).split(), env))
    rows, failed = [], []
    with tempfile.TemporaryDirectory(prefix="dds-cpu-") as tmp:
        graph = prepared_graph(os.path.join(a.bin, "tessera"), a.graph, tmp)
        for k in range(a.runs):
            for name, bindir, extra, env in variants:
                tessera = os.path.join(bindir, "tessera")
                row = run_launch(tessera, graph, a.agents, a.domain, extra, a.period_ms / 1000,
                                 tmp, env, a.end_to_end)
                if row is None:  # counted and skipped: one failed launch must not lose the rest
                    print("run %d (%s) failed (load %.1f): skipped" % (k + 1, name,
                                                                      os.getloadavg()[0]),
                          flush=True)
                    failed.append("%s%d" % (name, k + 1))
                    continue
                row["variant"], row["run"] = name, k + 1
                (row["cpu_inprocess_s"], row["wait_inprocess_s"],
                 row["slices_inprocess"]) = run_inprocess(tessera, graph, a.agents, tmp,
                                                          a.period_ms / 1000, a.end_to_end)
                row["load"] = os.getloadavg()[0]
                rows.append(row)
                if a.end_to_end:
                    print_phases("%s run %d (load %.1f, %d rounds, total %.0f ms)" % (
                        name, k + 1, row["load"], row["rounds"], row["total_ms"]), row)
                    continue
                print("%s run %d: %d rounds, cost %.15g, load %.1f, partition %.0f ms, total %.0f "
                      "ms; CPU s to partitioned / first_status / finals / end: %s; in-process %.3f"
                      % (name, k + 1, row["rounds"], row["cost"], row["load"],
                         row["partition_ms"], row["total_ms"], "; ".join(
                          "%s %s" % (role, " / ".join("%.3f" % row.get("%s@%s" % (role, m), 0)
                                                      for m in MARKS + ["end"]))
                          for role in ROLES), row["cpu_inprocess_s"]), flush=True)
                print("    to partitioned: run-queue wait s / time slices: %s; in-process run "
                      "(all of it) %.3f / %.0f" % ("; ".join(
                          "%s %.3f / %.0f" % (role, row["%s@partitioned:wait" % role],
                                              row["%s@partitioned:slices" % role])
                          for role in ROLES), row["wait_inprocess_s"], row["slices_inprocess"]),
                      flush=True)
    if failed:
        print("failed runs (skipped): %s" % ", ".join(failed))
    for name, _, _, _ in variants:
        mine = [r for r in rows if r["variant"] == name]
        if not mine:
            sys.exit("every run of %s failed" % name)
        med = {key: statistics.median(r[key] for r in mine)
               for key in mine[0] if isinstance(mine[0][key], float)}
        if a.end_to_end:
            print_phases("%s median over %d runs (loads %s)" % (
                name, len(mine), ", ".join("%.1f" % r["load"] for r in mine)), med)
            continue
        print("%s median over %d runs: partition %.0f ms, total %.0f ms; CPU s %s; in-process %.3f" % (
            name, len(mine), med["partition_ms"], med["total_ms"], "; ".join("%s %s" % (role, " / ".join(
                "%.3f" % med.get("%s@%s" % (role, m), 0) for m in MARKS + ["end"]))
                for role in ROLES), med["cpu_inprocess_s"]))
        print("  run-queue wait s / time slices to partitioned: %s; in-process %.3f / %.0f" % (
            "; ".join("%s %.3f / %.0f" % (role, med["%s@partitioned:wait" % role],
                                          med["%s@partitioned:slices" % role]) for role in ROLES),
            med["wait_inprocess_s"], med["slices_inprocess"]))
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=sorted({k for r in rows for k in r}))
            w.writeheader()
            w.writerows(rows)


if __name__ == "__main__":
    main()
