"""Alternates peer and skillc runs in one sitting and prints medians (the figures of benches/README.md).

Each round times every peer once (after a warm-up call) and then runs the matching criterion
benchmarks of skillc (short measurement, their median read from target/criterion); the table
gives the median over the rounds. Run from the repository root with the peers' venv:
    OPENBLAS_NUM_THREADS=1 /tmp/peers-venv/bin/python benches/peers/compare.py [ROUNDS]
"""

import json
import os
import statistics
import subprocess
import sys
import time

import numpy as np
import ruptures as rpt
from movement_primitives.dmp import DMP
from sklearn.cluster import AgglomerativeClustering
from sklearn.neighbors import kneighbors_graph

sys.path.insert(0, os.path.dirname(__file__))
from data import dmp_demo, slide, steps_1d  # noqa: E402

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def timed(fn):
    fn()
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def ward(n):
    x = slide(n)
    graph = kneighbors_graph(np.arange(n, dtype=float).reshape(-1, 1), 10, include_self=False)
    model = AgglomerativeClustering(n_clusters=3, connectivity=graph, linkage="ward", compute_full_tree=True)
    return lambda: model.fit(x)


def kernel_cpd():
    signal, _ = steps_1d()
    return lambda: rpt.KernelCPD(kernel="linear", min_size=2).fit(signal).predict(pen=100.0)


def dmp_fit():
    t, y = dmp_demo()
    dmp = DMP(n_dims=3, execution_time=t[-1], dt=1e-3, n_weights_per_dim=50)
    return lambda: dmp.imitate(t, y)


# (measure, peer, criterion bench target, criterion benchmark id)
CASES = [
    ("Ward ±5, 10k", ward(10_000), "learn_cluster", "cluster_connectivity_ward/k5/10000"),
    ("Ward ±5, 50k", ward(50_000), "learn_cluster", "cluster_connectivity_ward/k5/50000"),
    ("change points 1-D 10k", kernel_cpd(), "learn_cluster", "changepoint_1d_10_breaks_constant/10000"),
    ("DMP fit 3-D 10k, 50 bases", dmp_fit(), "dmp_fit_rollout", "dmp_fit_3d_ridge_50_bases_10000"),
]


def skillc(target, bench_id):
    subprocess.run(
        ["cargo", "bench", "-q", "-p", "skill-runtime", "--bench", target, "--",
         "--warm-up-time", "1", "--measurement-time", "3", "--noplot", f"^{bench_id}$"],
        cwd=ROOT, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )
    # Criterion nests a group's benchmarks in folders and writes a plain function's `/` as `_`.
    path = os.path.join(ROOT, "target", "criterion", *bench_id.split("/"), "new", "estimates.json")
    if not os.path.exists(path):
        path = os.path.join(ROOT, "target", "criterion", bench_id.replace("/", "_"), "new", "estimates.json")
    with open(path) as f:
        return json.load(f)["median"]["point_estimate"] * 1e-9


rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 5
peer_times = {case[0]: [] for case in CASES}
ours = {case[0]: [] for case in CASES}
for r in range(rounds):
    for name, peer, target, bench_id in CASES:
        peer_times[name].append(timed(peer))
        ours[name].append(skillc(target, bench_id))
    print(f"round {r + 1}/{rounds} done", file=sys.stderr)
# A shared host's load moves both figures of a round alike, so the median of the per-round
# ratios is steadier than the ratio of the medians; both are printed.
print(f"| measure | peer (median of {rounds}) | skillc (median of {rounds}) | peer / skillc | median of per-round ratios (range) |")
print("|---|---|---|---|---|")
for name, *_ in CASES:
    p, s = statistics.median(peer_times[name]), statistics.median(ours[name])
    ratios = [x / y for x, y in zip(peer_times[name], ours[name])]
    print(f"| {name} | {p * 1e3:.2f} ms | {s * 1e3:.3f} ms | {p / s:.1f} | "
          f"{statistics.median(ratios):.1f} ({min(ratios):.1f}-{max(ratios):.1f}) |")
