#!/usr/bin/env python3
"""Message steps to the certified optimum: IRBCD's rounds alone against IRBCD's rounds followed by
the distributed Newton refinement (`--refine newton`, docs/newton-refine.md), in process.

For each graph, `tessera solve G --algorithm irbcd --agents N --certify` (same messages as over DDS)
  rounds    IRBCD to launch's default gradient tolerance (0.01) and its relative gap to f*
  refine    the same rounds, then Newton steps: CG iterations, neighbour exchanges, all-agent sums,
            the relative gap after the rounding
  tighter   IRBCD alone at tighter gradient tolerances (--tols) until its gap is <= --target,
            for the graphs where the default rounds end above it
A message step is one neighbour exchange or one all-agent sum: an IRBCD round is one of each
(the status sum, the selected blocks' poses), a CG iteration too. Counts do not depend on the
machine's load; the seconds printed beside them do (the load is printed). f* is optima.csv's
(the _qnorm row: the reader normalises quaternions). Writes docs/benchmarks/newton_refine.csv.

usage: newton_refine.py [--bin build/bin] [--graphs parking-garage,...] [--agents 5]
                        [--tols 1e-3,1e-4,3e-5,1e-5] [--target 1e-6] [--csv FILE]
(--tols "": no tighter runs; ais2klinik's take tens of minutes)
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402

GRAPHS = ["parking-garage", "ais2klinik", "sphere2500", "torus3D", "city10000", "cubicle"]


def solve(a, graph, fstar, extra):
    with tempfile.TemporaryDirectory() as tmp:
        js = os.path.join(tmp, "s.json")
        cmd = [os.path.join(a.bin, "tessera"), "solve", graph, "--algorithm", "irbcd", "--agents",
               str(a.agents), "--certify", "--reference-cost", repr(fstar), "--json", js] + extra
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        if p.returncode != 0:
            sys.exit(f"failed: {' '.join(cmd)}\n{p.stdout}")
        with open(js) as f:
            return json.load(f)


def load():
    with open("/proc/loadavg") as f:
        return float(f.read().split()[0])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin"))
    ap.add_argument("--shared", default=os.path.join(ROOT, "..", "shared"))
    ap.add_argument("--graphs", default=",".join(GRAPHS))
    ap.add_argument("--agents", type=int, default=5)
    ap.add_argument("--tols", default="1e-3,1e-4,3e-5,1e-5")
    ap.add_argument("--target", type=float, default=1e-6)
    ap.add_argument("--csv", default=os.path.join(ROOT, "docs", "benchmarks", "newton_refine.csv"))
    a = ap.parse_args()
    optima = bc.read_reference(a.shared, "optima.csv", "dataset")
    rows, table = [], []
    for name in a.graphs.split(","):
        graph = os.path.join(a.shared, "datasets", name + ".g2o")
        fstar = float((optima.get(name + "_qnorm") or optima[name])["f_star"])
        l0 = load()
        base = solve(a, graph, fstar, [])
        ref = solve(a, graph, fstar, ["--refine", "newton"])
        tight = None
        if base["rel_gap"] > a.target:
            for t in [x for x in a.tols.split(",") if x]:
                tight = solve(a, graph, fstar, ["--grad-tol", t])
                tight["grad_tol"] = float(t)
                if tight["rel_gap"] <= a.target:
                    break
        row = dict(graph=name, poses=base.get("poses"),
                   rounds=base["rounds"], rounds_gap=base["rel_gap"],
                   refine_rounds=ref["rounds"], cg=ref["refine_cg_iterations"],
                   translation_cg=ref.get("refine_translation_iterations", 0),
                   steps=ref["refine_steps"], exchanges=ref["refine_exchanges"],
                   sums=ref["refine_reductions"], refine_gap=ref["rel_gap"],
                   refine_certified=ref["certified"],
                   message_steps_refine=2 * ref["rounds"] + ref["refine_exchanges"] + ref["refine_reductions"],
                   tight_tol=tight["grad_tol"] if tight else None,
                   tight_rounds=tight["rounds"] if tight else None,
                   tight_gap=tight["rel_gap"] if tight else None,
                   message_steps_rounds=2 * (tight["rounds"] if tight else base["rounds"]),
                   solve_s_rounds=(tight or base)["solve_s"], solve_s_refine=ref["solve_s"],
                   load=max(l0, load()))
        rows.append(row)
        table.append([name, row["rounds"], bc.fmt(row["rounds_gap"], "{:.1e}"),
                      f"{row['cg']} / {row['translation_cg']} / {row['steps']}", row["exchanges"], row["sums"],
                      bc.fmt(row["refine_gap"], "{:.1e}"), row["message_steps_refine"],
                      bc.fmt(row["tight_tol"]), bc.fmt(row["tight_rounds"]), bc.fmt(row["tight_gap"], "{:.1e}"),
                      row["message_steps_rounds"], f"{row['solve_s_refine']:.2f} / {row['solve_s_rounds']:.2f}",
                      f"{row['load']:.1f}"])
        bc.progress(f"{name}: " + ", ".join(f"{k}={v}" for k, v in row.items()))
        bc.write_csv(a.csv, rows, announce=False)  # a long run keeps what it has
    bc.print_table(f"IRBCD rounds vs rounds + Newton refinement, N = {a.agents} (in process, counts load-free)",
                   ["graph", "rounds", "gap", "CG / translation CG / steps", "exchanges", "sums", "gap refined",
                    "msg steps refined", "tighter tol", "rounds", "gap", "msg steps rounds",
                    "solve s refined / rounds", "load"], table)
    bc.write_csv(a.csv, rows)


if __name__ == "__main__":
    main()
