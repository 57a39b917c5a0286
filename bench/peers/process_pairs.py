"""The peers' whole work beside `skillc` as a process, on the same CSV files, in paired rounds.

Issue 27's process-level comparison: a user with a demonstration file runs either a Python
script (read the file, fit) or `skillc learn` (read the file, segment, fit every motion, frame
and force, write the learned file). Each round times the peer's work from reading the file to
its result inside one Python process (interpreter start and imports left out, in the peer's
favour) and then the `skillc learn` process's wall time, back to back, so that the host's load
moves both alike; the median of the per-round ratios is printed with its range.

  ward:  pandas.read_csv + scikit-learn AgglomerativeClustering(ward, kneighbors_graph(t, 10))
         on the standardised position and force, against `skillc learn` of the slide template
         with `connectivity: 5` (the same ±5 neighbourhood);
  dmp:   pandas.read_csv + movement_primitives DMP(n_dims=3, n_weights_per_dim=50).imitate on
         the positions, against the same `skillc learn` (which fits three DMPs, and more).

Usage: process_pairs.py SKILLC [ROUNDS] [SIZES...]  (in a venv with numpy, pandas,
scikit-learn, movement_primitives; never needed by the build or the tests)
"""

import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
import pandas as pd
from movement_primitives.dmp import DMP
from sklearn.cluster import AgglomerativeClustering
from sklearn.neighbors import kneighbors_graph

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def write_demo(path, n):
    """A slide-like 1 kHz demonstration like benches/verbs.rs's (approach, 12 N stroke, retreat)."""
    rng = np.random.default_rng(7)
    i = np.arange(n)
    na, nc = min(n * 3 // 10, 5000), min(n // 5, 5000)
    a, c = i < na, i >= n - nc
    b = ~(a | c)
    wave = 0.05 if n <= 100_000 else 0.0
    pos = np.zeros((n, 3))
    force = np.zeros((n, 3))
    ua = i[a] / na
    pos[a] = np.stack([np.full(a.sum(), 0.5), np.zeros(a.sum()), 0.3 - 0.2 * ua], axis=1)
    ub = (i[b] - na) / b.sum()
    pos[b] = np.stack([0.5 + 0.15 * ub, wave * np.sin(5 * ub), np.full(b.sum(), 0.1)], axis=1)
    force[b] = [1.0, 0.5, -12.0]
    uc = (i[c] - (n - nc)) / nc
    pos[c] = np.stack([np.full(c.sum(), 0.65), np.full(c.sum(), wave * np.sin(5)), 0.1 + 0.2 * uc], axis=1)
    pos += 1e-4 * rng.standard_normal((n, 3))
    force += 0.3 * rng.standard_normal((n, 3))
    q = np.tile([0.0, 1.0, 0.0, 0.0], (n, 1))
    data = np.concatenate([(i / 1000.0)[:, None], pos, q, force, np.zeros((n, 3))], axis=1)
    np.savetxt(path, data, delimiter=",", fmt="%.6f", comments="",
               header="t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,mx,my,mz")


def ward(path):
    frame = pd.read_csv(path)
    x = frame[["px", "py", "pz", "fx", "fy", "fz"]].to_numpy()
    x = (x - x.mean(axis=0)) / np.where(x.std(axis=0) > 0, x.std(axis=0), 1.0)
    graph = kneighbors_graph(frame[["t"]].to_numpy(), 10, include_self=False)
    return AgglomerativeClustering(n_clusters=3, linkage="ward", connectivity=graph).fit(x).labels_


def dmp(path):
    frame = pd.read_csv(path)
    t = frame["t"].to_numpy()
    y = frame[["px", "py", "pz"]].to_numpy()
    model = DMP(n_dims=3, execution_time=t[-1] - t[0], dt=t[1] - t[0], n_weights_per_dim=50)
    model.imitate(t - t[0], y)
    return model


def skillc_learn(skillc, template, path, out):
    started = time.perf_counter()
    subprocess.run([skillc, "learn", template, path, "-o", out, "-q"], check=True)
    return time.perf_counter() - started


def main():
    skillc = os.path.abspath(sys.argv[1])
    rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    sizes = [int(s) for s in sys.argv[3:]] or [10_000, 50_000]
    folder = tempfile.mkdtemp(prefix="skillc-process-pairs-")
    template = os.path.join(folder, "slide5.skill")
    with open(os.path.join(ROOT, "stdlib-skills", "slide.skill")) as f:
        text = f.read().replace("connectivity: 10", "connectivity: 5")
    with open(template, "w") as f:
        f.write(text)
    for n in sizes:
        path = os.path.join(folder, f"demo_{n}.csv")
        write_demo(path, n)
        for name, peer in [("ward", ward), ("dmp", dmp)]:
            if name == "dmp" and n != 10_000:
                continue
            peers, ours, ratios = [], [], []
            for _ in range(rounds):
                started = time.perf_counter()
                peer(path)
                p = time.perf_counter() - started
                s = skillc_learn(skillc, template, path, os.path.join(folder, "learned.json"))
                peers.append(p)
                ours.append(s)
                ratios.append(p / s)
            print(f"{name:5} {n:>7} samples: peer {statistics.median(peers) * 1e3:9.1f} ms, "
                  f"skillc learn {statistics.median(ours) * 1e3:8.1f} ms, per-round ratio median "
                  f"{statistics.median(ratios):6.2f} (range {min(ratios):.2f}-{max(ratios):.2f}), "
                  f"ratio of medians {statistics.median(peers) / statistics.median(ours):.2f}",
                  flush=True)


if __name__ == "__main__":
    main()
