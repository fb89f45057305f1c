#!/usr/bin/env python3
"""Where the start-up of one `tessera launch G --agents N` goes, process by process.

Runs the launch with TESSERA_DDS_TRACE=1 and --keep-logs, merges the processes' logs on the
host's monotonic clock and prints, per process, the wall time (ms since the coordinator's start)
and the process's own CPU time (ms, all its threads: what a step cost whatever the load) at each
start-up step:
  created     its DDS participant exists
  endpoints   its readers and writers exist
  announce    (agents) its announcement writer matched the coordinator's reader
  assignment  (agents) the assignment received
  barrier     the readiness barrier passed (every endpoint matched, READY from everyone)
  init        (agents) the initialisation stage done (chordal start)
  hand-off    (agents) every other agent's hand-off received
  set-up      (agents) the block set-up done (the block updates' factorizations)
and the coordinator's timeline; how long after the coordinator's announcement reader matched
each agent's writer the announcement arrived; what sending agent 0's hand-off took (parts, wall,
waits for acknowledgements). Then every ordered pair of processes (X sees Y) whose endpoint
matches completed more than --late ms after X discovered Y's participant: the signature of an
endpoint-discovery message that arrived before its sender's participant was known, dropped and
recovered only by the reader's first acknowledgement (Fast DDS 2.9's built-in endpoint-discovery
readers wait 70 ms for it), when the reverse direction (Y sees X) completed at once.

usage: launch_trace.py GRAPH [--agents 5] [--domain 158] [--bin build/bin] [--keep DIR]
                             [--late 40] [-- extra launch flags]
"""
import argparse
import glob
import json
import os
import re
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))

DDS_LINE = re.compile(r"^\[dds\s+[\d.]+ @([\d.]+) cpu ([\d.]+) (\S+)\] (.*)$")
AGENT_LINE = re.compile(r"^tessera-agent\[(\d+)\] @([\d.]+) cpu ([\d.]+): (.*)$")
STEPS = [("created", "participant created", True), ("endpoints", "endpoints created", True),
         ("announce", "tessera_announce/w matched", True),
         ("assignment", "received on tessera_assignment", True),
         ("barrier", "barrier: passed", True), ("init", "initialisation '", False),
         ("hand-off", "hand-off complete", False), ("set-up", "memory after block set-up", False)]


def who_of(participant):
    last = participant.split(":")[-1]
    return "c" if last == "coordinator" else "a" + last


def read_events(folder):
    """(monotonic s, CPU s, process, text, from the DDS trace) of every stamped line."""
    events = []
    for path in glob.glob(os.path.join(folder, "*.log")):
        for line in open(path, errors="replace"):
            m = DDS_LINE.match(line)
            if m:
                events.append((float(m.group(1)), float(m.group(2)), who_of(m.group(3)),
                               m.group(4), True))
                continue
            m = AGENT_LINE.match(line)
            if m:
                events.append((float(m.group(2)), float(m.group(3)), "a" + m.group(1), m.group(4),
                               False))
    events.sort()
    return events


def peer_of(text):
    m = re.search(r"discovered: '[^']*:(agent:(\d+)|coordinator)'", text)
    if m:
        return "c" if m.group(1) == "coordinator" else "a" + m.group(2)
    m = re.search(r" matched (agent (\d+)|the coordinator)", text)
    if m:
        return "c" if m.group(1) == "the coordinator" else "a" + m.group(2)
    return None


def late_pairs(events, late_ms):
    discovered, last_match = {}, {}
    for t, _, who, text, _ in events:
        peer = peer_of(text)
        if not peer:
            continue
        if "participant discovered" in text:
            discovered.setdefault((who, peer), t)
        elif " matched " in text and "unmatched" not in text:
            last_match[(who, peer)] = t
    out = []
    for pair, t in sorted(last_match.items()):
        if pair not in discovered:
            continue
        gap = 1000 * (t - discovered[pair])
        back = (pair[1], pair[0])
        back_gap = 1000 * (last_match[back] - discovered[back]) if back in last_match and \
            back in discovered else float("nan")
        if gap > late_ms:
            out.append((pair, gap, back_gap))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("graph")
    ap.add_argument("--agents", type=int, default=5)
    ap.add_argument("--domain", type=int, default=158)
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin"))
    ap.add_argument("--keep", default="", help="folder for the logs (default: a temporary one)")
    ap.add_argument("--late", type=float, default=40.0, help="ms; see above")
    ap.add_argument("extra", nargs="*", help="extra tessera launch flags (after --)")
    a = ap.parse_args()
    folder = a.keep or tempfile.mkdtemp(prefix="launch-trace-")
    summary = os.path.join(folder, "summary.json")
    env = dict(os.environ, TESSERA_DDS_TRACE="1")
    load = open("/proc/loadavg").read().split()[0]
    p = subprocess.run([os.path.join(a.bin, "tessera"), "launch", a.graph, "--agents", str(a.agents),
                        "--domain", str(a.domain), "--keep-logs", folder, "--json", summary,
                        "--quiet"] + a.extra, env=env, capture_output=True, text=True)
    if p.returncode != 0 or not os.path.exists(summary):
        print(p.stdout[-2000:] + p.stderr[-2000:], file=sys.stderr)
        sys.exit(1)
    s = json.load(open(summary))
    t0 = s["started_monotonic_ms"] / 1000
    events = read_events(folder)
    print("%s, %d agents, load %s before the run (logs in %s)" % (a.graph, a.agents, load, folder))
    print("wall ms since the coordinator's start / process CPU ms")
    print("%-4s" % "" + "".join("%15s" % name for name, _, _ in STEPS))
    for who in ["c"] + ["a%d" % k for k in range(a.agents)]:
        cells = []
        for _, text, dds in STEPS:
            hit = next(((t, c) for t, c, w, m, d in events
                        if w == who and d == dds and (m.startswith(text) or text in m)), None)
            cells.append("%8.0f/%5.0f" % (1000 * (hit[0] - t0), 1000 * hit[1]) if hit else "%14s" % "-")
        print("%-4s" % who + " ".join(cells))
    print("coordinator timeline, ms: " +
          ", ".join("%s %.0f" % (k, v) for k, v in (s.get("timeline_ms") or {}).items()))
    # A TRANSIENT_LOCAL announcement that arrived before the coordinator's reader had matched its
    # writer comes again only when that reader asks (its first acknowledgement).
    matched, received = {}, {}
    for t, _, who, text, _ in events:
        m = re.match(r"tessera_announce/r matched agent (\d+)", text)
        if who == "c" and m:
            matched.setdefault(int(m.group(1)), t)
        m = re.match(r"received on tessera_announce from agent (\d+)", text)
        if who == "c" and m:
            received.setdefault(int(m.group(1)), t)
    print("announcements, the coordinator's reader matched -> sample received, ms: " +
          ", ".join("a%d %.0f" % (k, 1000 * (received[k] - matched[k]))
                    for k in sorted(matched) if k in received))
    for line in open(os.path.join(folder, "agent0.log"), errors="replace"):
        if "hand-off complete" in line and "sent" in line:
            print("agent 0's hand-off: " + line.split("measurements; ", 1)[-1].strip())
    pairs = late_pairs(events, a.late)
    print("endpoint matches later than %.0f ms after the participant's discovery (X sees Y: ms; "
          "Y sees X: ms): %s" % (a.late, ", ".join("%s<-%s %.0f (%.0f)" % (x, y, g, b)
                                                   for (x, y), g, b in pairs) or "none"))


if __name__ == "__main__":
    main()
