"""The benchmark data of benches/, generated exactly as the Rust benches do."""

import numpy as np

MASK = (1 << 64) - 1


def lcg(seed, count):
    """`count` uniform values in [-1, 1) from the benches' 64-bit LCG."""
    out = np.empty(count)
    state = seed
    for i in range(count):
        state = (state * 6364136223846793005 + 1442695040888963407) & MASK
        out[i] = ((state >> 11) / float(1 << 53) - 0.5) * 2.0
    return out


def standardise(x):
    mean = x.mean(axis=0)
    var = ((x - mean) ** 2).mean(axis=0)
    scale = np.where(var > 1e-24, 1.0 / np.sqrt(np.maximum(var, 1e-300)), 0.0)
    return (x - mean) * scale


def slide(n):
    """learn_cluster.rs `synthetic(n)`: 6-D approach / slide / retract rows, standardised."""
    noise = lcg(0x12345678, 6 * n).reshape(n, 6)
    u = np.arange(n) / n
    pos = np.empty((n, 3))
    force = np.zeros((n, 3))
    a, b = u < 0.3, (u >= 0.3) & (u < 0.8)
    c = ~(a | b)
    pos[a] = np.stack([np.full(a.sum(), 0.5), np.zeros(a.sum()), 0.3 - 0.2 * u[a] / 0.3], axis=1)
    pos[b] = np.stack([0.5 + 0.3 * (u[b] - 0.3), 0.05 * np.sin(10.0 * u[b]), np.full(b.sum(), 0.1)], axis=1)
    force[b] = [1.0, 0.5, 12.0]
    pos[c] = np.stack([np.full(c.sum(), 0.65), np.full(c.sum(), 0.05 * np.sin(8.0)), 0.1 + (u[c] - 0.8)], axis=1)
    x = np.concatenate([pos + 1e-4 * noise[:, :3], force + 0.5 * noise[:, 3:]], axis=1)
    return standardise(x)


def steps_1d():
    """learn_cluster.rs `steps_1d()`: 10 000 samples, 10 breaks every 909 samples."""
    n = 10_000
    breaks = [909 * b for b in range(1, 11)]
    levels = [0.0, 3.0, 1.0, 4.0, 2.0]
    piece = np.searchsorted(breaks, np.arange(n), side="right")
    signal = np.array(levels)[piece % len(levels)] + 0.5 * lcg(42, n)
    return signal.reshape(-1, 1), breaks


def dmp_demo(n=10_000):
    """dmp_fit_rollout.rs `demo(n)`: times and 3-D minimum-jerk-like positions."""
    t = np.arange(n) * 1e-3
    u = t / t[-1]
    s = 10.0 * u**3 - 15.0 * u**4 + 6.0 * u**5
    y = np.stack([0.4 + 0.3 * s, -0.1 + 0.2 * s + 0.03 * np.sin(3.0 * np.pi * u) ** 2, 0.3 - 0.15 * s], axis=1)
    return t, y


def median_time(fn, rounds):
    """Median wall time (s) of `rounds` calls after one warm-up call, and the last result."""
    import time

    result = fn()
    times = []
    for _ in range(rounds):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return float(np.median(times)), result
