#!/usr/bin/env python3
"""Permanent-loss fault benchmark of the DDS runtime (issue 8, item 2).

A generated 3D grid, N = 5 agents, the coordinator with --replicas 1 (every agent's
measurements and lifted poses replicated to one neighbour) and a short --rejoin-timeout.
Each trial SIGKILLs a random agent when the coordinator reports a random round and never
restarts it: the coordinator re-partitions its block among the survivors, which take over
from the replicas and finish with N - 1 agents. A trial counts as finished when every
surviving process exits 0, the merged estimate holds every pose, and the summary names the
loss; its cost error is measured against f* (the centralized solver's optimum).

Writes docs/benchmarks/faults_loss.csv with the column contract of scripts/bench/faults.py
(fault,trials,finished,cost_error,extra_time_s; extra time = mean wall time over the
undisturbed replicated run), per-trial rows in docs/benchmarks/faults/loss_trials.csv, and
re-assembles docs/benchmarks/faults.md.
"""
import csv
import json
import os
import random
import signal
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402
import faults_common as fc  # noqa: E402


class LossRun:
    def __init__(self, args, work, name, replicas):
        self.args, self.name, self.replicas = args, name, replicas
        self.dir = os.path.join(work, name)
        os.makedirs(self.dir, exist_ok=True)
        self.run_id = "loss-%d-%s" % (os.getpid(), name)
        self.summary = os.path.join(self.dir, "summary.json")
        self.merged = os.path.join(self.dir, "merged.g2o")

    def spawn(self, cmd, log):
        f = open(os.path.join(self.dir, log), "w")
        return subprocess.Popen(cmd, stdout=f, stderr=subprocess.STDOUT, start_new_session=True)

    def start(self):
        a = self.args
        self.t0 = time.time()
        self.coord = self.spawn([os.path.join(a.bin_dir, "tessera-coordinator"), "--agents", str(a.agents),
                                 "--run-id", self.run_id, "--domain", str(a.domain), "--timeout", "60",
                                 "--run-timeout", str(a.limit), "--summary", self.summary,
                                 "--output", self.merged, "--progress", "--partition", "eco",
                                 "--grad-tol", str(a.grad_tol), "--replicas", str(self.replicas),
                                 "--replica-every", str(a.replica_every),
                                 "--rejoin-timeout", str(a.rejoin_timeout), "--status-interval", "2",
                                 "--progress-interval", "0"],
                                "coordinator.log")
        self.agents = {k: self.spawn([os.path.join(a.bin_dir, "tessera-agent"), "--graph", a.graph_path,
                                      "--robots", str(a.agents), "--id", str(k), "--run-id", self.run_id,
                                      "--domain", str(a.domain), "--timeout", "60",
                                      # the loss-tolerant configuration (as `launch --on-agent-loss
                                      # continue`): with shared memory a SIGKILLed peer can leave the
                                      # survivors' ports unusable and every peer looks lost at once
                                      "--udp-only"], "agent%d.log" % k)
                       for k in range(a.agents)}

    def coordinator_output(self):
        with open(os.path.join(self.dir, "coordinator.log")) as f:
            return f.read()

    def kill_at(self, agent, at_round):
        if not bc.wait_for_output(self.coordinator_output, "round %d:" % at_round,
                                  time.time() + self.args.limit, lambda: self.coord.poll() is None):
            return False
        os.kill(self.agents[agent].pid, signal.SIGKILL)
        return True

    def wait(self, victim=None):
        deadline = time.time() + self.args.limit
        codes = {}
        for name, p in [("coordinator", self.coord)] + [(k, p) for k, p in self.agents.items()]:
            try:
                codes[name] = p.wait(timeout=max(1, deadline - time.time()))
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                codes[name] = -9
        wall = time.time() - self.t0
        summary = None
        if os.path.exists(self.summary):
            with open(self.summary) as f:
                summary = json.load(f)
        ok = all(c == 0 for n, c in codes.items() if n != victim) and summary is not None
        return ok, codes, wall, summary

    def merged_poses(self):
        return bc.g2o_vertex_ids(self.merged)


def loss_benchmark_start(doc, domain, prefix):
    """The start both permanent-loss benchmarks share (this one and faults_launch_loss.py):
    options (bench_common.add_loss_args), random generator, scratch folder with the graph, f*."""
    ap = fc.parser(doc)
    bc.add_loss_args(ap, domain=domain)
    args = ap.parse_args()
    work = fc.start(args, prefix, graph=False)
    fstar = bc.loss_graph_and_fstar(os.path.join(args.bin_dir, "tessera"), args, work)
    return args, random.Random(args.seed), work, fstar


def main():
    args, rng, work, fstar = loss_benchmark_start(__doc__, 213, "tessera_faults_loss_")

    base = {}
    for name, replicas in (("plain", 0), ("replicated", 1)):
        r = LossRun(args, work, "undisturbed-" + name, replicas)
        r.start()
        ok, codes, wall, summary = r.wait()
        if not ok:
            print("undisturbed run (%s) failed: %s; logs in %s" % (name, codes, r.dir))
            return 1
        base[name] = (wall, summary)
        print("undisturbed %-10s: %d rounds, cost %.12g (error %.1e vs f*), wall %.2f s, %d bytes" %
              (name, summary["rounds"], summary["cost"], abs(summary["cost"] - fstar) / fstar, wall,
               summary["bytes_exchanged"]))
    ref_wall, ref = base["replicated"]
    rounds = int(ref["rounds"])

    trials = []
    for t in range(args.trials):
        agent = rng.randrange(args.agents)
        at = rng.randrange(2, max(3, rounds - 5))
        r = LossRun(args, work, "trial%d" % t, 1)
        r.start()
        killed = r.kill_at(agent, at)
        ok, codes, wall, summary = r.wait(victim=agent)
        poses = len(r.merged_poses())
        fault = (summary or {}).get("fault") or {}
        ok = ok and killed and poses == args.poses and fault.get("lost_agents") == [agent]
        err = abs(summary["cost"] - fstar) / fstar if ok else float("nan")
        trials.append(dict(trial=t, agent=agent, kill_round=at, finished=int(ok),
                           survivors=len(fault.get("survivors", [])), poses_in_estimate=poses,
                           moved_poses=fault.get("moved_poses", ""),
                           repartition_at_s=fault.get("repartition_at_s", ""),
                           rounds_after=summary["rounds"] if summary else "",
                           cost=summary["cost"] if summary else "", rel_cost_error=err,
                           wall_s=round(wall, 3), extra_s=round(wall - ref_wall, 3)))
        print("trial %d: kill agent %d at round %d for good -> %s, %d poses, cost error %.2e vs f*, "
              "wall %.2f s (+%.2f)" % (t, agent, at, "finished with %d agents" % len(fault.get("survivors", []))
                                       if ok else "FAILED %s" % codes, poses, err, wall, wall - ref_wall))
        if not ok:
            print("  logs kept in %s" % r.dir)
    row = bc.fault_row("agent SIGKILLed for good at a random round, block re-partitioned to the survivors "
                       "(N=%d, %d-pose grid3d, --replicas 1; cost error vs f*)" % (args.agents, args.poses),
                       trials)
    os.makedirs(os.path.join(args.out_dir, "faults"), exist_ok=True)
    with open(os.path.join(args.out_dir, "faults", "loss_replication_cost.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["run", "replicas", "wall_s", "rounds", "bytes_exchanged", "cost"])
        for name, (wall, s) in base.items():
            w.writerow([name, 0 if name == "plain" else 1, "%.3f" % wall, s["rounds"], s["bytes_exchanged"],
                        "%.12g" % s["cost"]])
    return fc.finish(args, "loss", row, trials, work)


if __name__ == "__main__":
    sys.exit(main())
