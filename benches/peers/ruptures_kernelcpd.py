"""ruptures KernelCPD (linear kernel) on learn_cluster.rs's 1-D signal with 10 true breaks.

Times `fit(signal).predict(...)` with the number of breaks given (`n_bkps=10`, dynamic
programming) and with a penalty (`pen`, PELT), `min_size=2` (ruptures' default).
Usage: ruptures_kernelcpd.py [ROUNDS] [PEN]
"""

import sys

import ruptures as rpt

from data import median_time, steps_1d

rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 5
pen = float(sys.argv[2]) if len(sys.argv) > 2 else 100.0
signal, breaks = steps_1d()
for name, predict in [("pen", {"pen": pen}), ("n_bkps", {"n_bkps": 10})]:
    seconds, found = median_time(lambda: rpt.KernelCPD(kernel="linear", min_size=2).fit(signal).predict(**predict), rounds)
    found = [int(b) for b in found[:-1]]
    print(f"ruptures_kernelcpd_linear {name} median {seconds * 1e3:.2f} ms over {rounds}; "
          f"found {len(found)} breaks, exact {found == breaks}: {found}")
