#!/usr/bin/env python3
"""The Newton refinement's trial translations: exact solves through the team's interface (the
default, `--refine-translation-interface 2000`) against the block-Jacobi CG
(`--refine-translation-interface 0`), in process, on the paper graphs (docs/newton-refine.md,
"Exact trial translations").

For each graph and mode, `tessera solve G --algorithm irbcd --agents N --certify [extra flags]`
(same messages as over DDS; default `--refine auto`): the rounds, the refinement's steps, Newton CG
iterations, translation CG iterations, exact translation solves and the team's interface poses,
its message steps (exchanges + all-agent sums), the bytes of the whole run, the relative gap to
optima.csv's f* (the _qnorm row where there is one: the reader normalises quaternions) and the
certificate. Counts do not depend on the machine's load; the load is printed per run.

usage: refine_translations.py [--bin build/bin] [--graphs CSAIL,...] [--agents 5] [--csv FILE]
                              [-- extra solve flags, e.g. --refine newton --grad-tol 1]
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import bench_common as bc  # noqa: E402

GRAPHS = ["CSAIL", "intel", "MIT", "parking-garage", "manhattan3500", "kitti_00", "kitti_02",
          "kitti_05", "ais2klinik"]
MODES = [("cg", ["--refine-translation-interface", "0"]), ("exact", [])]


def fstar(shared, name):
    best = None
    with open(os.path.join(shared, "reference", "optima.csv")) as f:
        for r in csv.DictReader(f):
            if r["dataset"] in (name, name + "_qnorm"):
                best = float(r["f_star"]) if best is None or r["dataset"].endswith("_qnorm") else best
    return best


def solve(a, graph, extra):
    with tempfile.TemporaryDirectory() as tmp:
        js = os.path.join(tmp, "s.json")
        cmd = [os.path.join(a.bin, "tessera"), "solve", graph, "--algorithm", "irbcd", "--agents",
               str(a.agents), "--certify", "--json", js] + extra
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        if p.returncode != 0:
            sys.exit(f"failed: {' '.join(cmd)}\n{p.stdout}")
        with open(js) as f:
            return json.load(f)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin"))
    ap.add_argument("--shared", default=os.path.join(ROOT, "..", "shared"))
    ap.add_argument("--graphs", default=",".join(GRAPHS))
    ap.add_argument("--agents", type=int, default=5)
    ap.add_argument("--csv", default=os.path.join(ROOT, "docs", "benchmarks",
                                                  "refine_translations.csv"))
    ap.add_argument("extra", nargs="*", help="extra tessera solve flags (after --)")
    a = ap.parse_args()
    print(bc.machine())
    rows = []
    for name in [g for g in a.graphs.split(",") if g]:
        graph = os.path.join(a.shared, "datasets", name + ".g2o")
        f = fstar(a.shared, name)
        for mode, flags in MODES:
            load = os.getloadavg()[0]
            j = solve(a, graph, flags + a.extra)
            rows.append(dict(
                graph=name, mode=mode, rounds=j["rounds"], steps=j.get("refine_steps", 0),
                cg=j.get("refine_cg_iterations", 0),
                translation_cg=j.get("refine_translation_iterations", 0),
                translation_solves=j.get("refine_translation_solves", 0),
                interface_poses=j.get("refine_translation_interface_poses", 0),
                message_steps=j.get("refine_exchanges", 0) + j.get("refine_reductions", 0),
                mb=round(j["bytes_exchanged"] / 1e6, 3),
                rel_gap=(j["cost"] - f) / f if f else "", certified=j["certified"],
                load=round(load, 2)))
            r = rows[-1]
            print(f"{name:16s} {mode:6s} rounds {r['rounds']:4d}  steps {r['steps']:3d}  CG {r['cg']:5d}"
                  f"  translation CG {r['translation_cg']:4d}  solves {r['translation_solves']:3d}"
                  f" ({r['interface_poses']} poses)  message steps {r['message_steps']:5d}"
                  f"  MB {r['mb']:.2f}  gap {r['rel_gap']:.1e}  cert {r['certified']}"
                  f"  load {r['load']}", flush=True)
    print(bc.machine())
    with open(a.csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {os.path.relpath(a.csv)}")


if __name__ == "__main__":
    main()
