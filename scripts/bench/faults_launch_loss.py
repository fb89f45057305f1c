#!/usr/bin/env python3
"""Permanent loss under `tessera launch --on-agent-loss continue` (issue 8, item 2 via launch).

The same experiment as faults_loss.py, but through the user-facing command: one
`tessera launch GRAPH --agents 5 --on-agent-loss continue` per trial, a random agent
SIGKILLed (for good) when launch prints a random round, and launch alone decides what
happens (it passes --replicas/--replica-every/--rejoin-timeout to the coordinator and
--udp-only to the agents). A trial counts as finished when launch exits 0, the merged
estimate (--out) holds every pose and the summary's fault record names the killed agent;
its cost error is against f* (centralized solver). Extra time is against an undisturbed
launch with the same options (replicas on).

Writes docs/benchmarks/faults_launch_loss.csv (column contract of scripts/bench/faults.py),
per-trial rows in docs/benchmarks/faults/launch_loss_trials.csv, and re-assembles faults.md.
CPU time = user + sys of launch and every process it started (they are all waited for).

usage: scripts/bench/faults_launch_loss.py [--bin-dir build/bin] [--out-dir docs/benchmarks]
           [--trials 10] [--agents 5] [--poses 500] [--domain 223] [--seed 1] [--limit 300]
"""
import json
import os
import signal
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402
import faults_common as fc  # noqa: E402
from faults_loss import loss_benchmark_start  # noqa: E402


class LaunchRun:
    """One `tessera launch` with its own run id and folder."""

    def __init__(self, args, work, name):
        self.args, self.name = args, name
        self.dir = os.path.join(work, name)
        os.makedirs(self.dir, exist_ok=True)
        self.run_id = "launchloss-%d-%s" % (os.getpid(), name)
        self.summary = os.path.join(self.dir, "summary.json")
        self.merged = os.path.join(self.dir, "merged.g2o")
        self.log_path = os.path.join(self.dir, "launch.log")

    def start(self):
        a = self.args
        cmd = [os.path.join(a.bin_dir, "tessera"), "launch", a.graph_path, "--agents", str(a.agents),
               "--run-id", self.run_id, "--domain", str(a.domain), "--partition", "eco",
               "--grad-tol", str(a.grad_tol), "--on-agent-loss", "continue",
               "--rejoin-timeout", str(a.rejoin_timeout), "--replica-every", str(a.replica_every),
               "--out", self.merged, "--json", self.summary, "--timeout", str(a.limit),
               "--status-interval", "2", "--progress-interval", "0"]
        self.cpu0 = bc.children_usage()
        self.t0 = time.time()
        self.log = open(self.log_path, "w")
        self.proc = subprocess.Popen(cmd, stdout=self.log, stderr=subprocess.STDOUT, start_new_session=True)

    def output(self):
        with open(self.log_path) as f:
            return f.read()

    def agent_pid(self, agent):
        # launch starts each agent with "--id K --run-id RUN ..." (its own run id: only ours match).
        out = subprocess.run(["pgrep", "-f", "tessera-agent .*--id %d --run-id %s " % (agent, self.run_id)],
                             stdout=subprocess.PIPE, text=True).stdout.split()
        return int(out[0]) if out else None

    def kill_at(self, agent, at_round):
        # The pid is looked up before the rounds start: pgrep on a loaded host can take longer
        # than the rest of the run.
        deadline = time.time() + self.args.limit
        pid = None
        while pid is None:
            if time.time() > deadline or self.proc.poll() is not None:
                return False
            pid = self.agent_pid(agent)
            time.sleep(0.05)
        pattern = "round %d:" % at_round
        while pattern not in self.output():
            if time.time() > deadline or self.proc.poll() is not None:
                return False
            time.sleep(0.005)
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            return False
        return True

    def wait(self):
        try:
            code = self.proc.wait(timeout=self.args.limit + 30)
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, signal.SIGKILL)  # launch's own group; its children have theirs
            subprocess.run(["pkill", "-9", "-f", "tessera-.*--run-id %s " % self.run_id])
            code = -9
            self.proc.wait()
        wall = time.time() - self.t0
        self.log.close()
        cpu = bc.cpu_since(self.cpu0)
        summary = None
        if code == 0 and os.path.exists(self.summary):
            with open(self.summary) as f:
                summary = json.load(f)
        return code, wall, cpu, summary

    def merged_poses(self):
        return bc.g2o_vertex_ids(self.merged)


def main():
    args, rng, work, fstar = loss_benchmark_start(__doc__, 223, "tessera_faults_launch_loss_")

    ref = LaunchRun(args, work, "undisturbed")
    ref.start()
    code, ref_wall, ref_cpu, ref_summary = ref.wait()
    if code != 0 or ref_summary is None:
        print("undisturbed launch failed (exit %d); log in %s" % (code, ref.log_path))
        return 1
    rounds = int(ref_summary["rounds"])
    print("undisturbed launch: %d rounds, cost %.12g (error %.1e vs f*), wall %.2f s, cpu %.2f s" %
          (rounds, ref_summary["cost"], abs(ref_summary["cost"] - fstar) / fstar, ref_wall, ref_cpu),
          flush=True)

    trials = []
    for t in range(args.trials):
        agent = rng.randrange(args.agents)
        at = rng.randrange(2, max(3, rounds - 5))
        r = LaunchRun(args, work, "trial%d" % t)
        r.start()
        killed = r.kill_at(agent, at)
        code, wall, cpu, summary = r.wait()
        poses = len(r.merged_poses())
        fault = (summary or {}).get("fault") or {}
        ok = code == 0 and killed and poses == args.poses and fault.get("lost_agents") == [agent]
        err = abs(summary["cost"] - fstar) / fstar if ok else float("nan")
        trials.append(dict(trial=t, agent=agent, kill_round=at, finished=int(ok), launch_exit=code,
                           survivors=len(fault.get("survivors", [])), poses_in_estimate=poses,
                           moved_poses=fault.get("moved_poses", ""),
                           repartition_at_s=fault.get("repartition_at_s", ""),
                           cost=summary["cost"] if summary else "", rel_cost_error=err,
                           wall_s=round(wall, 3), cpu_s=round(cpu, 3), extra_s=round(wall - ref_wall, 3)))
        print("trial %d: kill agent %d at round %d -> %s, %d poses, cost error %.2e vs f*, wall %.2f s "
              "(+%.2f), cpu %.2f s" % (t, agent, at, "launch exit 0 with %d agents" % len(fault.get("survivors", []))
                                       if ok else "FAILED (exit %d, killed %s)" % (code, killed), poses, err,
                                       wall, wall - ref_wall, cpu), flush=True)
        if not ok:
            print("  log kept in %s" % r.log_path, flush=True)
    row = bc.fault_row("agent SIGKILLed for good under `tessera launch --on-agent-loss continue` "
                       "(N=%d, %d-pose grid3d; cost error vs f*)" % (args.agents, args.poses), trials)
    notes = fc.notes_head("Agent lost for good under `tessera launch`", "launch_loss") + [
             "`tessera launch GRAPH --agents %d --partition eco --grad-tol %g --on-agent-loss continue "
             "--rejoin-timeout %g --replica-every %d` on a %d-pose generated grid3d (seed 3); each trial "
             "SIGKILLs a random agent when launch prints a random round and never restarts it. "
             "f* = %.12g (centralized). Undisturbed launch with the same options: %d rounds, cost error "
             "%.1e, wall %.2f s, CPU %.2f s (all processes)." %
             (args.agents, args.grad_tol, args.rejoin_timeout, args.replica_every, args.poses, fstar, rounds,
              abs(ref_summary["cost"] - fstar) / fstar, ref_wall, ref_cpu), "",
             "| trial | agent | kill round | finished | survivors | poses | moved | rel. cost error vs f* "
             "| wall s | CPU s | extra s |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for x in trials:
        notes.append("| %d | %d | %d | %s | %s | %d | %s | %.1e | %.2f | %.2f | %+.2f |" %
                     (x["trial"], x["agent"], x["kill_round"], "yes" if x["finished"] else "NO (exit %d)" %
                      x["launch_exit"], x["survivors"], x["poses_in_estimate"], x["moved_poses"],
                      x["rel_cost_error"], x["wall_s"], x["cpu_s"], x["extra_s"]))
    return fc.finish(args, "launch_loss", row, trials, work, notes)


if __name__ == "__main__":
    sys.exit(main())
