#!/usr/bin/env python3
"""What a launch costs after a pause against back to back, and what the heaps' page size has to do
with it.

A virtual machine whose kernel reports free memory to its host (free page reporting: free blocks of
2 MB and more are handed back a few seconds after they are freed) pays for the first touch of such
memory again: the host maps it anew. Transparent huge pages are taken whole from those blocks; 4 KB
pages mostly come from smaller free blocks the kernel did not report. So a process whose heap is in
huge pages (glibc.malloc.hugetlb=1) pays after a pause what it does not pay back to back.

Two measurements, each `--repeat` times:
  memory  first touch of `--memory` MB of fresh anonymous memory, in 2 MB pages (madvise
          MADV_HUGEPAGE) and in 4 KB pages: after `--pause` seconds, then again at once; CPU-s of
          this process (user + system)
  launch  per heap mode (`4k`: GLIBC_TUNABLES=glibc.malloc.hugetlb=0; `huge`: ...=1, what
          `--heap-pages auto` gives where a fresh 4 KB page costs 8 us or more), after `--pause` seconds, `--runs`
          launches of G back to back (`tessera launch G --agents N`); per position: CPU-s of all
          the run's processes (user, system), minor faults, huge pages faulted (/proc/vmstat
          thp_fault_alloc, machine-wide) and the wall
The modes alternate (which goes first changes each repeat). Prints medians per mode and position
and the load; CPU-s are load-dependent only through cache and scheduling effects, faults not.

usage: launch_cold.py [--bin build/bin] [--graph G] [--agents 5] [--domain 198] [--pause 10]
                      [--runs 3] [--repeat 3] [--memory 256] [--modes 4k,huge] [--skip-memory]
"""
import argparse
import mmap
import os
import resource
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402

PAGE = 4096


def own_cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def first_touch(mb, huge):
    """CPU-s to touch `mb` MB of fresh anonymous memory once per 4 KB page."""
    m = mmap.mmap(-1, mb << 20, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)
    if huge:
        m.madvise(mmap.MADV_HUGEPAGE)
    c0 = own_cpu()
    for at in range(0, mb << 20, PAGE):
        m[at] = 1
    c = own_cpu() - c0
    m.close()
    return c


def thp_faults():
    with open("/proc/vmstat") as f:
        for line in f:
            if line.startswith("thp_fault_alloc "):
                return int(line.split()[1])
    return 0


def run_launch(a, env):
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    h0 = thp_faults()
    t0 = time.monotonic()
    p = subprocess.run([os.path.join(a.bin, "tessera"), "launch", a.graph, "--agents", str(a.agents),
                        "--domain", str(a.domain)], env=env, capture_output=True, text=True)
    wall = time.monotonic() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        print(p.stdout[-400:] + p.stderr[-400:], file=sys.stderr)
        return None
    user, system = r1.ru_utime - r0.ru_utime, r1.ru_stime - r0.ru_stime
    return dict(cpu=user + system, user=user, system=system, minflt=r1.ru_minflt - r0.ru_minflt,
                thp=thp_faults() - h0, wall=wall)


def env_for(mode):
    env = dict(os.environ)
    # Both modes say it explicitly, so the script measures the same on launches that set no
    # tunable and on launches that ask for huge pages themselves (launch/heap_pages.hpp).
    env["GLIBC_TUNABLES"] = "glibc.malloc.hugetlb=" + ("1" if mode == "huge" else "0")
    return env


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin"))
    ap.add_argument("--graph", default=os.path.join(ROOT, "..", "shared", "datasets", "city10000.g2o"))
    ap.add_argument("--agents", type=int, default=5)
    ap.add_argument("--domain", type=int, default=198)
    ap.add_argument("--pause", type=float, default=10.0, help="seconds idle before each series")
    ap.add_argument("--runs", type=int, default=3, help="launches back to back after each pause")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--memory", type=int, default=256, help="MB touched by the memory probe")
    ap.add_argument("--modes", default="4k,huge")
    ap.add_argument("--skip-memory", action="store_true")
    a = ap.parse_args()
    modes = a.modes.split(",")
    print(f"machine at start: {bc.machine()}")
    if not a.skip_memory:
        touch = {}
        for rep in range(a.repeat):
            for huge in (True, False) if rep % 2 == 0 else (False, True):
                time.sleep(a.pause)
                cold = first_touch(a.memory, huge)
                hot = first_touch(a.memory, huge)
                touch.setdefault(huge, []).append((cold, hot))
        for huge, v in touch.items():
            print(f"memory {a.memory} MB in {'2 MB' if huge else '4 KB'} pages: after the pause "
                  f"{statistics.median(c for c, _ in v):.3f} CPU-s ({', '.join(f'{c:.3f}' for c, _ in v)}), "
                  f"at once {statistics.median(h for _, h in v):.3f} ({', '.join(f'{h:.3f}' for _, h in v)})")
    rows = {}
    for rep in range(a.repeat):
        for mode in modes if rep % 2 == 0 else modes[::-1]:
            time.sleep(a.pause)
            for pos in range(a.runs):
                r = run_launch(a, env_for(mode))
                if r:
                    r["load"] = os.getloadavg()[0]
                    rows.setdefault((mode, pos), []).append(r)
    print(f"launch {os.path.basename(a.graph)} --agents {a.agents}: medians of {a.repeat} "
          "(position 0 = first launch after the pause)")
    print(f"{'mode':6s} {'pos':>3s} {'CPU-s':>7s} {'user':>7s} {'system':>7s} {'minflt':>8s} {'THP':>5s} "
          f"{'wall':>7s}  single runs' CPU-s")
    for (mode, pos), rs in sorted(rows.items()):
        med = {k: statistics.median(r[k] for r in rs) for k in ("cpu", "user", "system", "minflt", "thp", "wall")}
        print(f"{mode:6s} {pos:3d} {med['cpu']:7.3f} {med['user']:7.3f} {med['system']:7.3f} "
              f"{med['minflt']:8.0f} {med['thp']:5.0f} {med['wall']:7.3f}  "
              f"{', '.join('%.3f' % r['cpu'] for r in rs)}")
    print(f"machine at end: {bc.machine()}")


if __name__ == "__main__":
    main()
