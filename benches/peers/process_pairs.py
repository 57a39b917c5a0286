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
         the positions, against `skillc learn` of a template with one segment and one 50-basis
         motion (FOLLOW below: a position and an orientation DMP, their reconstruction check,
         and what every learn does: the wrench's frame, sign and bias, the contact phases);
  cpd:   pandas.read_csv + ruptures KernelCPD(linear, min_size=2).predict(n_bkps=10) on the force
         of a demonstration whose force steps through 11 levels (learn_cluster.rs's 1-D signal,
         10 breaks), against `skillc learn` of a template cutting it by CHAMP into 11 segments
         (LEVELS below); both must find the 10 true breaks. `cpd` gives ruptures the count of
         breaks (n_bkps = 10, dynamic programming), `pelt` a penalty (pen = 100, PELT).

Usage: process_pairs.py SKILLC [ROUNDS] [SIZES...]  (in a venv with numpy, pandas,
scikit-learn, movement_primitives, ruptures; never needed by the build or the tests)
"""

import os
import statistics
import subprocess
import sys
import tempfile
import time

import json

import numpy as np
import pandas as pd
import ruptures as rpt
from movement_primitives.dmp import DMP
from sklearn.cluster import AgglomerativeClustering
from sklearn.neighbors import kneighbors_graph

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from data import steps_1d  # noqa: E402

def one_motion_skill(name, segments, basis):
    """A template with the segmentation `segments` and one motion over its first segment."""
    return f"""skill {name} {{
    learn {{
        segments = {segments}
        motion path = dmp(segment 1, basis: {basis})
    }}
    state go {{
        move path from current
        control position all in base
        on motion_done -> done
        on timeout 60 s -> lost
    }}
    terminal done: success
    terminal lost: failure "the motion did not finish"
}}
"""


# The DMP fit alone: one segment, one 50-basis motion.
FOLLOW = one_motion_skill("follow_path", "none", 50)
# Change points of the force alone: CHAMP cutting the demonstration into its 11 levels.
LEVELS = one_motion_skill(
    "levels",
    "changepoint(min_length: 200 ms, models: [constant], particles: 100, features: [force_magnitude]) expect 11",
    10,
)


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


def write_levels(path):
    """A still tool pressing with a force that steps through 11 levels: fz = 5 N + the signal."""
    signal, breaks = steps_1d()
    n = len(signal)
    t = np.arange(n) * 1e-3
    rng = np.random.default_rng(3)
    pos = np.tile([0.5, 0.0, 0.2], (n, 1)) + 1e-5 * rng.standard_normal((n, 3))
    q = np.tile([0.0, 1.0, 0.0, 0.0], (n, 1))
    force = np.zeros((n, 3))
    force[:, 2] = signal[:, 0] + 5.0
    data = np.concatenate([t[:, None], pos, q, force, np.zeros((n, 3))], axis=1)
    np.savetxt(path, data, delimiter=",", fmt="%.6f", comments="",
               header="t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,mx,my,mz")
    return breaks


def levels_signal(path):
    """The force of a levels demonstration, as ruptures takes it."""
    return pd.read_csv(path)[["fz"]].to_numpy()


def cpd(path):
    return rpt.KernelCPD(kernel="linear", min_size=2).fit(levels_signal(path)).predict(n_bkps=10)[:-1]


def cpd_pen(path):
    """The same with a penalty instead of the count (PELT, ruptures_kernelcpd.py's pen = 100)."""
    return rpt.KernelCPD(kernel="linear", min_size=2).fit(levels_signal(path)).predict(pen=100.0)[:-1]


def skillc_learn(skillc, template, path, out):
    started = time.perf_counter()
    subprocess.run([skillc, "learn", template, path, "-o", out, "-q"], check=True)
    return time.perf_counter() - started


def pair(name, n, peer, skillc, template, path, out, rounds):
    """Rounds of the peer then `skillc learn`, back to back; prints the medians and ratios."""
    peers, ours, ratios = [], [], []
    for _ in range(rounds):
        started = time.perf_counter()
        peer(path)
        p = time.perf_counter() - started
        s = skillc_learn(skillc, template, path, out)
        peers.append(p)
        ours.append(s)
        ratios.append(p / s)
    print(f"{name:5} {n:>7} samples: peer {statistics.median(peers) * 1e3:9.1f} ms, "
          f"skillc learn {statistics.median(ours) * 1e3:8.1f} ms, per-round ratio median "
          f"{statistics.median(ratios):6.2f} (range {min(ratios):.2f}-{max(ratios):.2f}), "
          f"ratio of medians {statistics.median(peers) / statistics.median(ours):.2f}",
          flush=True)


def main():
    skillc = os.path.abspath(sys.argv[1])
    rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    sizes = [int(s) for s in sys.argv[3:]] or [10_000, 50_000]
    folder = tempfile.mkdtemp(prefix="skillc-process-pairs-")
    templates = {}
    with open(os.path.join(ROOT, "stdlib-skills", "slide.skill")) as f:
        templates["ward"] = f.read().replace("connectivity: 10", "connectivity: 5")
    templates["dmp"] = FOLLOW
    templates["cpd"] = LEVELS
    for name, text in templates.items():
        with open(os.path.join(folder, f"{name}.skill"), "w") as f:
            f.write(text)
    out = os.path.join(folder, "learned.json")
    for n in sizes:
        path = os.path.join(folder, f"demo_{n}.csv")
        write_demo(path, n)
        for name, peer in [("ward", ward), ("dmp", dmp)]:
            if name == "dmp" and n != 10_000:
                continue
            pair(name, n, peer, skillc, os.path.join(folder, f"{name}.skill"), path, out, rounds)
    levels = os.path.join(folder, "levels.csv")
    breaks = write_levels(levels)
    found = [int(b) for b in cpd(levels)]
    found_pen = [int(b) for b in cpd_pen(levels)]
    skillc_learn(skillc, os.path.join(folder, "cpd.skill"), levels, out)
    with open(out) as f:
        ours = [segment["start_index"] for segment in json.load(f)["segments"][1:]]
    print(f"cpd: the 10 true breaks {breaks}; ruptures found them: {found == breaks} (n_bkps), "
          f"{found_pen == breaks} (pen); skillc found them: {ours == breaks}")
    pair("cpd", 10_000, cpd, skillc, os.path.join(folder, "cpd.skill"), levels, out, rounds)
    pair("pelt", 10_000, cpd_pen, skillc, os.path.join(folder, "cpd.skill"), levels, out, rounds)


if __name__ == "__main__":
    main()
