#!/usr/bin/env python3
"""Distributed certification on every graph of ../shared/datasets (issue #7).

For each graph: `tessera solve G --algorithm irbcd --agents 5 --partition highest --certify`
(the in-process engine: same messages and rounds as over DDS) and the centralized certifiable
solver `tessera solve G --algorithm centralized`. Prints, and writes to
docs/benchmarks/distributed_certificate.{csv,md}: whether the distributed certificate holds,
its lambda_min beside the centralized one, the certificate's rounds and bytes beside the
solver's rounds and bytes (and the solver rounds spent refining an inconclusive certificate),
the staircase's final rank, and wall/CPU times. Each run has a time limit; graphs that did not
finish are listed as such. The machine's load average is recorded in the header (wall times
grow with load, CPU times much less).

usage: scripts/bench/distributed_certificate.py [--bin build/bin/tessera] [--limit 600]
       [--only NAME,NAME] [--datasets ../shared/datasets] [--algorithm irbcd]
       [--max-rounds 30000] [--extra "--certify-grad-tol 1e-4"]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402


def run(cmd, limit):
    """(json dict or None, wall s, cpu s of the child, status text)."""
    before = bc.children_usage()
    t0 = time.monotonic()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=limit)
        status = "ok" if p.returncode == 0 else f"exit {p.returncode}: {p.stderr.strip()[-200:]}"
    except subprocess.TimeoutExpired:
        status = f"timeout ({limit:.0f} s)"
    wall = time.monotonic() - t0
    cpu = bc.cpu_since(before)
    return status, wall, cpu


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin", "tessera"))
    ap.add_argument("--datasets", default=os.path.join(ROOT, "..", "shared", "datasets"))
    ap.add_argument("--limit", type=float, default=600.0, help="seconds per run")
    ap.add_argument("--only", default="", help="comma-separated graph names")
    ap.add_argument("--algorithm", default="irbcd", help="rbcd, rbcd++ or irbcd")
    ap.add_argument("--max-rounds", type=int, default=30000, help="solver round cap")
    ap.add_argument("--extra", default="", help="more `tessera solve` options (distributed run)")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "benchmarks", "distributed_certificate"))
    a = ap.parse_args()
    if not os.path.isdir(a.datasets):
        print(f"no datasets at {a.datasets}: nothing to do", file=sys.stderr)
        return 0
    graphs = sorted((f for f in os.listdir(a.datasets) if f.endswith(".g2o")),
                    key=lambda f: os.path.getsize(os.path.join(a.datasets, f)))
    if a.only:
        keep = set(a.only.split(","))
        graphs = [g for g in graphs if g[:-4] in keep]
    rows = []
    a.load_start = os.getloadavg()
    t_start = time.monotonic()
    tmp = tempfile.mkdtemp(prefix="tessera-cert-")
    for g in graphs:
        name, path = g[:-4], os.path.join(a.datasets, g)
        dj, cj = os.path.join(tmp, name + ".dist.json"), os.path.join(tmp, name + ".central.json")
        print(f"{name}: distributed ...", file=sys.stderr, flush=True)
        ds, dwall, dcpu = run([a.bin, "solve", path, "--algorithm", a.algorithm, "--agents", "5",
                               "--partition", "highest", "--certify", "--max-rounds",
                               str(a.max_rounds), "--json", dj] + a.extra.split(), a.limit)
        print(f"{name}: {ds}, {dwall:.1f} s; centralized ...", file=sys.stderr, flush=True)
        cs, cwall, ccpu = run([a.bin, "solve", path, "--algorithm", "centralized", "--json", cj], a.limit)
        d = json.load(open(dj)) if ds == "ok" else {}
        c = json.load(open(cj)) if cs == "ok" else {}
        total = d.get("bytes_exchanged")
        cert_b, esc_b = d.get("certificate_bytes"), d.get("escape_bytes")
        solver_b = total - cert_b - esc_b if None not in (total, cert_b, esc_b) else None
        rows.append({
            "graph": name, "poses": d.get("poses", c.get("poses")),
            "status": ds if ds == cs else f"distributed {ds}; centralized {cs}",
            "certified": d.get("certified"), "central_certified": c.get("certified"),
            "min_eigenvalue": d.get("min_eigenvalue"), "central_min_eigenvalue": c.get("min_eigenvalue"),
            "eta": d.get("certificate_tolerance"), "residual": d.get("certificate_residual"),
            "final_rank": d.get("final_rank"), "central_final_rank": c.get("final_rank"),
            "solver_rounds": d.get("rounds"), "solver_bytes": solver_b,
            "refine_rounds": d.get("refine_rounds"), "stop_reason": d.get("stop_reason"),
            "certificate_rounds": d.get("certificate_rounds"), "certificate_bytes": cert_b,
            "escape_rounds": d.get("escape_rounds"), "escape_bytes": esc_b,
            "grad_norm": d.get("grad_norm"), "cost": d.get("cost"), "central_cost": c.get("cost"),
            "rel_gap": (d["cost"] - c["cost"]) / abs(c["cost"]) if d.get("cost") and c.get("cost") else None,
            "wall_s": round(dwall, 2), "cpu_s": round(dcpu, 2), "central_wall_s": round(cwall, 2),
        })
        print(rows[-1], file=sys.stderr, flush=True)
        a.load_end = os.getloadavg()
        a.total_s = time.monotonic() - t_start
        write(a.out, rows, a)
    return 0


def fmt(x, spec="{:.3g}"):
    if x is None:
        return "-"
    if isinstance(x, bool):
        return "yes" if x else "NO"
    return spec.format(x) if isinstance(x, float) else str(x)


def write(out, rows, a):
    os.makedirs(os.path.dirname(out), exist_ok=True)
    bc.write_csv(out + ".csv", rows, announce=False)
    head = ["graph", "poses", "certified (dist / central)", "lambda_min dist", "lambda_min central",
            "eta", "final rank", "solver rounds", "solver MB", "of which refine rounds",
            "cert rounds", "cert MB", "escape rounds", "rel gap", "wall s (CPU s)", "status"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    mb = lambda b: None if b is None else b / 1e6
    for r in rows:
        lines.append("| " + " | ".join([
            r["graph"], fmt(r["poses"]), f"{fmt(r['certified'])} / {fmt(r['central_certified'])}",
            fmt(r["min_eigenvalue"]), fmt(r["central_min_eigenvalue"]), fmt(r["eta"]),
            f"{fmt(r['final_rank'])} / {fmt(r['central_final_rank'])}", fmt(r["solver_rounds"]),
            fmt(mb(r["solver_bytes"])), fmt(r["refine_rounds"]),
            fmt(r["certificate_rounds"]), fmt(mb(r["certificate_bytes"])),
            fmt(r["escape_rounds"]), fmt(r["rel_gap"]), f"{r['wall_s']} ({r['cpu_s']})", r["status"]]) + " |")
    cmd = "scripts/bench/distributed_certificate.py --limit {:.0f}".format(a.limit)
    if a.algorithm != "irbcd":
        cmd += " --algorithm " + a.algorithm
    if a.max_rounds != 30000:
        cmd += f" --max-rounds {a.max_rounds}"
    if a.extra:
        cmd += f' --extra "{a.extra}"'
    load = lambda l: "/".join(f"{x:.1f}" for x in l)
    text = (f"Distributed certification, N = 5, highest partition, {a.algorithm}, chordal init, "
            f"solver grad tol 0.01, refinement to 1e-4 only when a certificate is inconclusive; "
            f"round cap {a.max_rounds}, limit {a.limit:.0f} s per run (`{cmd}`, under nice -n 10). "
            f"Machine: 2 cores shared with other jobs, load average (1/5/15 min) {load(a.load_start)} "
            f"at the start and {load(a.load_end)} at the end; {len(rows)} graphs in "
            f"{a.total_s:.0f} s wall. Wall times are inflated by the load; the CPU column is the "
            "process's own user+sys time. Solver MB excludes the certificate's and escapes' bytes; "
            "rel gap = (distributed cost - centralized cost) / centralized cost of the rounded poses.\n\n"
            + "\n".join(lines) + "\n")
    with open(out + ".md", "w") as f:
        f.write(text)
    print(text)


if __name__ == "__main__":
    sys.exit(main())
