#!/usr/bin/env python3
"""Memory and phases of `tessera launch` on a generated 3D grid: where a large run's wall time and
memory go, and the memory model that says how large a run fits on one host.

Each run: `tessera generate --kind grid3d --poses P --robots N` (once per size, into --work), then
`tessera launch GRID --agents N --partition fast --init distributed` (the distributed
initialisation: `chordal` gathers the whole graph on agent 0, which does not scale), certified by
default. While it runs, the resident set (RSS) and proportional set (PSS: shared pages divided
among the processes sharing them, so the sum over processes is what the run takes from the host)
of launch and every process it started (the fork server, the coordinator, the agents: launch is
their subreaper) are sampled every --period seconds from /proc. Printed and written to
docs/benchmarks/dds_scale.csv, one row per run, appended to the rows already there (--replace: only
this run's rows; --label names what was measured):
  - the phases of the coordinator's timeline (`timeline_ms` of the summary): start (launch to the
    coordinator's session), discovery and partition (to the assignment), ready (the readiness
    barrier), setup (initialisation, hand-off and the agents' set-up to the first round status),
    rounds (first to last round status), finish (last status to the final estimates: certificate,
    rounding, final report) and merge (to the summary);
  - the summary's peak memory fields (`peak_rss_mb_per_agent`, `peak_rss_mb_agent_max`,
    `peak_rss_mb_coordinator`, `peak_rss_mb_run`), the sampled peak PSS of the largest agent and the
    sampled peak of the run's PSS sum (the host's real cost), and the load average;
  - with --reference-cost F (the graph's f*, from `tessera solve --algorithm centralized`): the
    summary's `rel_gap_to_reference`, (cost - F) / F.
Timings taken on a shared machine move with its load (printed beside them); the memory figures
do not.

docs/scale.md reads its memory model off these rows.

With --robot-files the grid is also written as one file per robot (generate --split) and launch
reads that folder: each agent parses only its own file and nothing is preloaded, as robots with
their own data would run (the fork server's preloaded whole graph is in every agent's RSS).

usage: dds_scale.py [--bin build/bin/tessera] [--sizes 20000:2,100000:10] [--domain 65]
                    [--work DIR] [--timeout 3600] [--period 0.5] [--csv FILE] [--robot-files]
                    [--launch-args="..."] [--min-available-mb MB] [--reference-cost F]
                    [--samples FILE]

The set-up's peaks (setup_pss_mb_*) are sampled until the coordinator's first round line;
--min-available-mb stops a run (SIGTERM to launch) when the host's MemAvailable falls below it;
--samples writes every sample (the agents' mean and largest PSS over the run's time).
"""
import argparse
import csv
import json
import os
import re
import signal
import subprocess
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402

PHASES = [("start", None, "session"), ("discovery+partition", "session", "partitioned"),
          ("ready", "partitioned", "ready"), ("setup", "ready", "first_status"),
          ("rounds", "first_status", "last_status"), ("finish", "last_status", "finals"),
          ("merge", "finals", "merged")]


def status_kb(pid, key, name="status"):
    try:
        with open(f"/proc/{pid}/{name}") as f:
            for line in f:
                if line.startswith(key):
                    return int(line.split()[1])
    except OSError:
        return None
    return None


def descendants(root):
    """pids of root and everything below it (by parent pid)."""
    children = {}
    for p in os.listdir("/proc"):
        if not p.isdigit():
            continue
        try:
            with open(f"/proc/{p}/stat") as f:
                ppid = int(f.read().rsplit(")", 1)[1].split()[1])
        except (OSError, IndexError, ValueError):
            continue
        children.setdefault(ppid, []).append(int(p))
    out, todo = [], [root]
    while todo:
        p = todo.pop()
        out.append(p)
        todo.extend(children.get(p, []))
    return out


def role_of(pid):
    try:
        with open(f"/proc/{pid}/cmdline") as f:
            args = f.read().split("\0")
        with open(f"/proc/{pid}/comm") as f:
            comm = f.read().strip()
    except OSError:
        return None
    if not comm.startswith("tessera"):
        return None
    for k, a in enumerate(args[:-1]):
        if a == "--id":
            return "agent" + args[k + 1]
    return comm


def mem_available_mb():
    with open("/proc/meminfo") as f:
        for line in f:
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) // 1024
    return None


class Sampler(threading.Thread):
    """Peak RSS and PSS (kB) per role and the peak of the PSS sum over the run's processes, split
    at the first round (set-up before it, the rounds, certificate and rounding after). With
    min_available_mb > 0 a watchdog: when the host's MemAvailable falls below it, launch is sent
    SIGTERM (other jobs share the host; a run must not push it into the OOM killer)."""

    def __init__(self, root, period, min_available_mb=0, samples=None):
        super().__init__(daemon=True)
        self.root, self.period, self.min_available_mb = root, period, min_available_mb
        self.samples, self.t0 = samples, time.monotonic()  # samples: an open CSV file, or None
        self.rss, self.pss, self.pss_sum, self.stop = {}, {}, 0, False
        self.in_rounds, self.setup_pss_sum, self.setup_pss_agent = False, 0, 0
        self.stopped_by_watchdog, self.least_available_mb = False, None

    def run(self):
        while not self.stop:
            total = 0
            largest = 0
            agents = []
            for p in descendants(self.root):
                role = role_of(p)
                if role is None:
                    continue
                rss = status_kb(p, "VmRSS:")
                pss = status_kb(p, "Pss:", "smaps_rollup")
                if rss is None or pss is None:
                    continue
                self.rss[role] = max(self.rss.get(role, 0), rss)
                self.pss[role] = max(self.pss.get(role, 0), pss)
                if role.startswith("agent"):
                    largest = max(largest, pss)
                    agents.append(pss)
                total += pss
            self.pss_sum = max(self.pss_sum, total)
            if not self.in_rounds:
                self.setup_pss_sum = max(self.setup_pss_sum, total)
                self.setup_pss_agent = max(self.setup_pss_agent, largest)
            avail = mem_available_mb()
            if self.samples:
                mean = sum(agents) / len(agents) if agents else 0
                self.samples.write(f"{time.monotonic() - self.t0:.1f},{int(self.in_rounds)},{len(agents)},"
                                   f"{mean / 1024:.1f},{largest / 1024:.1f},{total / 1024:.1f},{avail},"
                                   f"{load():.2f}\n")
                self.samples.flush()
            if avail is not None:
                self.least_available_mb = min(avail, self.least_available_mb or avail)
                if self.min_available_mb and avail < self.min_available_mb and not self.stopped_by_watchdog:
                    self.stopped_by_watchdog = True
                    bc.progress(f"watchdog: MemAvailable {avail} MB < {self.min_available_mb} MB: "
                                f"stopping the run (PSS sum {total // 1024} MB)")
                    try:
                        os.kill(self.root, signal.SIGTERM)
                    except OSError:
                        pass
            time.sleep(self.period)


def load():
    with open("/proc/loadavg") as f:
        return float(f.read().split()[0])


def run_one(args, poses, agents, domain):
    graph = os.path.join(args.work, f"grid3d_{poses}_{agents}.g2o")
    robots_dir = os.path.join(args.work, f"grid3d_{poses}_{agents}_robots")
    if not os.path.exists(graph) or (args.robot_files and not os.path.isdir(robots_dir)):
        bc.progress(f"generating {graph}")
        split = ["--split", robots_dir] if args.robot_files else []
        subprocess.run([args.bin, "generate", "--kind", "grid3d", "--poses", str(poses), "--robots",
                        str(agents), "--out", graph] + split, check=True, stdout=subprocess.DEVNULL)
    if args.robot_files:
        graph = robots_dir  # one file per robot: each agent reads its own, nothing preloaded
    summary = os.path.join(args.work, f"summary_{poses}_{agents}.json")
    cmd = [args.bin, "launch", graph, "--agents", str(agents), "--partition", "fast", "--init",
           "distributed", "--domain", str(domain), "--json", summary, "--timeout",
           str(args.timeout), "--status-interval", "30"] + args.launch_args.split()
    if args.reference_cost:
        cmd += ["--reference-cost", repr(args.reference_cost)]
    bc.progress(" ".join(cmd))
    load0 = load()
    t0 = time.monotonic()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    samples = None
    if args.samples:
        samples = open(args.samples.replace("{size}", f"{poses}_{agents}"), "w")
        samples.write("elapsed_s,in_rounds,agents,agent_pss_mb_mean,agent_pss_mb_max,run_pss_mb_sum,"
                      "mem_available_mb,load\n")
    sampler = Sampler(proc.pid, args.period, args.min_available_mb, samples)
    sampler.start()
    in_summary = False
    for line in proc.stdout:  # progress and errors stay visible; the summary is read from its file
        in_summary = in_summary or line.startswith("summary:")
        # The coordinator's first round progress line ends the set-up.
        if not sampler.in_rounds and re.search(r"round \d+\S*: cost", line):
            sampler.in_rounds = True
        if not in_summary:
            sys.stdout.write(f"  | {time.monotonic() - t0:7.1f}s " + line)
        in_summary = in_summary and not line.startswith("}")
    rc = proc.wait()
    wall = time.monotonic() - t0
    sampler.stop = True
    sampler.join()
    if samples:
        samples.close()
    agent_pss = {k: v for k, v in sampler.pss.items() if k.startswith("agent")}
    agent_rss = {k: v for k, v in sampler.rss.items() if k.startswith("agent")}
    row = {"poses": poses, "agents": agents, "input": "robot files" if args.robot_files else "one file",
           "launch_args": args.launch_args, "rc": rc, "wall_s": round(wall, 1),
           "load_start": load0, "load_end": load(),
           # sampled, so known for a failed run too
           "peak_pss_mb_agent_max": round(max(agent_pss.values(), default=0) / 1024, 1),
           "sampled_rss_mb_agent_max": round(max(agent_rss.values(), default=0) / 1024, 1),
           "peak_pss_mb_coordinator": round(sampler.pss.get("tessera-coordin", 0) / 1024, 1),
           "peak_pss_mb_fork_server": round(sampler.pss.get("tessera-fork-se", 0) / 1024, 1),
           "peak_pss_mb_run_sum": round(sampler.pss_sum / 1024, 1),
           "setup_pss_mb_run_sum": round(sampler.setup_pss_sum / 1024, 1),
           "setup_pss_mb_agent_max": round(sampler.setup_pss_agent / 1024, 1),
           "least_mem_available_mb": sampler.least_available_mb,
           "stopped_by_watchdog": sampler.stopped_by_watchdog}
    if rc != 0 or not os.path.exists(summary):
        return row
    with open(summary) as f:
        s = json.load(f)
    tl = s.get("timeline_ms", {})
    for name, a, b in PHASES:
        if b in tl and (a is None or a in tl):
            row[name + "_s"] = round((tl[b] - (tl[a] if a else 0.0)) / 1000.0, 2)
    row.update({
        "edges": s.get("edges"), "rounds": s.get("rounds"), "certified": s.get("certified"),
        "min_eigenvalue": s.get("min_eigenvalue"), "cut_edges": s.get("cut_edges"),
        "cost": s.get("cost"), "grad_norm": s.get("grad_norm"),
        "reference_cost": s.get("reference_cost"), "rel_gap_to_reference": s.get("rel_gap_to_reference"),
        "rounding_s": round(s["rounding_ms"] / 1000.0, 1) if s.get("rounding_ms") else None,
        "rounding_cg_iterations": s.get("rounding_cg_iterations"),
        "peak_rss_mb_agent_max": round(s.get("peak_rss_mb_agent_max", 0), 1),
        "peak_rss_mb_coordinator": round(s.get("peak_rss_mb_coordinator", 0), 1),
        "peak_rss_mb_run": round(s.get("peak_rss_mb_run", 0), 1),
    })
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin", "tessera"))
    ap.add_argument("--sizes", default="20000:2,100000:10", help="POSES:AGENTS,...")
    ap.add_argument("--domain", type=int, default=65)
    ap.add_argument("--work", default="/tmp/tessera-dds-scale")
    ap.add_argument("--timeout", type=int, default=3600)
    ap.add_argument("--period", type=float, default=0.5)
    ap.add_argument("--csv", default=os.path.join(bc.OUT_DIR, "dds_scale.csv"))
    ap.add_argument("--robot-files", action="store_true",
                    help="launch the folder of robot files (generate --split) instead of the whole file")
    ap.add_argument("--launch-args", default="", help="more launch options, e.g. \"--max-rounds 20\"")
    ap.add_argument("--label", default="",
                    help="what was measured (the CSV's `binaries` column), e.g. the change under test")
    ap.add_argument("--replace", action="store_true",
                    help="write only this run's rows; by default they are appended to the CSV's rows")
    ap.add_argument("--min-available-mb", type=int, default=0,
                    help="watchdog: stop a run when the host's MemAvailable falls below this (0 = off)")
    ap.add_argument("--samples", default="",
                    help="write every memory sample to this CSV ({size} becomes POSES_AGENTS): elapsed "
                         "s, whether the rounds have begun, the agents' mean and largest PSS, the run's "
                         "PSS sum, MemAvailable, load")
    ap.add_argument("--reference-cost", type=float, default=0,
                    help="the graph's optimal cost f* (one size only): launch reports the final cost's "
                         "relative gap to it (rel_gap_to_reference)")
    args = ap.parse_args()
    args.bin = os.path.abspath(args.bin)
    if args.reference_cost and "," in args.sizes:
        sys.exit("dds_scale.py: --reference-cost is one graph's f*: give one size")
    os.makedirs(args.work, exist_ok=True)
    rows = []
    for k, spec in enumerate(args.sizes.split(",")):
        poses, agents = (int(x) for x in spec.split(":"))
        rows.append(run_one(args, poses, agents, args.domain + k))
    cols = ["poses", "agents", "input", "rc", "wall_s"] + [p[0] + "_s" for p in PHASES] + [
        "rounds", "grad_norm", "rel_gap_to_reference", "certified", "min_eigenvalue", "peak_rss_mb_agent_max", "peak_pss_mb_agent_max", "peak_rss_mb_coordinator",
        "peak_pss_mb_fork_server", "peak_rss_mb_run", "peak_pss_mb_run_sum", "setup_pss_mb_agent_max",
        "setup_pss_mb_run_sum", "load_start", "load_end"]
    certify = "not certified" if "--no-certify" in args.launch_args.split() else "certified"
    bc.print_table(f"tessera launch on generated 3D grids (fast partition, distributed init, {certify})",
                   cols, [[bc.fmt(r.get(c, "-")) if not isinstance(r.get(c), str) else r[c] for c in cols]
                          for r in rows])
    # The CSV is the record of every scale run: earlier rows stay unless --replace.
    kept = []
    if not args.replace and os.path.exists(args.csv):
        with open(args.csv, newline="") as f:
            kept = list(csv.DictReader(f))
    for r in rows:
        r["binaries"] = args.label
    bc.write_csv(args.csv, kept + rows)


if __name__ == "__main__":
    main()
