#!/usr/bin/env python3
"""Secured run (issue 8, item 4) for the fault table: `tessera launch --security DIR` against
the same launch without security, with an unauthenticated outsider watching the secured run.

Per trial, on one generated grid3d (fresh run ids, one domain):
  unsecured   tessera launch GRAPH --agents N --partition eco --no-certify --transport default
              (UDP + shared memory as the secured run; launch alone would use shared memory only)
  secured     the same with --security DIR (scripts/security/make_identities.sh DIR N), while
              tessera-dds-snoop (no identity) subscribes to every Tessera topic of that run, and
              a second one (no identity) advertises agent 1's participant name ("impostor")
A secured trial counts as finished when launch exits 0 with the unsecured run's rounds; its
cost error is against that trial's unsecured run; extra time is the secured wall time minus
the unsecured one (handshakes, encryption). The outsider's sample count must be 0 (and the same
outsider must read > 0 samples of the unsecured run: the control that it works); the impostor
must read 0 samples and stop nothing.

Writes docs/benchmarks/faults_secured.csv (column contract of scripts/bench/faults.py),
docs/benchmarks/faults/secured.md (per-trial table) and re-assembles faults.md.
CPU time = user + sys of launch and every process it started.

usage: scripts/bench/faults_secured.py [--bin-dir build/bin] [--out-dir docs/benchmarks]
           [--trials 5] [--agents 3] [--poses 500] [--domain 224] [--limit 120]
"""
import json
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402
import faults_common as fc  # noqa: E402

MAKE_IDENTITIES = os.path.join(fc.ROOT, "scripts", "security", "make_identities.sh")


def launch(args, work, name, extra):
    """One launch; returns (exit code, wall s, cpu s, summary or None)."""
    summary = os.path.join(work, name + ".json")
    cmd = [os.path.join(args.bin_dir, "tessera"), "launch", args.graph, "--agents", str(args.agents),
           "--partition", "eco", "--no-certify", "--quiet", "--domain", str(args.domain), "--run-id", name,
           "--json", summary, "--timeout", str(args.limit)] + extra
    before = bc.children_usage()
    t0 = time.time()
    with open(os.path.join(work, name + ".log"), "w") as log:
        try:
            code = subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT, timeout=args.limit + 30).returncode
        except subprocess.TimeoutExpired:
            code = -9
    wall = time.time() - t0
    cpu = bc.cpu_since(before)
    data = None
    if code == 0 and os.path.exists(summary):
        with open(summary) as f:
            data = json.load(f)
    return code, wall, cpu, data


def start_snoop(args, work, log_name, name, extra=()):
    """tessera-dds-snoop (no identity) on run `name`, started and listening; returns (process, log path)."""
    snoop_log = os.path.join(work, log_name)
    log = open(snoop_log, "w")
    snoop = subprocess.Popen([os.path.join(args.bin_dir, "tessera-dds-snoop"), "--domain", str(args.domain),
                              "--run-id", name, "--duration", str(args.limit + 10)] + list(extra),
                             stdout=log, stderr=subprocess.STDOUT)
    log.close()
    for _ in range(200):  # its readers exist before the run starts
        with open(snoop_log) as f:
            if "listening" in f.read():
                break
        time.sleep(0.05)
    return snoop, snoop_log


def stop_snoop(snoop, snoop_log):
    """Stops a snoop; its sample count (-1 when it printed none)."""
    snoop.send_signal(2)
    try:
        snoop.wait(timeout=10)
    except subprocess.TimeoutExpired:
        snoop.kill()
        snoop.wait()
    with open(snoop_log) as f:
        m = re.search(r"samples=(\d+)", f.read())
    return int(m.group(1)) if m else -1


def watched_launch(args, work, name, extra, impostor=False):
    """launch() while tessera-dds-snoop (no identity) subscribes to the run; adds its sample count.
    `impostor`: a second snoop without identity advertises agent 1's participant name (and a
    "UDP only" tag) during the run; adds its sample count too (else -1)."""
    snoop = start_snoop(args, work, name + "-snoop.log", name)
    fake = start_snoop(args, work, name + "-impostor.log", name,
                       ["--name", "tessera:%s:agent:1" % name, "--user-data", "tessera-tags;udp_only=1"]) \
        if impostor else None
    result = launch(args, work, name, extra)
    samples = stop_snoop(*snoop)
    return result + (samples, stop_snoop(*fake) if fake else -1)


def main():
    args = fc.parser(__doc__, trials=5, agents=3, poses=500, domain=224, limit=120).parse_args()
    work = fc.start(args, "tessera_faults_secured_")
    args.graph = args.graph_path
    sec = os.path.join(work, "sec")
    subprocess.run([MAKE_IDENTITIES, sec, str(args.agents)], check=True, stdout=subprocess.DEVNULL)

    rows = []
    for t in range(args.trials):
        base = "sec-%d-%d" % (os.getpid(), t)
        # The same outsider reads the unsecured run (control: > 0 shows the snoop works).
        # Over UDP + shared memory like the secured run (launch's own default for an unsecured
        # run is shared memory only, which an outsider on the default transports never hears).
        pc, pwall, pcpu, plain, control, _ = watched_launch(args, work, base + "-plain",
                                                            ["--transport", "default"])
        # The secured run also has an impostor of agent 1 (it must change nothing, read nothing).
        sc, swall, scpu, secured, samples, fake = watched_launch(args, work, base + "-secured",
                                                                 ["--security", sec], impostor=True)
        ok = sc == 0 and secured is not None and plain is not None and \
            secured["rounds"] == plain["rounds"] and samples == 0 and fake == 0 and control > 0
        err = abs(secured["cost"] - plain["cost"]) / plain["cost"] if ok else float("nan")
        rows.append(dict(trial=t, plain_exit=pc, secured_exit=sc, finished=int(ok),
                         rounds=secured["rounds"] if secured else "", rel_cost_error=err,
                         plain_wall_s=pwall, secured_wall_s=swall, extra_s=swall - pwall,
                         plain_cpu_s=pcpu, secured_cpu_s=scpu,
                         outsider_samples=samples, outsider_samples_unsecured=control,
                         impostor_samples=fake))
        print("trial %d: unsecured exit %d wall %.2f s cpu %.2f s | secured exit %d wall %.2f s cpu %.2f s | "
              "rel. cost error %.1e | outsider samples %d (unsecured run: %d), impostor %d" %
              (t, pc, pwall, pcpu, sc, swall, scpu, err, samples, control, fake),
              flush=True)
    row = bc.fault_row("secured run (--security, %d agents, %d-pose grid3d; cost error vs the unsecured run; "
                       "an unauthenticated outsider and an impostor of agent 1's name read 0 samples)" % (args.agents, args.poses),
                       rows)
    notes = fc.notes_head("Secured run", "secured") + [
             "`tessera launch GRAPH --agents %d --partition eco --no-certify` without and with `--security DIR` "
             "(identities from `scripts/security/make_identities.sh`) on a %d-pose generated grid3d; during "
             "each secured run `tessera-dds-snoop` without an identity subscribes to every Tessera topic "
             "of that run, and a second one without identity advertises agent 1's participant name "
             "(`--name tessera:RUN:agent:1 --user-data 'tessera-tags;udp_only=1'`; a secured run must "
             "ignore it)." % (args.agents, args.poses), "",
             "| trial | finished | rounds | rel. cost error | unsecured wall s | secured wall s | "
             "unsecured CPU s | secured CPU s | outsider samples (secured / unsecured) | impostor samples |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        notes.append("| %d | %s | %s | %.1e | %.2f | %.2f | %.2f | %.2f | %d / %d | %d |" %
                     (r["trial"], "yes" if r["finished"] else "NO (exit %d/%d)" % (r["plain_exit"], r["secured_exit"]),
                      r["rounds"], r["rel_cost_error"], r["plain_wall_s"], r["secured_wall_s"], r["plain_cpu_s"],
                      r["secured_cpu_s"], r["outsider_samples"], r["outsider_samples_unsecured"],
                      r["impostor_samples"]))
    return fc.finish(args, "secured", row, rows, work, notes)


if __name__ == "__main__":
    sys.exit(main())
