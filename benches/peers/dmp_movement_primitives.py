"""movement_primitives DMP fit on dmp_fit_rollout.rs's data: 3-D, 10 000 samples, 50 bases.

Times `DMP.imitate` (its weights by least squares over the demonstration).
Usage: dmp_movement_primitives.py [ROUNDS]
"""

import sys

from movement_primitives.dmp import DMP

from data import dmp_demo, median_time

rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 5
t, y = dmp_demo()
dmp = DMP(n_dims=3, execution_time=t[-1], dt=1e-3, n_weights_per_dim=50)
seconds, _ = median_time(lambda: dmp.imitate(t, y), rounds)
print(f"movement_primitives_dmp_fit median {seconds * 1e3:.2f} ms over {rounds}")
