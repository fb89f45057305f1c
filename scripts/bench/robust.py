#!/usr/bin/env python3
"""Outlier rejection benchmark: `tessera solve --robust gnc-tls` against the plain solve of the
same file, on graphs with known wrong loop closures (docs/benchmarks/README.md, "Robust").

Per graph, the clean file is solved once (its optimum f*_clean and poses are the reference);
then for each outlier kind and fraction F (of the graph's loop closures) wrong closures are
appended and the robust and plain solves run. Per cell: precision and recall of the rejected
set against the labels, relative gap of the robust cost (over the kept measurements) to
f*_clean, ATE of the estimate against the clean optimum after a rigid alignment, outer steps,
solver iterations, wall time, certified; beside it the plain solve's cost gap and ATE; for the
distributed run also its rounds and message steps (two a round plus the Newton refinements'
exchanges and sums) against the clean distributed run's.

--cluster-probes K gives the centralized robust solve `--gnc-cluster-probes K`; --explain adds,
for group cells, the TLS cost at the robust estimate and at the clean optimum, the groups that
kept members and the true closures cut (is the wrong answer TLS's optimum, or a search failure?);
--compare BASE prints two runs' centralized columns side by side (docs/benchmarks/robust.md,
"Group outliers").

With --clean-all instead: F = 0 on every shared dataset, the robust distributed solve with 5
agents in process (and with --dds over DDS too), against f* of ../shared/reference/optima.csv
(robust_clean.csv; docs/benchmarks/robust.md, "F = 0 on every shared dataset").

Generated 3D grid: `tessera generate --outliers F --outlier-kind K --labels FILE`. Shared
datasets: the outliers are appended here in the same way (random: uniform pose pairs, random
relative pose, the information of a random loop closure of the file; group: groups of 10
closures (a+k, b+k) all measuring one wrong rigid motion of the clean optimum), since the
generator only makes synthetic graphs.
"""
import argparse
import atexit
import csv
import json
import math
import os
import random
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import bench_common  # noqa: E402


def work_dir(args, prefix):
    """A temporary folder for the generated files and summaries, removed when the script ends
    unless --keep-work (then its path is printed, to read the runs' files)."""
    path = tempfile.mkdtemp(prefix=prefix)
    if args.keep_work:
        progress(f"work files kept in {path}")
    else:
        atexit.register(shutil.rmtree, path, ignore_errors=True)
    return path

GROUP = 10
ALL_GRAPHS = ["grid3d", "intel", "CSAIL", "manhattan3500", "sphere2500", "torus3D", "city10000"]


def progress(msg):
    print(f"[{time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)


# ---- SE(d) helpers (poses as (R, t): 2D (theta, [x, y]); 3D (quaternion [w, x, y, z], [x, y, z]))
def qmul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return [w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2]


def qconj(q):
    return [q[0], -q[1], -q[2], -q[3]]


def qrot(q, v):
    return qmul(qmul(q, [0.0] + list(v)), qconj(q))[1:]


def compose(d, a, b):
    if d == 2:
        c, s = math.cos(a[0]), math.sin(a[0])
        return (a[0] + b[0], [a[1][0] + c * b[1][0] - s * b[1][1], a[1][1] + s * b[1][0] + c * b[1][1]])
    t = qrot(a[0], b[1])
    return (qmul(a[0], b[0]), [a[1][k] + t[k] for k in range(3)])


def inverse(d, a):
    if d == 2:
        c, s = math.cos(a[0]), math.sin(a[0])
        return (-a[0], [-(c * a[1][0] + s * a[1][1]), -(-s * a[1][0] + c * a[1][1])])
    qi = qconj(a[0])
    t = qrot(qi, a[1])
    return (qi, [-x for x in t])


def random_rotation(d, rng):
    if d == 2:
        return rng.uniform(-math.pi, math.pi)
    q = [rng.gauss(0, 1) for _ in range(4)]
    n = math.sqrt(sum(x * x for x in q))
    return [x / n for x in q]


# ---- g2o files
def read_edges(path):
    """(d, vertex lines, edge lines as token lists)."""
    vertices, edges, d = [], [], 0
    with open(path) as f:
        for line in f:
            tok = line.split()
            if not tok:
                continue
            if tok[0].startswith("VERTEX"):
                vertices.append(line.rstrip("\n"))
            elif tok[0].startswith("EDGE"):
                d = 2 if tok[0] == "EDGE_SE2" else 3
                edges.append(tok)
    return d, vertices, edges


def rotation_matrix(d, r):
    """Rotation of a pose as a d x d list of rows (2D: angle; 3D: quaternion [w, x, y, z])."""
    if d == 2:
        c, s = math.cos(r), math.sin(r)
        return [[c, -s], [s, c]]
    n = math.sqrt(sum(x * x for x in r))
    w, x, y, z = (v / n for v in r)
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]


def isotropic_weights(d, info):
    """(kappa, tau) of a g2o information upper triangle, as tessera reads it
    (core/io/information_weights.cpp)."""
    info = [float(x) for x in info]
    if d == 2:
        a, b, c = info[0], info[1], info[3]
        return info[5], 2.0 / ((a + c) / (a * c - b * b))

    def trace_inv(k):
        def a(r, c):
            r, c = k + min(r, c), k + max(r, c)
            return info[r * 6 - r * (r - 1) // 2 + (c - r)]
        m00 = a(1, 1) * a(2, 2) - a(1, 2) ** 2
        m11 = a(0, 0) * a(2, 2) - a(0, 2) ** 2
        m22 = a(0, 0) * a(1, 1) - a(0, 1) ** 2
        det = (a(0, 0) * m00 - a(0, 1) * (a(0, 1) * a(2, 2) - a(1, 2) * a(0, 2)) +
               a(0, 2) * (a(0, 1) * a(1, 2) - a(1, 1) * a(0, 2)))
        return (m00 + m11 + m22) / det
    return 3.0 / (2.0 * trace_inv(3)), 3.0 / trace_inv(0)


def residuals(path, poses):
    """(i, j, r^2) of every EDGE line at `poses` (read_tum's): kappa ||R_j - R_i R_ij||_F^2 +
    tau ||t_j - t_i - R_i t_ij||^2, the edge's term of the objective (quaternions normalised)."""
    d, _, edges = read_edges(path)
    rot = [rotation_matrix(d, r) for r, _ in poses]
    out = []
    for e in edges:
        i, j = int(e[1]), int(e[2])
        if d == 2:
            rij, tij, info = rotation_matrix(2, float(e[5])), [float(e[3]), float(e[4])], e[6:12]
        else:
            rij = rotation_matrix(3, [float(e[9]), float(e[6]), float(e[7]), float(e[8])])
            tij, info = [float(x) for x in e[3:6]], e[10:31]
        kappa, tau = isotropic_weights(d, info)
        ri, rj, ti, tj = rot[i], rot[j], poses[i][1], poses[j][1]
        rot_err = sum((rj[a][b] - sum(ri[a][k] * rij[k][b] for k in range(d))) ** 2
                      for a in range(d) for b in range(d))
        tr_err = sum((tj[a] - ti[a] - sum(ri[a][k] * tij[k] for k in range(d))) ** 2 for a in range(d))
        out.append((i, j, kappa * rot_err + tau * tr_err))
    return out


def explain(path, estimate, optimum, labels, rejected, c2):
    """Why a group cell fails: the TLS cost sum min(r^2, c^2) (odometry r^2 in full) at the
    robust estimate and at the clean optimum, split into odometry, true closures and wrong
    closures, and the groups (GROUP consecutive labels) that kept members."""
    wrong, rejected = set(labels), set(rejected)

    def tls(poses):
        parts = {"odometry": 0.0, "true": 0.0, "wrong": 0.0}
        for n, (i, j, r2) in enumerate(residuals(path, poses)):
            key = "odometry" if abs(i - j) == 1 else "wrong" if n in wrong else "true"
            parts[key] += r2 if key == "odometry" else min(r2, c2)
        return parts
    at_est, at_clean = tls(estimate), tls(optimum)
    groups = [labels[k:k + GROUP] for k in range(0, len(labels), GROUP)]
    kept = [g for g in groups if any(n not in rejected for n in g)]
    return {"tls": sum(at_est.values()), "tls_clean": sum(at_clean.values()),
            "tls_parts": at_est, "tls_clean_parts": at_clean,
            "groups_kept": f"{len(kept)}/{len(groups)}",
            "true_cut": len(rejected - wrong)}


def read_tum(path, d):
    """Poses of a TUM file written by tessera (2D: yaw from the quaternion)."""
    poses = []
    with open(path) as f:
        for line in f:
            v = [float(x) for x in line.split()]
            if len(v) < 8:
                continue
            t, (qx, qy, qz, qw) = v[1:4], v[4:8]
            if d == 2:
                poses.append((2 * math.atan2(qz, qw), t[:2]))
            else:
                poses.append(([qw, qx, qy, qz], t))
    return poses


def edge_tokens(d, i, j, rel, info):
    if d == 2:
        return ["EDGE_SE2", str(i), str(j), repr(rel[1][0]), repr(rel[1][1]), repr(rel[0])] + info
    q = rel[0]
    return ["EDGE_SE3:QUAT", str(i), str(j)] + [repr(x) for x in rel[1]] + [repr(q[1]), repr(q[2]), repr(q[3]),
                                                                             repr(q[0])] + info


def inject(clean_path, out_path, labels_path, fraction, kind, seed, optimum):
    """Appends round(F * loop closures) wrong closures to the clean file; writes the labels."""
    d, vertices, edges = read_edges(clean_path)
    rng = random.Random(seed)
    n = len(optimum)
    closures = [e for e in edges if abs(int(e[1]) - int(e[2])) != 1] or edges
    count = int(round(fraction * len(closures)))
    info_at = 6 if d == 2 else 10
    lo = [min(p[1][k] for p in optimum) for k in range(d)]
    size = [max(1.0, max(p[1][k] for p in optimum) - lo[k]) for k in range(d)]

    def random_pose():
        return (random_rotation(d, rng), [lo[k] + size[k] * rng.uniform(0, 1) for k in range(d)])

    added = []
    while len(added) < count:
        info = rng.choice(closures)[info_at:]
        if kind == "random" or n < 2 * GROUP + 2:
            while True:
                a, b = sorted((rng.randrange(n), rng.randrange(n)))
                if b > a + 1:
                    break
            added.append(edge_tokens(d, a, b, random_pose(), info))
            continue
        g = min(GROUP, count - len(added))
        a = rng.randrange(n - 2 * g - 1)
        b = a + g + 1 + rng.randrange(n - 2 * g - a)
        motion = random_pose()
        for k in range(g):
            moved = compose(d, motion, optimum[b + k])
            rel = compose(d, inverse(d, optimum[a + k]), moved)
            added.append(edge_tokens(d, a + k, b + k, rel, info))
    with open(out_path, "w") as f:
        for v in vertices:
            f.write(v + "\n")
        for e in edges + added:
            f.write(" ".join(e) + "\n")
    with open(labels_path, "w") as f:
        json.dump({"outliers": list(range(len(edges), len(edges) + len(added)))}, f)


# ---- alignment (Horn's closed form; 3D eigenvector by Jacobi rotations)
def jacobi_top_eigenvector(a):
    n = len(a)
    a = [row[:] for row in a]
    v = [[1.0 if i == j else 0.0 for j in range(n)] for i in range(n)]
    for _ in range(100):
        off = sum(a[i][j] ** 2 for i in range(n) for j in range(n) if i != j)
        if off < 1e-30:
            break
        for p in range(n):
            for q in range(p + 1, n):
                if abs(a[p][q]) < 1e-300:
                    continue
                theta = (a[q][q] - a[p][p]) / (2 * a[p][q])
                t = (1 if theta >= 0 else -1) / (abs(theta) + math.sqrt(theta * theta + 1))
                c = 1 / math.sqrt(t * t + 1)
                s = t * c
                for k in range(n):
                    akp, akq = a[k][p], a[k][q]
                    a[k][p], a[k][q] = c * akp - s * akq, s * akp + c * akq
                for k in range(n):
                    apk, aqk = a[p][k], a[q][k]
                    a[p][k], a[q][k] = c * apk - s * aqk, s * apk + c * aqk
                for k in range(n):
                    vkp, vkq = v[k][p], v[k][q]
                    v[k][p], v[k][q] = c * vkp - s * vkq, s * vkp + c * vkq
    best = max(range(n), key=lambda i: a[i][i])
    return [v[k][best] for k in range(n)]


def ate(estimate, reference, d):
    """RMS translation error after the rigid motion that best aligns estimate to reference."""
    n = len(reference)
    ps = [p[1] for p in estimate]
    qs = [p[1] for p in reference]
    cp = [sum(p[k] for p in ps) / n for k in range(d)]
    cq = [sum(q[k] for q in qs) / n for k in range(d)]
    x = [[p[k] - cp[k] for k in range(d)] for p in ps]
    y = [[q[k] - cq[k] for k in range(d)] for q in qs]
    if d == 2:
        sxx = sum(a[0] * b[0] + a[1] * b[1] for a, b in zip(x, y))
        sxy = sum(a[0] * b[1] - a[1] * b[0] for a, b in zip(x, y))
        th = math.atan2(sxy, sxx)
        c, s = math.cos(th), math.sin(th)
        err = sum((c * a[0] - s * a[1] - b[0]) ** 2 + (s * a[0] + c * a[1] - b[1]) ** 2 for a, b in zip(x, y))
        return math.sqrt(err / n)
    m = [[sum(a[i] * b[j] for a, b in zip(x, y)) for j in range(3)] for i in range(3)]
    (sxx, sxy, sxz), (syx, syy, syz), (szx, szy, szz) = m
    nmat = [[sxx + syy + szz, syz - szy, szx - sxz, sxy - syx],
            [syz - szy, sxx - syy - szz, sxy + syx, szx + sxz],
            [szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy],
            [sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz]]
    q = jacobi_top_eigenvector(nmat)
    err = 0.0
    for a, b in zip(x, y):
        r = qrot(q, a)
        err += sum((r[k] - b[k]) ** 2 for k in range(3))
    return math.sqrt(err / n)


# ---- runs
def message_steps(rounds, summary):
    """Message steps of a distributed run, each a wait for peers: the JSON's message_steps_total
    (two a round, docs/irbcd.md, two a solve stage (its opening pose exchange and closing status
    round), plus every Newton refinement's neighbour exchanges and all-agent sums, plus a robust
    run's own exchanges: poses, votes, weights, rejected sets, verdicts, gathers, its
    gnc_exchange_steps). Under `--refine auto` a clean run hands over to the
    refinement early, so its rounds alone undercount its work (intel: 1 round, 13 refinement
    steps). A binary without message_steps_total: two a round plus the refinements' steps
    (GNC's own exchanges left out)."""
    if "message_steps_total" in summary:
        return summary["message_steps_total"]
    return (2 * rounds + summary.get("refine_exchanges", 0) + summary.get("refine_reductions", 0) +
            summary.get("gnc_refine_steps", 0))


def solve(tessera, graph, work, tag, extra, timeout, algorithm="centralized"):
    js = os.path.join(work, tag + ".json")
    tum = os.path.join(work, tag + ".tum")
    cmd = [tessera, "solve", graph, "--algorithm", algorithm, "--json", js, "--out", tum] + extra
    if algorithm != "centralized":
        # N = 5 agents on contiguous id ranges (the robots of the multi-robot convention)
        cmd += ["--agents", "5", "--partition", "sequential", "--certify"]
    t0 = time.monotonic()
    try:
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, None, time.monotonic() - t0, f"timed out after {timeout:.0f} s"
    wall = time.monotonic() - t0
    if p.returncode != 0:
        return None, None, wall, p.stdout.strip().splitlines()[-1] if p.stdout.strip() else str(p.returncode)
    with open(js) as f:
        return json.load(f), tum, wall, ""


def clean_graph(args, work, name):
    if name == "grid3d":
        path = os.path.join(work, "grid3d_clean.g2o")
        subprocess.run([args.bin, "generate", "--kind", "grid3d", "--poses", str(args.grid_poses), "--robots",
                        "5", "--seed", "1", "--out", path], check=True, stdout=subprocess.DEVNULL)
        return path
    return os.path.join(args.shared, "datasets", name + ".g2o")


def dirty_graph(args, work, name, clean, kind, fraction, optimum):
    tag = f"{name}_{kind}_{fraction}"
    path, labels = os.path.join(work, tag + ".g2o"), os.path.join(work, tag + ".labels.json")
    if name == "grid3d":
        subprocess.run([args.bin, "generate", "--kind", "grid3d", "--poses", str(args.grid_poses), "--robots", "5",
                        "--seed", "1", "--outliers", str(fraction), "--outlier-kind", kind, "--labels", labels,
                        "--out", path], check=True, stdout=subprocess.DEVNULL)
    else:
        inject(clean, path, labels, fraction, kind, args.seed, optimum)
    with open(labels) as f:
        return path, json.load(f)["outliers"]


def plot(csv_path, png_path):
    """Four panels against F: recall and precision of the rejected set, |relative gap| to
    f*_clean, ATE of the robust and of the plain estimate (centralized), and the distributed
    run's rounds over the clean run's (solid random, dashed group)."""
    plt = bench_common.pyplot()
    with open(csv_path) as f:
        rows = list(csv.DictReader(f))
    graphs = []
    for r in rows:
        if r["graph"] not in graphs:
            graphs.append(r["graph"])
    fig, ax = plt.subplots(1, 4, figsize=(20, 4.2))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]

    def series(g, kind, key):
        pts = []
        for r in rows:
            if r["graph"] == g and (r["kind"] == kind or float(r["F"]) == 0) and r.get(key, "") != "":
                pts.append((float(r["F"]), float(r[key])))
        return sorted(pts)

    for n, g in enumerate(graphs):
        c = colours[n % len(colours)]
        for kind, style in (("random", "-"), ("group", "--")):
            label = f"{g} {kind}"
            pts = series(g, kind, "recall")
            if pts:
                ax[0].plot(*zip(*pts), style, color=c, marker="o", label=label)
            pts = series(g, kind, "precision")
            if pts:
                ax[0].plot(*zip(*pts), style, color=c, marker="x", alpha=0.5)
            pts = [(x, max(abs(y), 1e-16)) for x, y in series(g, kind, "gap")]
            if pts:
                ax[1].semilogy(*zip(*pts), style, color=c, marker="o", label=label)
            pts = [(x, max(y, 1e-9)) for x, y in series(g, kind, "ate_m")]
            if pts:
                ax[2].semilogy(*zip(*pts), style, color=c, marker="o", label=label + " robust")
            pts = [(x, max(y, 1e-9)) for x, y in series(g, kind, "plain_ate_m")]
            if pts:
                ax[2].semilogy(*zip(*pts), style, color=c, marker="s", alpha=0.35)
            pts = series(g, kind, "d_round_ratio")
            if pts:
                ax[3].plot(*zip(*pts), style, color=c, marker="o", label=label)
            pts = series(g, kind, "d_msg_ratio")
            if pts:
                ax[3].plot(*zip(*pts), style, color=c, marker="x", alpha=0.5)
    ax[0].set(xlabel="outlier fraction F", ylabel="recall (o) / precision (x)", title="rejected set vs labels")
    ax[1].set(xlabel="outlier fraction F", ylabel="|cost - f*_clean| / f*_clean", title="cost over the kept edges")
    ax[2].set(xlabel="outlier fraction F", ylabel="ATE to the clean optimum [m]",
              title="ATE: robust (o) vs plain (faint squares)")
    ax[3].axhline(5, color="grey", linestyle=":")
    ax[3].set(xlabel="outlier fraction F", ylabel="rounds (o), message steps (x) / clean run's",
              title="distributed (irbcd, 5 agents): all rounds")
    ax[0].set_ylim(-0.02, 1.05)
    ax[1].set_ylim(1e-16, 1e4)
    ax[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(png_path, dpi=90)
    plt.close(fig)
    progress(f"wrote {png_path}")


def table(csv_path):
    """The CSV as a markdown table (the columns that matter, rounded)."""
    with open(csv_path) as f:
        rows = list(csv.DictReader(f))

    def num(v, spec):
        try:
            return spec.format(float(v))
        except ValueError:
            return v or "-"

    head = ("| graph | kind | F | outliers | rejected | precision | recall | gap to f*_clean | ATE m | outer | "
            "certified | wall s | plain gap | plain ATE m | dist. rejected | dist. precision | dist. recall | "
            "dist. gap | dist. ATE m | dist. rounds (clean) | dist. message steps (clean) | dist. probes (kept) | "
            "dist. GNC exchange steps | dist. refine steps | dist. MB | "
            "dist. wall s | dist. certified | load |")
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for r in rows:
        lines.append("| " + " | ".join([
            r["graph"], r["kind"], r["F"], r["outliers"], r["rejected"] or "-", num(r["precision"], "{:.3f}"),
            num(r["recall"], "{:.3f}"), num(r["gap"], "{:.1e}"), num(r["ate_m"], "{:.2g}"), r["outer"] or "-",
            r["certified"] or "-", num(r["wall_s"], "{:.3g}"), num(r["plain_gap"], "{:.3g}"),
            num(r["plain_ate_m"], "{:.2g}"),
            r.get("d_rejected", "") or "-", num(r.get("d_precision", ""), "{:.3f}"),
            num(r.get("d_recall", ""), "{:.3f}"), num(r.get("d_gap", ""), "{:.1e}"),
            num(r.get("d_ate_m", ""), "{:.2g}"),
            (f"{r['d_rounds']} ({r['d_clean_rounds']})" if r.get("d_rounds") else "-"),
            (f"{r['d_msg_steps']} ({r['d_clean_msg_steps']}) = {float(r['d_msg_ratio']):.1f}x"
             if r.get("d_msg_steps") and r.get("d_msg_ratio") else r.get("d_msg_steps") or "-"),
            (f"{r['d_probes']} ({r['d_probes_kept']})" if r.get("d_probes") else "-"),
            r.get("d_gnc_exchange_steps", "") or "-", r.get("d_refine_steps", "") or "-",
            num(str(float(r["d_bytes"]) / 1e6) if r.get("d_bytes") else "", "{:.1f}"),
            num(r.get("d_wall_s", ""), "{:.3g}"), r.get("d_certified", "") or "-", r["load"]]) + " |")
    return "\n".join(lines)


CENTRAL_COLS = ["rejected", "precision", "recall", "gap", "ate_m", "outer", "iterations", "wall_s", "certified"]
PLAIN_COLS = ["plain_gap", "plain_ate_m", "plain_wall_s"]


def merge(into_csv, from_csv):
    """Merges the cells of from_csv (a run with some of the solves switched off) into into_csv by
    (graph, kind, F, scheme): each solve that ran in from_csv (centralized robust, plain,
    distributed) replaces that solve's columns of the matching row, the others stay; a cell
    not in into_csv is added (rows sorted by graph, kind, F). The load column keeps one figure per side, "centralized /
    distributed"; a note starting with "distributed" belongs to the distributed side."""
    with open(into_csv) as f:
        reader = csv.DictReader(f)
        fields = reader.fieldnames
        rows = list(reader)
    with open(from_csv) as f:
        reader = csv.DictReader(f)
        fields += [c for c in reader.fieldnames if c not in fields]  # columns added since
        incoming = list(reader)

    def key(r):
        return (r["graph"], r["kind"], float(r["F"]), r.get("scheme", ""))

    def notes(r):
        parts = [n.strip() for n in (r.get("note") or "").split(";") if n.strip()]
        dist = [n for n in parts if n.startswith("distributed")]
        return [n for n in parts if n not in dist], dist

    dist_cols = [c for c in fields if c.startswith("d_")]
    for new in incoming:
        new_central, new_dist = notes(new)
        ran_dist = any(new.get(c) for c in dist_cols) or bool(new_dist)
        ran_central = any(new.get(c) for c in CENTRAL_COLS) or bool(new_central)
        ran_plain = any(new.get(c) for c in PLAIN_COLS)
        old = next((r for r in rows if key(r) == key(new)), None)
        if old is None:
            # after the graph's last row, so a graph's cells stay together
            at = max((i + 1 for i, r in enumerate(rows) if r["graph"] == new["graph"]), default=len(rows))
            rows.insert(at, {c: new.get(c, "") for c in fields})
            continue
        loads = [x.strip() for x in (old.get("load") or "").split(" / ")]
        central_load, dist_load = loads[0], loads[-1]
        old_central, old_dist = notes(old)
        for cols, ran in ((CENTRAL_COLS, ran_central), (PLAIN_COLS, ran_plain), (dist_cols, ran_dist)):
            if ran:
                for c in cols:
                    old[c] = new.get(c, "")
        if ran_central or ran_plain:
            central_load, old_central = new["load"], new_central
        if ran_dist:
            dist_load, old_dist = new["load"], new_dist
        old["load"] = central_load if central_load == dist_load else f"{central_load} / {dist_load}"
        old["note"] = "; ".join(old_central + old_dist)
    # Each graph's cells together, kinds in order of first appearance, F ascending.
    graphs, kinds = {}, {}
    for r in rows:
        graphs.setdefault(r["graph"], len(graphs))
        kinds.setdefault(r["kind"], len(kinds))
    rows.sort(key=lambda r: (graphs[r["graph"]], kinds[r["kind"]], float(r["F"])))
    with open(into_csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for r in rows:
            w.writerow({c: r.get(c, "") for c in fields})
    progress(f"merged {len(incoming)} rows of {from_csv} into {into_csv}")


def compare_table(base_csv, new_csv):
    """Centralized columns of two runs side by side, by (graph, kind, F): `base_csv` (e.g.
    robust_group.csv, gnc-tls alone) and `new_csv` (e.g. robust_cluster.csv, with
    --cluster-probes): rejected / precision / recall / gap / certified of each and, where --explain
    wrote them, the TLS cost at the estimate (at the clean optimum), the groups that kept members
    and the true closures cut; the new run's probes (kept) and wall."""
    with open(base_csv) as f:
        base = {(r["graph"], r["kind"], float(r["F"])): r for r in csv.DictReader(f)}
    with open(new_csv) as f:
        rows = list(csv.DictReader(f))

    def num(v, spec):
        try:
            return spec.format(float(v))
        except (TypeError, ValueError):
            return v or "-"
    head = ("| graph | kind | F | outliers | rejected | precision | recall | gap | certified | TLS (clean) | "
            "groups kept | true cut | probes: rejected | precision | recall | gap | certified | probes (kept) | "
            "wall s | TLS (clean) | groups kept | true cut |")
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for r in rows:
        b = base.get((r["graph"], r["kind"], float(r["F"])), {})
        lines.append("| " + " | ".join([
            r["graph"], r["kind"], r["F"], r["outliers"], b.get("rejected") or "-",
            num(b.get("precision"), "{:.3f}"), num(b.get("recall"), "{:.3f}"), num(b.get("gap"), "{:.1e}"),
            b.get("certified") or "-", (f"{b['tls']} ({b['tls_clean']})" if b.get("tls") else "-"),
            b.get("groups_kept") or "-", b.get("true_cut") or "-", r["rejected"] or "-", num(r["precision"], "{:.3f}"),
            num(r["recall"], "{:.3f}"), num(r["gap"], "{:.1e}"), r["certified"] or "-",
            f"{r.get('probes') or 0} ({r.get('probes_kept') or 0})", num(r["wall_s"], "{:.3g}"),
            (f"{r['tls']} ({r['tls_clean']})" if r.get("tls") else "-"), r.get("groups_kept") or "-",
            r.get("true_cut") or "-"]) + " |")
    return "\n".join(lines)


def optima(shared):
    """f* of every shared dataset (reference/optima.csv); for the 3D files the `_qnorm` row (the
    same graph with unit quaternions, which is what tessera solves: reference/README.md)."""
    with open(os.path.join(shared, "reference", "optima.csv")) as f:
        rows = {r["dataset"]: float(r["f_star"]) for r in csv.DictReader(f)}
    return {k: rows.get(k + "_qnorm", v) for k, v in rows.items() if not k.endswith("_qnorm")}


def clean_all(args, out_csv):
    """F = 0 on every shared dataset: the robust distributed solve (5 agents) must reject nothing
    and end at f* (optima.csv), certified. In process (`tessera solve --algorithm irbcd`), and with
    --dds also over DDS (`tessera launch`, one process per agent)."""
    fstar = optima(args.shared)
    names = sorted(os.path.splitext(n)[0] for n in os.listdir(os.path.join(args.shared, "datasets"))
                   if n.endswith(".g2o"))
    if args.graphs != ",".join(ALL_GRAPHS):
        names = [n for n in names if n in args.graphs.split(",")]
    fields = ["graph", "engine", "poses", "edges", "rejected", "cost", "f_star", "gap", "certified", "outer",
              "rounds", "wall_s", "load", "extra", "note"]
    if not (args.append and os.path.exists(out_csv)):
        with open(out_csv, "w", newline="") as f:
            csv.writer(f).writerow(fields)
    work = work_dir(args, "tessera-robust-clean-")
    engines = (["in process"] if not args.dds_only else []) + (["dds"] if args.dds or args.dds_only else [])
    for name in names:
        graph = os.path.join(args.shared, "datasets", name + ".g2o")
        for engine in engines:
            js = os.path.join(work, f"{name}_{engine.replace(' ', '_')}.json")
            if engine == "dds":
                cmd = [args.bin, "launch", graph, "--agents", "5", "--robust", "gnc-tls", "--domain",
                       str(args.domain), "--json", js]
            else:
                cmd = [args.bin, "solve", graph, "--algorithm", "irbcd", "--agents", "5", "--robust", "gnc-tls",
                       "--certify", "--json", js]
            cmd += args.clean_extra.split()
            load = open("/proc/loadavg").read().split()[0]
            progress(f"{name} ({engine}): " + " ".join(cmd[1:]))
            t0 = time.monotonic()
            row = {"graph": name, "engine": engine, "f_star": fstar.get(name, ""), "load": load,
                   "extra": args.clean_extra}
            try:
                p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                   timeout=args.timeout)
                rc, out = p.returncode, p.stdout
            except subprocess.TimeoutExpired:
                rc, out = None, f"timed out after {args.timeout:.0f} s"
            row["wall_s"] = round(time.monotonic() - t0, 2)
            if rc != 0:
                row["note"] = out.strip().splitlines()[-1] if out.strip() else str(rc)
            else:
                with open(js) as f:
                    s = json.load(f)
                row.update(poses=s["poses"], edges=s.get("edges", s.get("measurements", "")),
                           rejected=len(s["rejected"]), cost=s["cost"], certified=s["certified"],
                           outer=s["outer_iterations"], rounds=s.get("total_rounds", s.get("rounds", "")))
                if name in fstar:
                    row["gap"] = (s["cost"] - fstar[name]) / fstar[name]
            progress("  " + ", ".join(f"{k}={row.get(k, '')}" for k in fields[1:]))
            with open(out_csv, "a", newline="") as f:
                csv.writer(f).writerow([row.get(k, "") for k in fields])
    print(clean_table(out_csv))


def clean_table(csv_path):
    """The F = 0 table as markdown."""
    with open(csv_path) as f:
        rows = list(csv.DictReader(f))
    head = ("| graph | engine | options | poses | edges | rejected | cost | f* | gap | certified | outer | rounds | "
            "wall s | load |")
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for r in rows:
        gap = f"{float(r['gap']):.1e}" if r["gap"] else "-"
        lines.append("| " + " | ".join([r["graph"], r["engine"], r.get("extra") or "-", r["poses"] or "-", r["edges"] or "-",
                                        r["rejected"] or "-", f"{float(r['cost']):.10g}" if r["cost"] else "-",
                                        r["f_star"] or "-", gap,
                                        r["certified"] or r["note"] or "-", r["outer"] or "-", r["rounds"] or "-",
                                        r["wall_s"], r["load"]]) + " |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin", "tessera"))
    ap.add_argument("--shared", default=bench_common.DEFAULT_SHARED)
    ap.add_argument("--out-dir", default=bench_common.OUT_DIR)
    ap.add_argument("--graphs", default=",".join(ALL_GRAPHS))
    ap.add_argument("--fractions", default="0,0.1,0.25,0.5,0.75")
    ap.add_argument("--kinds", default="random,group")
    ap.add_argument("--grid-poses", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=1800, help="seconds per solve")
    ap.add_argument("--keep-work", action="store_true",
                    help="keep the temporary folder of generated graphs and summaries (removed by default)")
    ap.add_argument("--no-distributed", dest="distributed", action="store_false",
                    help="skip the distributed (irbcd, 5 agents) column")
    ap.add_argument("--csv", default="robust.csv", help="file name in --out-dir (rows are appended per cell)")
    ap.add_argument("--scheme", default="gnc-tls", choices=["gnc-tls", "pcm-gnc"],
                    help="--robust value of the centralized robust solve (the distributed one is gnc-tls)")
    ap.add_argument("--cluster-probes", type=int, default=0,
                    help="--gnc-cluster-probes K for the centralized and the distributed robust solve (scheme "
                         "column: gnc-tls+cluster K)")
    ap.add_argument("--explain", action="store_true",
                    help="group cells: TLS cost at the robust estimates (centralized, distributed: d_ columns) and at the clean optimum, "
                         "groups that kept members (columns tls, tls_clean, groups_kept, true_cut)")
    ap.add_argument("--no-plain", dest="plain", action="store_false",
                    help="skip the plain (non-robust) centralized solve of the contaminated file (slow on "
                         "large graphs)")
    ap.add_argument("--no-centralized", dest="centralized", action="store_false",
                    help="skip the centralized robust solve")
    ap.add_argument("--append", action="store_true",
                    help="add rows to an existing --csv (e.g. the large graphs with fewer fractions)")
    ap.add_argument("--plot-only", action="store_true", help="only redraw the figure from the CSV")
    ap.add_argument("--merge", metavar="CSV",
                    help="instead of running: merge the cells of CSV (a run with --no-distributed, "
                         "--no-centralized or --no-plain) into --csv by (graph, kind, F, scheme), each solve that "
                         "ran replacing its columns; then redraw the figure and print the table")
    ap.add_argument("--compare", metavar="BASE_CSV",
                    help="only print --csv's centralized columns beside BASE_CSV's (a file in --out-dir)")
    ap.add_argument("--clean-all", action="store_true",
                    help="instead: F = 0 on every shared dataset (--graphs narrows them), robust distributed "
                         "solve with 5 agents, CSV robust_clean.csv")
    ap.add_argument("--dds", action="store_true", help="--clean-all: also `tessera launch` (over DDS)")
    ap.add_argument("--dds-only", action="store_true", help="--clean-all: only `tessera launch`")
    ap.add_argument("--domain", type=int, default=70, help="--clean-all --dds: DDS domain id")
    ap.add_argument("--dist-extra", default="",
                    help="more options for the distributed robust solve (e.g. --gnc-pass-refine auto); "
                         "the clean distributed run keeps its own")
    ap.add_argument("--clean-extra", default="", help="--clean-all: more options for every run (e.g. --grad-tol 1e-4)")
    ap.add_argument("--check", action="store_true",
                    help="after the run, hold the distributed cells to the issue's targets and exit 1 naming "
                         "each cell that misses one (random outliers up to F = 0.5: precision and recall >= 0.99, "
                         "certified, and the clean optimum to 1e-6 where the set is exact; at F = 0.25 at most "
                         "5x the clean run's message steps); exit 77 when ../shared is missing")
    args = ap.parse_args()
    if args.check and not os.path.isdir(os.path.join(args.shared, "datasets")) and \
            any(g != "grid3d" for g in args.graphs.split(",")):
        print(f"robust.py --check: {args.shared}/datasets is missing (../shared beside the checkout)",
              file=sys.stderr)
        sys.exit(77)
    os.makedirs(args.out_dir, exist_ok=True)
    if args.clean_all:
        clean_all(args, os.path.join(args.out_dir, "robust_clean.csv"))
        return
    out_csv = os.path.join(args.out_dir, args.csv)
    png = os.path.join(args.out_dir, os.path.splitext(args.csv)[0] + ".png")
    if args.compare:
        print(compare_table(os.path.join(args.out_dir, args.compare), out_csv))
        return
    if args.merge:
        merge(out_csv, args.merge)
    if args.plot_only or args.merge:
        plot(out_csv, png)
        print(table(out_csv))
        return
    fields = ["graph", "kind", "F", "scheme", "outliers", "rejected", "precision", "recall", "gap", "ate_m", "outer",
              "iterations", "wall_s", "certified", "plain_gap", "plain_ate_m", "plain_wall_s",
              "d_rejected", "d_precision", "d_recall", "d_gap", "d_ate_m", "d_outer", "d_rounds", "d_clean_rounds",
              "d_round_ratio", "d_bytes", "d_wall_s", "d_certified", "load", "note",
              "d_probes", "d_probes_kept", "d_refine_steps", "probes", "probes_kept", "tls", "tls_clean",
              "groups_kept", "true_cut", "d_tls", "d_tls_clean", "d_groups_kept", "d_true_cut",
              "d_msg_steps", "d_clean_msg_steps", "d_msg_ratio", "d_gnc_exchange_steps"]
    if args.append and os.path.exists(out_csv):
        with open(out_csv) as f:
            fields = next(csv.reader(f))  # an older CSV: its own columns, new ones left out
    else:
        with open(out_csv, "w", newline="") as f:
            csv.writer(f).writerow(fields)
    scheme = args.scheme + (f"+cluster{args.cluster_probes}" if args.cluster_probes else "")
    cluster_flags = ["--gnc-cluster-probes", str(args.cluster_probes)] if args.cluster_probes else []
    work = work_dir(args, "tessera-robust-")
    for name in args.graphs.split(","):
        clean = clean_graph(args, work, name)
        progress(f"{name}: clean solve")
        ref, ref_tum, _, err = solve(args.bin, clean, work, name + "_clean", [], args.timeout)
        if ref is None:
            progress(f"{name}: clean solve failed: {err}")
            continue
        d = ref["d"]
        optimum = read_tum(ref_tum, d)
        fstar = ref["cost"]
        dref = None
        if args.distributed:
            dref, _, _, _ = solve(args.bin, clean, work, name + "_dclean", [], args.timeout, "irbcd")
        for kind in args.kinds.split(","):
            for fraction in [float(x) for x in args.fractions.split(",")]:
                if fraction == 0 and kind != args.kinds.split(",")[0]:
                    continue  # F = 0 is the same file for every kind
                path, labels = dirty_graph(args, work, name, clean, kind, fraction, optimum)
                tag = f"{name}_{kind}_{fraction}"
                progress(f"{tag}: {len(labels)} outliers")
                load = open("/proc/loadavg").read().split()[0]
                rej = os.path.join(work, tag + ".rejected")
                rob, rob_tum, wall, err = None, None, 0, "not run"
                if args.centralized:
                    rob, rob_tum, wall, err = solve(args.bin, path, work, tag + "_robust",
                                                    ["--robust", args.scheme, "--rejected", rej] + cluster_flags,
                                                    args.timeout)
                plain = None
                if args.plain:
                    plain, plain_tum, plain_wall, _ = solve(args.bin, path, work, tag + "_plain", [], args.timeout)
                row = {"graph": name, "kind": kind, "F": fraction, "scheme": scheme, "outliers": len(labels),
                       "load": load}
                if plain is not None:
                    row.update(plain_gap=(plain["cost"] - fstar) / fstar,
                               plain_ate_m=ate(read_tum(plain_tum, d), optimum, d), plain_wall_s=round(plain_wall, 2))
                if rob is None:
                    if args.centralized:
                        row["note"] = err
                else:
                    rejected = set(rob["rejected"])
                    truth = set(labels)
                    hit = len(rejected & truth)
                    row.update(rejected=len(rejected),
                               precision=hit / len(rejected) if rejected else 1.0,
                               recall=hit / len(truth) if truth else 1.0,
                               gap=(rob["cost"] - fstar) / fstar,
                               ate_m=ate(read_tum(rob_tum, d), optimum, d),
                               outer=rob["outer_iterations"], iterations=rob["total_iterations"],
                               wall_s=round(wall, 2), certified=rob["certified"],
                               probes=rob.get("probes", ""), probes_kept=rob.get("probes_kept", ""))
                    if args.explain and kind == "group" and labels:
                        why = explain(path, read_tum(rob_tum, d), optimum, labels, rob["rejected"],
                                      rob["inlier_threshold_squared"])
                        row.update(tls=round(why["tls"], 1), tls_clean=round(why["tls_clean"], 1),
                                   groups_kept=why["groups_kept"], true_cut=why["true_cut"])
                        progress("  TLS at the estimate " + ", ".join(
                            f"{k} {v:.1f}" for k, v in why["tls_parts"].items()) + "; at the clean optimum " +
                            ", ".join(f"{k} {v:.1f}" for k, v in why["tls_clean_parts"].items()))
                if args.distributed:
                    drob, drob_tum, dwall, derr = solve(args.bin, path, work, tag + "_drobust",
                                                        ["--robust", "gnc-tls"] + cluster_flags +
                                                        args.dist_extra.split(), args.timeout,
                                                        "irbcd")
                    if drob is None:
                        row["note"] = (row.get("note", "") + " distributed: " + derr).strip()
                    else:
                        rejected = set(drob["rejected"])
                        truth = set(labels)
                        hit = len(rejected & truth)
                        row.update(d_rejected=len(rejected),
                                   d_precision=hit / len(rejected) if rejected else 1.0,
                                   d_recall=hit / len(truth) if truth else 1.0,
                                   d_gap=(drob["cost"] - fstar) / fstar,
                                   d_ate_m=ate(read_tum(drob_tum, d), optimum, d),
                                   d_outer=drob["outer_iterations"], d_rounds=drob["total_rounds"],
                                   d_bytes=drob["total_bytes"], d_wall_s=round(dwall, 2),
                                   d_certified=drob["certified"], d_probes=drob.get("probes", ""),
                                   d_probes_kept=drob.get("probes_kept", ""),
                                   # message steps of the final solve's Newton refinement
                                   d_refine_steps=drob.get("refine_exchanges", 0) +
                                   drob.get("refine_reductions", 0))
                        row["d_msg_steps"] = message_steps(drob["total_rounds"], drob)
                        row["d_gnc_exchange_steps"] = drob.get("gnc_exchange_steps", "")
                        if args.explain and kind == "group" and labels:
                            why = explain(path, read_tum(drob_tum, d), optimum, labels, drob["rejected"],
                                          drob["inlier_threshold_squared"])
                            row.update(d_tls=round(why["tls"], 1), d_tls_clean=round(why["tls_clean"], 1),
                                       d_groups_kept=why["groups_kept"], d_true_cut=why["true_cut"])
                        if dref is not None:
                            clean_steps = message_steps(dref["rounds"], dref)
                            row.update(d_clean_rounds=dref["rounds"],
                                       d_round_ratio=drob["total_rounds"] / max(1, dref["rounds"]),
                                       d_clean_msg_steps=clean_steps,
                                       d_msg_ratio=row["d_msg_steps"] / max(1, clean_steps))
                progress("  " + ", ".join(f"{k}={row.get(k, '')}" for k in fields[3:]))
                with open(out_csv, "a", newline="") as f:
                    csv.writer(f).writerow([row.get(k, "") for k in fields])
    progress(f"wrote {out_csv}")
    if args.check:
        misses = check_targets(out_csv)
        for m in misses:
            print("robust.py --check: " + m, file=sys.stderr)
        sys.exit(1 if misses else 0)
    plot(out_csv, png)


def check_targets(csv_path):
    """The distributed cells of csv_path that miss a target of the issue, one line each (empty
    when all hold). Message steps, rejected sets and costs do not depend on the machine's load."""
    with open(csv_path) as f:
        rows = list(csv.DictReader(f))
    misses = []
    for r in rows:
        cell = f"{r['graph']} {r['kind']} F={r['F']}"
        if not r.get("d_rejected"):
            misses.append(f"{cell}: the distributed robust solve did not finish ({r.get('note', '')})")
            continue
        fraction = float(r["F"])
        print(f"robust.py --check: {cell}: precision {float(r['d_precision']):.3f}, recall "
              f"{float(r['d_recall']):.3f}, gap {float(r['d_gap']):.1e}, certified {r['d_certified']}, "
              f"{r['d_msg_steps']} message steps = {float(r['d_msg_ratio'] or 0):.2f}x the clean run's "
              f"{r['d_clean_msg_steps']}", file=sys.stderr)
        if r["kind"] != "random" or fraction > 0.5:
            continue  # group outliers and F = 0.75 are reported, not held to the targets
        precision, recall = float(r["d_precision"]), float(r["d_recall"])
        if precision < 0.99 or recall < 0.99:
            misses.append(f"{cell}: precision {precision:.3f}, recall {recall:.3f} (target >= 0.99)")
        if r["d_certified"] != "True":
            misses.append(f"{cell}: not certified")
        if precision == 1.0 and recall == 1.0 and abs(float(r["d_gap"])) > 1e-6:
            misses.append(f"{cell}: every outlier found but the cost is {float(r['d_gap']):.2e} from f*_clean")
        if fraction == 0.25 and float(r["d_msg_ratio"] or "inf") > 5.0:
            misses.append(f"{cell}: {r['d_msg_steps']} message steps = {float(r['d_msg_ratio']):.2f}x the clean "
                          f"run's {r['d_clean_msg_steps']} (target <= 5x)")
    return misses


if __name__ == "__main__":
    main()
