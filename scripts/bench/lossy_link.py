#!/usr/bin/env python3
"""Lossy link: wall time of a run with 10% frame loss on one link against the loss-free run.

Network namespaces stand in for hosts (scripts/netns/netns.sh: coordinator on host 0, agent k
on host k+1; prefix tlb, subnet 10.77.39, both removed at the end). Loss is made with nftables
inside the namespaces only (`netns.sh loss`: `numgen random mod 100 < P drop` on both ends of
agent 0's veth, so every frame, IP fragments included, is dropped with probability P).

Per trial, on the same generated grid3d graph (fresh run id, same domain):
  loss-free            --network default, no loss
  lossy, no loss       --network lossy,   no loss (what the profile costs on a good link)
  lossy profile        --network lossy,   P% loss on agent 0's link
  default with loss    --network default, P% loss (stopped after --limit seconds: with
                       64 KB datagrams it often never finishes)
Printed: wall time (process start to the last exit), CPU time of all processes, rounds, cost,
relative cost error against the loss-free run, frames dropped. Written:
docs/benchmarks/faults_lossy_link.csv (fault,trials,finished,cost_error,extra_time_s: the
contract of scripts/bench/faults.py) and docs/benchmarks/faults/lossy_link_trials.csv.

Needs root (namespaces). usage:
  scripts/bench/lossy_link.py [--bin build/bin] [--poses 1000] [--agents 3] [--trials 3]
                              [--loss 10] [--limit 120] [--domain 199] [--out-dir docs/benchmarks]
                              [--prefix tlb] [--subnet 10.77.39]
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
NETNS = os.path.join(ROOT, "scripts", "netns", "netns.sh")
PREFIX, SUBNET = "tlb", "10.77.39"


def sh(*argv, check=True):
    return subprocess.run(list(argv), check=check, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True).stdout


def dropped_frames():
    total = 0
    for ns in (PREFIX + "-1", PREFIX + "-br"):
        out = sh("ip", "netns", "exec", ns, "nft", "list", "table", "netdev", "tessera_loss", check=False)
        at = out.find("counter packets ")
        if at >= 0:
            total += int(out[at + 16:].split()[0])
    return total


def run(bindir, graph, agents, domain, run_id, network, limit, work):
    """One run across the namespaces; returns (finished, wall_s, cpu_s, summary or None)."""
    summary = os.path.join(work, run_id + ".json")
    session = ["--run-id", run_id, "--domain", str(domain), "--network", network,
               "--timeout", str(limit)]
    cmds = [["ip", "netns", "exec", PREFIX + "-0", os.path.join(bindir, "tessera-coordinator"),
             "--agents", str(agents), "--partition", "highest", "--grad-tol", "0.01",
             "--run-timeout", str(limit), "--summary", summary] + session]
    for k in range(agents):
        cmds.append(["ip", "netns", "exec", "%s-%d" % (PREFIX, k + 1),
                     os.path.join(bindir, "tessera-agent"), "--graph", graph, "--robots", str(agents),
                     "--id", str(k)] + session)
    before = bc.children_usage()
    t0 = time.monotonic()
    logs = [open(os.path.join(work, "%s_%d.log" % (run_id, i)), "w") for i in range(len(cmds))]
    procs = [subprocess.Popen(c, stdout=l, stderr=subprocess.STDOUT) for c, l in zip(cmds, logs)]
    ok = True
    for p in procs:
        left = max(0.1, limit + 5 - (time.monotonic() - t0))
        try:
            ok = (p.wait(timeout=left) == 0) and ok
        except subprocess.TimeoutExpired:
            ok = False
            break
    for p in procs:  # only our own children
        if p.poll() is None:
            p.send_signal(2)
    for p in procs:
        try:
            p.wait(timeout=5)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()
    wall = time.monotonic() - t0
    for l in logs:
        l.close()
    cpu = bc.cpu_since(before)
    data = None
    if ok and os.path.exists(summary):
        with open(summary) as f:
            data = json.load(f)
    return ok and data is not None, wall, cpu, data


def main():
    global PREFIX, SUBNET  # --prefix / --subnet; dropped_frames() reads them
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin"))
    ap.add_argument("--poses", type=int, default=1000)
    ap.add_argument("--agents", type=int, default=3)
    ap.add_argument("--trials", type=int, default=3)
    ap.add_argument("--loss", type=int, default=10, help="percent of frames dropped on agent 0's link")
    ap.add_argument("--limit", type=float, default=120, help="seconds before a run is stopped")
    ap.add_argument("--domain", type=int, default=199)
    ap.add_argument("--out-dir", default=os.path.join(ROOT, "docs", "benchmarks"))
    ap.add_argument("--prefix", default=PREFIX, help="namespace name prefix (unique per user)")
    ap.add_argument("--subnet", default=SUBNET, help="10.77.X of the namespaces (unique per user)")
    args = ap.parse_args()
    PREFIX, SUBNET = args.prefix, args.subnet
    if os.geteuid() != 0 or subprocess.run([NETNS, "check"]).returncode != 0:
        print("lossy_link.py: network namespaces cannot be created here (need root); nothing measured")
        return 1
    bindir = os.path.abspath(args.bin)
    work = tempfile.mkdtemp(prefix="tessera-lossy-")
    graph = os.path.join(work, "grid3d.g2o")
    sh(os.path.join(bindir, "tessera"), "generate", "--kind", "grid3d", "--poses", str(args.poses),
       "--robots", str(args.agents), "--out", graph)
    sh(NETNS, "up", PREFIX, str(args.agents + 1), SUBNET)
    rows = []
    try:
        for t in range(args.trials):
            for config, network, loss in (("loss-free", "default", 0), ("lossy, no loss", "lossy", 0),
                                          ("lossy profile", "lossy", args.loss),
                                          ("default with loss", "default", args.loss)):
                sh(NETNS, "loss", PREFIX, "1", str(loss))
                run_id = "bench-%d-%d-%s" % (os.getpid(), t, network + str(loss))
                finished, wall, cpu, s = run(bindir, graph, args.agents, args.domain, run_id, network,
                                             args.limit, work)
                rows.append(dict(trial=t, config=config, network=network, loss_pct=loss,
                                 finished=int(finished), wall_s="%.2f" % wall, cpu_s="%.2f" % cpu,
                                 rounds=s["rounds"] if s else "", cost=repr(s["cost"]) if s else "",
                                 dropped_frames=dropped_frames() if loss else 0))
                r = rows[-1]
                print("trial %d %-18s finished=%d wall %6.2f s cpu %6.2f s rounds %s cost %s dropped %s"
                      % (t, config, finished, wall, cpu, r["rounds"], r["cost"], r["dropped_frames"]),
                      flush=True)
    finally:
        sh(NETNS, "down", PREFIX, check=False)
    # Per trial: error against that trial's loss-free run.
    clean = {r["trial"]: r for r in rows if r["config"] == "loss-free"}
    for r in rows:
        c = clean[r["trial"]]
        r["rel_cost_error"] = ""
        r["extra_s"] = ""
        if r["finished"] and c["finished"]:
            c0 = float(c["cost"])
            r["rel_cost_error"] = "%.1e" % (abs(float(r["cost"]) - c0) / abs(c0))
            r["extra_s"] = "%.2f" % (float(r["wall_s"]) - float(c["wall_s"]))
    print("\n%-18s | trials | finished | median wall s | median cpu s | worst rel. cost error | mean extra s"
          % "configuration")
    contract = []
    for config, fault in (("loss-free", None), ("lossy, no loss", None), ("lossy profile", "lossy link %d%% (--network lossy)" % args.loss),
                          ("default with loss", "lossy link %d%% (--network default)" % args.loss)):
        rs = [r for r in rows if r["config"] == config]
        fin = [r for r in rs if r["finished"]]
        errs = [float(r["rel_cost_error"]) for r in fin if r["rel_cost_error"] != ""]
        extra = [float(r["extra_s"]) for r in fin if r["extra_s"] != ""]
        med_wall = statistics.median(float(r["wall_s"]) for r in fin) if fin else float("nan")
        med_cpu = statistics.median(float(r["cpu_s"]) for r in fin) if fin else float("nan")
        worst = max(errs) if errs else float("nan")
        mean_extra = sum(extra) / len(extra) if extra else float("nan")
        print("%-18s | %6d | %8d | %13.2f | %12.2f | %21.1e | %12.2f"
              % (config, len(rs), len(fin), med_wall, med_cpu, worst, mean_extra))
        if fault:
            contract.append(dict(fault=fault, trials=len(rs), finished=len(fin),
                                 cost_error="%.1e" % worst if errs else "",
                                 extra_time_s="%.2f" % mean_extra if extra else ""))
    os.makedirs(os.path.join(args.out_dir, "faults"), exist_ok=True)
    path = os.path.join(args.out_dir, "faults_lossy_link.csv")
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["fault", "trials", "finished", "cost_error", "extra_time_s"])
        w.writeheader()
        w.writerows(contract)
    bc.write_csv(os.path.join(args.out_dir, "faults", "lossy_link_trials.csv"), rows, announce=False)
    print("\nwrote %s (grid3d %d poses, %d agents, %d%% loss on agent 0's link, limit %.0f s)"
          % (path, args.poses, args.agents, args.loss, args.limit))
    return 0


if __name__ == "__main__":
    sys.exit(main())
