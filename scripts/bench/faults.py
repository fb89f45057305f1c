#!/usr/bin/env python3
"""Fault benchmark of the DDS runtime (issue 8) and assembler of docs/benchmarks/faults.md.

Every fault benchmark writes one docs/benchmarks/faults_<name>.csv row with the column
contract of scripts/bench/faults_common.py (fault,trials,finished,cost_error,extra_time_s);
`--assemble-only` rebuilds faults.md from whatever faults_*.csv exist, followed by every
docs/benchmarks/faults/*.md (each experiment's notes: command, machine, details).

This script's own experiment (`restart`): a generated 3D grid, N = 5 agents with
--checkpoint-dir, the coordinator with --rejoin-timeout. Each trial SIGKILLs a random agent
when the coordinator reports a random round, starts it again with the same options after a
random delay (0-1 s), and checks that the run finishes at the undisturbed run's cost.
Per-trial details go to docs/benchmarks/faults/restart_trials.csv, the checkpoint write cost
(undisturbed runs without / with checkpoints) to docs/benchmarks/faults/checkpoint_cost.csv.
"""
import csv
import glob
import json
import os
import random
import re
import signal
import subprocess
import sys
import time
import functools

print = functools.partial(print, flush=True)  # progress shows up in logs as it happens

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402
import faults_common as fc  # noqa: E402
from faults_common import COLUMNS, OUT_DIR, assemble, write_contract_csv  # noqa: E402,F401 (used by older callers)


class Run:
    """A coordinator and N agents started together; optional kill + restart of one agent."""

    def __init__(self, args, work, name, checkpoints=True, rejoin_timeout=30):
        self.args, self.work, self.name = args, work, name
        self.dir = os.path.join(work, name)
        os.makedirs(self.dir, exist_ok=True)
        self.ckpt = os.path.join(self.dir, "ckpt")
        os.makedirs(self.ckpt, exist_ok=True)
        self.run_id = "faults-%d-%s" % (os.getpid(), name)
        self.checkpoints = checkpoints
        self.rejoin_timeout = rejoin_timeout
        self.procs = []

    def agent_cmd(self, k):
        cmd = [os.path.join(self.args.bin_dir, "tessera-agent"), "--graph", self.args.graph_path,
               "--robots", str(self.args.agents), "--id", str(k), "--run-id", self.run_id,
               "--domain", str(self.args.domain), "--timeout", "60"]
        if self.checkpoints:
            cmd += ["--checkpoint-dir", self.ckpt, "--checkpoint-every", str(self.args.every)]
        return cmd

    def spawn(self, cmd, log, env=None):
        f = open(os.path.join(self.dir, log), "w")
        full = dict(os.environ)
        for kv in env or []:
            k, _, v = kv.partition("=")
            full[k] = v
        return subprocess.Popen(cmd, stdout=f, stderr=subprocess.STDOUT, start_new_session=True, env=full)

    def start(self):
        self.t0 = time.time()
        self.summary = os.path.join(self.dir, "summary.json")
        ccmd = [os.path.join(self.args.bin_dir, "tessera-coordinator"), "--agents", str(self.args.agents),
                "--run-id", self.run_id, "--domain", str(self.args.domain), "--timeout", "60",
                "--run-timeout", str(self.args.limit), "--summary", self.summary, "--progress",
                "--partition", "highest", "--grad-tol", str(self.args.grad_tol),
                "--rejoin-timeout", str(self.rejoin_timeout), "--status-interval", "2",
                "--progress-interval", "0"]
        self.coord = self.spawn(ccmd, "coordinator.log")
        self.agents = {k: self.spawn(self.agent_cmd(k), "agent%d.log" % k) for k in range(self.args.agents)}
        self.procs = [self.coord] + list(self.agents.values())

    def coordinator_output(self):
        with open(os.path.join(self.dir, "coordinator.log")) as f:
            return f.read()

    def kill_and_restart(self, agent, at_round, delay):
        if not bc.wait_for_output(self.coordinator_output, "round %d:" % at_round,
                                  time.time() + self.args.limit, lambda: self.coord.poll() is None):
            return False
        victim = self.agents[agent]
        os.kill(victim.pid, signal.SIGKILL)
        victim.wait()
        self.procs.remove(victim)  # its exit code is the kill, not a failure
        time.sleep(delay)
        p = self.spawn(self.agent_cmd(agent), "agent%d-restarted.log" % agent, self.args.restart_env)
        self.procs.append(p)
        return True

    def wait(self):
        deadline = time.time() + self.args.limit
        codes = []
        for p in self.procs:
            try:
                codes.append(p.wait(timeout=max(1, deadline - time.time())))
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                codes.append(-9)
        wall = time.time() - self.t0
        summary = None
        if os.path.exists(self.summary):
            with open(self.summary) as f:
                summary = json.load(f)
        return codes, wall, summary

    def checkpoint_cost(self):
        """Sum over agents of (writes, ms) from the agents' 'checkpoints:' lines."""
        writes, ms, size = 0, 0.0, 0
        for log in glob.glob(os.path.join(self.dir, "agent*.log")):
            with open(log) as f:
                m = re.search(r"checkpoints: (\d+) written, ([0-9.]+) ms in total .* (\d+) bytes each", f.read())
            if m:
                writes += int(m.group(1))
                ms += float(m.group(2))
                size = max(size, int(m.group(3)))
        return writes, ms, size


def main():
    ap = fc.parser(__doc__, trials=10, agents=5, poses=500, domain=212, limit=300)
    ap.add_argument("--grad-tol", type=float, default=0.002)
    ap.add_argument("--every", type=int, default=1, help="--checkpoint-every of the agents")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--assemble-only", action="store_true")
    ap.add_argument("--restart-env", action="append", default=[], help="KEY=VALUE for the restarted agent (diagnostics)")
    args = ap.parse_args()
    if args.assemble_only:
        assemble(args.out_dir)
        return 0
    if args.every < 1:
        sys.exit("option --every: must be at least 1")
    rng = random.Random(args.seed)
    work = fc.start(args, "tessera_faults_")

    # Undisturbed runs: without checkpoints, and with them (the reference of the trials).
    base = {}
    for name, ck in (("plain", False), ("checkpointed", True)):
        r = Run(args, work, "undisturbed-" + name, checkpoints=ck)
        r.start()
        codes, wall, summary = r.wait()
        if any(codes) or not summary:
            print("undisturbed run (%s) failed: exit codes %s; logs in %s" % (name, codes, r.dir))
            return 1
        base[name] = (wall, summary, r.checkpoint_cost())
        print("undisturbed %-12s: %d rounds, cost %.12g, wall %.2f s" %
              (name, summary["rounds"], summary["cost"], wall))
    ref_wall, ref, _ = base["checkpointed"]
    rounds = int(ref["rounds"])
    if rounds < 8:
        print("the run is too short (%d rounds) to kill it in the middle" % rounds)
        return 1

    trials = []
    for t in range(args.trials):
        agent = rng.randrange(args.agents)
        at = rng.randrange(2, max(3, rounds - 3))
        delay = rng.uniform(0.0, 1.0)
        r = Run(args, work, "trial%d" % t)
        r.start()
        killed = r.kill_and_restart(agent, at, delay)
        codes, wall, summary = r.wait()
        ok = killed and not any(codes) and summary is not None
        err = abs(summary["cost"] - ref["cost"]) / ref["cost"] if ok else float("nan")
        trials.append(dict(trial=t, agent=agent, kill_round=at, restart_delay_s=round(delay, 3),
                           finished=int(ok), rounds=summary["rounds"] if summary else "",
                           rollbacks=summary.get("rollbacks", "") if summary else "",
                           cost=summary["cost"] if summary else "", rel_cost_error=err,
                           wall_s=round(wall, 3), extra_s=round(wall - ref_wall, 3)))
        print("trial %d: kill agent %d at round %d, restart after %.2f s -> %s, cost error %.2e, "
              "wall %.2f s (+%.2f)" % (t, agent, at, delay, "finished" if ok else "FAILED %s" % codes,
                                       err, wall, wall - ref_wall))
        if not ok:
            print("  logs kept in %s" % r.dir)
    row = bc.fault_row("agent SIGKILLed at a random round, restarted with the same id (N=%d, %d-pose grid3d)"
                       % (args.agents, args.poses), trials)
    os.makedirs(os.path.join(args.out_dir, "faults"), exist_ok=True)
    with open(os.path.join(args.out_dir, "faults", "checkpoint_cost.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["run", "wall_s", "rounds", "checkpoint_writes", "checkpoint_ms_total", "checkpoint_bytes"])
        for name, (wall, s, (writes, ms, size)) in base.items():
            w.writerow([name, "%.3f" % wall, s["rounds"], writes, "%.1f" % ms, size])
    w_plain, w_ck = base["plain"][0], base["checkpointed"][0]
    writes, ms, size = base["checkpointed"][2]
    print("checkpoints (every %d rounds): %d writes by %d agents, %.1f ms in total (%.2f ms each, %d bytes); "
          "undisturbed wall %.2f s without, %.2f s with" %
          (args.every, writes, args.agents, ms, ms / max(1, writes), size, w_plain, w_ck))
    notes = fc.notes_head("Agent killed and restarted", "restart") + [
             "%d-pose generated grid3d, N = %d, IRBCD, `highest`, grad tol %g; every agent with "
             "`--checkpoint-dir` (`--checkpoint-every %d`), the coordinator with `--rejoin-timeout 30`. "
             "Each trial SIGKILLs a random agent when the coordinator reports a random round and starts "
             "it again with the same options after a random 0-1 s delay. cost_error is against the "
             "undisturbed run with checkpoints; extra_time_s is the mean wall-time difference (it "
             "includes the restart delay, the 1.5-lease wait of the restarted agent before it joins, "
             "discovery, and the repeated rounds)." % (args.poses, args.agents, args.grad_tol, args.every), "",
             "| trial | agent | kill round | restart delay s | finished | rounds | rollbacks | rel. cost error | wall s | extra s |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for x in trials:
        notes.append("| %d | %d | %d | %.2f | %s | %s | %s | %.1e | %.2f | %+.2f |" % (
            x["trial"], x["agent"], x["kill_round"], x["restart_delay_s"], "yes" if x["finished"] else "NO",
            x["rounds"], x["rollbacks"], x["rel_cost_error"], x["wall_s"], x["extra_s"]))
    notes += ["", "Checkpoint cost (undisturbed runs): %d rounds; wall %.2f s without checkpoints, %.2f s "
              "with (one run each); %d checkpoint writes by the %d agents took %.1f ms in total "
              "(%.2f ms per write: encode, write, fsync, rename, folder fsync; %d bytes each)." %
              (ref["rounds"], w_plain, w_ck, writes, args.agents, ms, ms / max(1, writes), size),
              "", "Machine: %s, %d cores, shared with other builds and benchmarks while measured "
              "(wall times are inflated and noisy)." % (os.uname().machine, os.cpu_count())]
    return fc.finish(args, "restart", row, trials, work, notes)


if __name__ == "__main__":
    sys.exit(main())
