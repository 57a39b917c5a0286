"""scikit-learn connectivity Ward on learn_cluster.rs's slide data, ±5 samples (k = 5).

`kneighbors_graph(t, 10)` on the sample index connects each sample to the 10 nearest in time,
the ±5 neighbourhood of `Temporal::Connectivity { k: 5 }`. Times `fit` (3 clusters, full tree)
with the graph built beforehand. Usage: ward_sklearn.py N [ROUNDS]
"""

import sys

import numpy as np
from sklearn.cluster import AgglomerativeClustering
from sklearn.neighbors import kneighbors_graph

from data import median_time, slide

n = int(sys.argv[1])
rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 3
x = slide(n)
t = np.arange(n, dtype=float).reshape(-1, 1)
graph = kneighbors_graph(t, 10, include_self=False)
model = AgglomerativeClustering(n_clusters=3, connectivity=graph, linkage="ward", compute_full_tree=True)
seconds, fitted = median_time(lambda: model.fit(x), rounds)
labels = fitted.labels_
breaks = [i for i in range(1, n) if labels[i] != labels[i - 1]]
print(f"sklearn_ward n={n} median {seconds * 1e3:.2f} ms over {rounds}; label changes {len(breaks)}: {breaks[:8]}")
