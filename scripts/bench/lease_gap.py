#!/usr/bin/env python3
"""Participant lease: which scheduling gaps a run survives, and how soon a killed agent is lost.

Per lease L (seconds, `tessera launch --lease L`) and trial, on a running
`tessera launch --agents 3 --poses 10000 --refine none` (still in its rounds after 2 minutes):
  gap G   agent 1 is stopped (SIGSTOP) for G seconds and continued: what a host that does not
          schedule it for G s looks like to its peers. Printed: kept (the run went on) or lost
          (a "participant lease of L s expired" error).
  kill    agent 1 is SIGKILLed; with TESSERA_DDS_TRACE=1 every peer's log times the
          "participant dropped" event on the host's monotonic clock. Printed: the slowest peer's
          delay after the kill.
Load-free in what it asserts (stop lengths are exact; kept/lost is decided by the lease), but
the kill delays include scheduling: give `uptime` beside them. Written: OUT (CSV: lease_s, case,
trial, outcome, seconds).

usage:
  scripts/bench/lease_gap.py [--bin build/bin] [--domain 231] [--leases 1,2] [--gaps 0.7,1.2,1.5]
                             [--trials 3] [--out docs/benchmarks/lease_gap.csv]
"""
import argparse
import csv
import glob
import os
import re
import signal
import subprocess
import tempfile
import time


def start_run(args, lease, tag, logs=None):
    run = f"lease-{tag}-{os.getpid()}"
    argv = [os.path.join(args.bin, "tessera"), "launch", "--agents", "3", "--poses", "10000",
            "--domain", str(args.domain), "--run-id", run, "--init", "file", "--grad-tol",
            "1e-12", "--max-rounds", "100000", "--partition", "fast", "--status-interval", "1",
            "--no-certify", "--refine", "none",
            "--lease", str(lease)]
    env = dict(os.environ)
    if logs:
        argv += ["--keep-logs", logs]
        env["TESSERA_DDS_TRACE"] = "1"
    p = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
    while True:  # until the rounds run
        line = p.stdout.readline()
        if not line or re.match(r"round \d+", line):
            break
    time.sleep(2)
    pid = subprocess.run(f"pgrep -f '[t]essera-agent.*--id 1 --run-id {run} ' | head -1",
                         shell=True, capture_output=True, text=True).stdout.strip()
    return p, int(pid) if pid else 0


def gap_trial(args, lease, gap):
    p, pid = start_run(args, lease, "gap")
    if pid:
        os.kill(pid, signal.SIGSTOP)
        time.sleep(gap)
        os.kill(pid, signal.SIGCONT)
        time.sleep(4)
    if p.poll() is None:
        p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=120)
    return ("lost" if "participant lease of" in out else "kept") if pid else "no-agent", None


def kill_trial(args, lease):
    logs = tempfile.mkdtemp(prefix="tessera_lease_gap_")
    p, pid = start_run(args, lease, "kill", logs)
    if not pid:
        p.kill()
        return "no-agent", None
    t_kill = time.monotonic()  # CLOCK_MONOTONIC, as the trace's @ times
    os.kill(pid, signal.SIGKILL)
    p.communicate(timeout=120)
    delays = []
    for f in glob.glob(os.path.join(logs, "*.log")):
        for line in open(f, errors="replace"):
            m = re.search(r"@([0-9.]+) .*participant dropped: '[^']*:agent:1'", line)
            if m:
                delays.append(float(m.group(1)) - t_kill)
                break
    subprocess.run(["rm", "-rf", logs])
    return f"dropped by {len(delays)} peers", max(delays) if delays else None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default="build/bin")
    ap.add_argument("--domain", type=int, default=231)
    ap.add_argument("--leases", default="1,2")
    ap.add_argument("--gaps", default="0.7,1.2,1.5")
    ap.add_argument("--trials", type=int, default=3)
    ap.add_argument("--out", default="docs/benchmarks/lease_gap.csv")
    args = ap.parse_args()
    rows = []
    print(f"{'lease s':>7} {'case':>8} {'trial':>5}  outcome              seconds  load")
    for lease in [float(x) for x in args.leases.split(",")]:
        cases = [f"gap {g}" for g in args.gaps.split(",")] + ["kill"]
        for case in cases:
            for t in range(args.trials):
                if case == "kill":
                    outcome, secs = kill_trial(args, lease)
                else:
                    outcome, secs = gap_trial(args, lease, float(case.split()[1]))
                load = os.getloadavg()[0]
                s = f"{secs:.3f}" if secs is not None else ""
                print(f"{lease:7.1f} {case:>8} {t:5d}  {outcome:20s} {s:>7}  {load:.1f}", flush=True)
                rows.append([lease, case, t, outcome, s, f"{load:.1f}"])
    with open(args.out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["lease_s", "case", "trial", "outcome", "seconds", "load1"])
        w.writerows(rows)


if __name__ == "__main__":
    main()
