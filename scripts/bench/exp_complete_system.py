#!/usr/bin/python3
"""Experiment 4 -- complete system (paper Table II): sequential+RBCD vs highest+IRBCD.

Graphs: sphere2500, parking-garage, manhattan3500, city10000 and a generated 3D grid (stand-in for
grid3D; rim has no measurements). Both configurations start from the same chordal initialisation
(written once into a copy of the graph by `tessera solve --max-rounds 0 --out`, then read with
the file's VERTEX poses). Runs as real agent processes over DDS with `tessera launch` when the
binary given by --launch-bin has it; otherwise with the in-process engine (same messages, one
process), and the output says which. Reported: final cost, f*, relative gap, average time per
round per agent, rounds, average Cvolume (of the partition `tessera partition` computes with the
same preset), partition time, bytes sent per agent.

  scripts/bench/exp_complete_system.py [--quick] [--bin B] [--launch-bin B] [--shared S] [--out-dir D]
"""
import argparse
import json
import os
import re
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_common as bc  # noqa: E402

CONFIGS = [("sequential", "rbcd"), ("highest", "irbcd")]
ROUND_RE = re.compile(r"^round (\d+): cost ([-+0-9.eE]+), grad norm ([-+0-9.eE]+)")


def has_launch(binary):
    if not binary or not os.path.exists(binary):
        return False
    # A build without DDS still parses `launch` but has no agent/coordinator processes to start.
    here = os.path.dirname(binary)
    if not all(os.path.exists(os.path.join(here, b)) for b in ("tessera-agent", "tessera-coordinator")):
        return False
    p = subprocess.run([binary, "launch", "--help"], capture_output=True, text=True)
    return p.returncode == 0 and "launch" in p.stdout


def chordal_copy(ctx, name, path):
    out = os.path.join(ctx.work, f"{name}.chordal.g2o")
    if not os.path.exists(out):
        cmd = [ctx.bin, "solve", path, "--algorithm", "irbcd", "--agents", "1", "--partition", "sequential",
               "--max-rounds", "0", "--out", out]
        ctx.log(cmd)
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return out


def run_launch(ctx, launch_bin, path, preset, alg, max_rounds, timeout):
    js = os.path.join(ctx.work, f"launch_{os.path.basename(path)}_{preset}_{alg}.json")
    cmd = [launch_bin, "launch", path, "--agents", "5", "--algorithm", alg, "--partition", preset,
           "--grad-tol", "0.01", "--max-rounds", str(max_rounds), "--json", js, "--timeout", str(timeout)]
    # The solver alone (launch certifies by default, which tightens the gradient tolerance).
    if "--no-certify" in subprocess.run([launch_bin, "launch", "--help"], capture_output=True, text=True).stdout:
        cmd.append("--no-certify")
    ctx.log(cmd)
    t0 = time.monotonic()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1)
    trace, tail, last = [], [], 0.0
    for line in p.stdout:
        tail = (tail + [line])[-30:]
        m = ROUND_RE.match(line)
        if m:
            trace.append({"round": float(m.group(1)), "cost": float(m.group(2)), "grad_norm": float(m.group(3)),
                          "elapsed_s": time.monotonic() - t0})
            if time.monotonic() - last > 10:
                last = time.monotonic()
                bc.progress(f"  ... round {m.group(1)}, grad norm {m.group(3)}")
    p.wait()
    if p.returncode != 0:
        raise RuntimeError("tessera launch failed:\n" + "".join(tail))
    with open(js) as f:
        s = json.load(f)
    rounds = max(1, s["rounds"])
    return {"rounds": s["rounds"], "cost": s["cost"], "grad_norm": s["grad_norm"],
            # The coordinator's round timing (status to status) when it has one; solve_ms / rounds
            # would also spread the fixed costs (hand-off, initialisation, rounding) over the rounds.
            "ms_per_round": s.get("ms_per_round") or s["solve_ms"] / rounds, "partition_ms": s.get("partition_ms"),
            "bytes_per_agent": sum(s["bytes_sent"]) / len(s["bytes_sent"]), "cut_edges": s.get("cut_edges"),
            "wall_s": time.monotonic() - t0}, trace


def run_inprocess(ctx, path, preset, alg, max_rounds):
    s, tr, _, wall = bc.run_tessera(ctx, ["solve", path, "--algorithm", alg, "--agents", "5", "--partition", preset,
                                          "--init", "file", "--grad-tol", "0.01", "--max-rounds", str(max_rounds)])
    return {"rounds": s["rounds"], "cost": s["cost"], "grad_norm": s["grad_norm"],
            "ms_per_round": s["ms_per_round"], "partition_ms": None,
            "bytes_per_agent": s["bytes_exchanged"] / s["agents"], "cut_edges": s["cut_edges"],
            "wall_s": wall}, tr


def partition_figures(ctx, path, preset):
    cmd = [ctx.bin, "partition", path, "--parts", "5", "--preset", preset, "--json", "-"]
    ctx.log(cmd)
    p = subprocess.run(cmd, capture_output=True, text=True, check=True)
    return json.loads(p.stdout)


def run(ctx, launch_bin=None):
    res = bc.Result("4. Complete system (paper Table II)")
    dds = has_launch(launch_bin)
    engine = (f"real agent processes over DDS (`tessera launch`, {os.path.relpath(launch_bin, bc.ROOT)})" if dds
              else "the in-process engine (`tessera solve`; no `tessera launch` in the given binary)")
    max_rounds = 1000 if ctx.quick else 3000
    names = ["parking-garage"] if ctx.quick else ["sphere2500", "parking-garage", "manhattan3500", "city10000"]
    graphs = [(n, ctx.dataset(n), n) for n in names] + [(f"grid3d-{ctx.grid_poses()}", ctx.grid(), None)]
    rows, table, traces = [], [], {}
    for label, path, name in graphs:
        fstar, fsrc = ctx.fstar(name if name else path)
        init = chordal_copy(ctx, label, path)
        for preset, alg in CONFIGS:
            bc.progress(f"complete system: {preset}+{alg} on {label} ({'DDS' if dds else 'in-process'}, "
                        f"max {max_rounds} rounds)")
            part = partition_figures(ctx, init, preset)
            if dds:
                try:
                    r, tr = run_launch(ctx, launch_bin, init, preset, alg, max_rounds, 900)
                    how = "dds"
                except RuntimeError as e:
                    print(f"launch failed, falling back to the in-process engine:\n{e}", file=sys.stderr)
                    r, tr = run_inprocess(ctx, init, preset, alg, max_rounds)
                    how = "in-process (launch failed)"
            else:
                r, tr = run_inprocess(ctx, init, preset, alg, max_rounds)
                how = "in-process"
            traces[(label, preset)] = tr
            gap = (r["cost"] - fstar) / fstar
            row = {"graph": label, "config": f"{preset}+{alg}", "engine": how, "rounds": r["rounds"],
                   "final_cost": r["cost"], "f_star": fstar, "f_star_source": fsrc, "rel_gap": gap,
                   "final_grad_norm": r["grad_norm"], "ms_per_round_per_agent": r["ms_per_round"],
                   "avg_cvolume": part["cvolume"], "cut_edges": part["cut_edges"],
                   "partition_ms": r["partition_ms"] if r["partition_ms"] is not None else part["time_ms"],
                   "bytes_sent_per_agent": r["bytes_per_agent"], "wall_s": r["wall_s"]}
            rows.append(row)
            table.append([label, row["config"], how, f"{r['cost']:.10g}", f"{fstar:.10g}", f"{gap:.1e}",
                          f"{r['ms_per_round']:.2f}", r["rounds"], f"{part['cvolume']:.4f}",
                          f"{row['partition_ms']:.1f}", f"{r['bytes_per_agent'] / 1e6:.2f}"])
    md = bc.print_table("Complete system, N = 5 agents", ["graph", "config", "engine", "final cost", "f*",
                                                          "rel gap", "ms/round/agent", "rounds", "avg Cvolume",
                                                          "partition ms", "MB sent/agent"], table)
    # The claim to check: highest+IRBCD at or below sequential+RBCD in rounds, time per round and Cvolume,
    # and within 1e-5 of f*.
    checks = []
    for label, _, _ in graphs:
        seq = next(r for r in rows if r["graph"] == label and r["config"].startswith("sequential"))
        hi = next(r for r in rows if r["graph"] == label and r["config"].startswith("highest"))
        bad = []
        for k in ("rounds", "ms_per_round_per_agent", "avg_cvolume"):
            if hi[k] > seq[k]:
                why = ""
                if k == "ms_per_round_per_agent":
                    why = (f" ({hi[k]:.2f} vs {seq[k]:.2f} ms: an IRBCD round has more work and message phases -- "
                           f"every agent forms the extrapolated point P^k (one projection per pose, its own and its "
                           f"neighbours' mirrored public poses), updates its momentum V (another projection per "
                           f"pose), and a restart redoes the update (docs/irbcd.md, section 2) -- but it needs "
                           f"{hi['rounds']} rounds instead of {seq['rounds']}, so the whole solve takes "
                           f"{hi[k] * hi['rounds'] / 1000:.2f} s instead of {seq[k] * seq['rounds'] / 1000:.2f} s)")
                bad.append(k + why)
        if abs(hi["rel_gap"]) > 1e-5:
            tr = traces[(label, "highest")]
            g0 = tr[0]["grad_norm"] if tr else float("nan")
            bad.append(f"rel gap {hi['rel_gap']:.1e} > 1e-5: the run stopped, as asked, at grad norm "
                       f"{hi['final_grad_norm']:.3g} (from {g0:.3g} at round 0; see the figure); the absolute "
                       f"tolerance 0.01 is loose for this graph's small f* = {hi['f_star']:.4g}")
        checks.append(f"- {label}: " + ("highest+IRBCD at or below sequential+RBCD in rounds, ms/round and "
                                        "Cvolume, within 1e-5 of f*" if not bad else "NOT met: " + "; ".join(bad)))
    print("\n".join(checks))
    res.add(f"N = 5 agents, run as {engine}. Both configurations start from the same chordal initialisation "
            f"(VERTEX poses of a copy written by `tessera solve --max-rounds 0 --out`), stop at grad norm 0.01 or "
            f"{max_rounds} rounds. ms/round/agent = solve time / rounds (agents run concurrently, so this is also "
            f"each agent's time per round); Cvolume from `tessera partition` with the same preset; bytes = mean "
            f"over agents. f* of the public graphs from `reference/optima.csv`; of the generated grid from the "
            f"centralized solver in this run. {bc.GRID_NOTE} (P = {ctx.grid_poses()}); rim has no measurements."
            + (" `--quick`: parking-garage and the grid only." if ctx.quick else "") + "\n\n" + md
            + "\n\nChecks (highest+IRBCD vs sequential+RBCD):\n\n" + "\n".join(checks))
    res.add_csv(ctx, "exp4_complete_system.csv", rows)
    res.images.append(plot(ctx, graphs, traces, rows))
    return res


def plot(ctx, graphs, traces, rows):
    plt = bc.pyplot()
    n = len(graphs)
    fig, axes = plt.subplots(2, n, figsize=(5 * n, 8), squeeze=False)
    for k, (label, _, _) in enumerate(graphs):
        fstar = next(r["f_star"] for r in rows if r["graph"] == label)
        for preset, alg in CONFIGS:
            tr = traces[(label, preset)]
            axes[0][k].plot([r["round"] for r in tr], [r["grad_norm"] for r in tr], label=f"{preset}+{alg}")
            xs, ys = bc.gap_series(tr, fstar)
            axes[1][k].plot(xs, ys, label=f"{preset}+{alg}")
        axes[0][k].set_ylabel("gradient norm (cost units, log)")
        axes[1][k].set_ylabel("f - f* (cost units, log)")
        for ax in (axes[0][k], axes[1][k]):
            bc.style_log_axes(ax, "round", f"{label}, N = 5")
    return bc.save_figure(ctx, fig, "exp4_complete_system.png", dpi=90)


def add_args(ap):
    ap.add_argument("--launch-bin", default=os.path.join(bc.ROOT, "build", "bin", "tessera"),
                    help="a tessera built with DDS (has `launch`); otherwise the in-process engine is used")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    bc.add_common_args(ap)
    add_args(ap)
    a = ap.parse_args()
    run(bc.Ctx(a), os.path.abspath(a.launch_bin))


if __name__ == "__main__":
    main()
