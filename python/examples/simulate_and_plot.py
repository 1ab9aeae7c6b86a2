"""Simulates the skirt through a walk and plots its hem's height and swing over time, with
the last frame's garment and body from the side.

    python simulate_and_plot.py [OUT.png]      (needs matplotlib; prints the numbers without)
"""

import sys

import numpy as np

import dit_garment as dg

r = dg.simulate(garment="skirt", motion="walk", frames=90, body_vertices=True)
print(r)
# The hem: the template's lowest ring of vertices.
rest_y = r.template[:, 1]
hem = rest_y < rest_y.min() + 0.01
height = r.garment[:, hem, 1].mean(axis=1)
swing = np.linalg.norm(r.garment[:, hem] - r.garment[:, hem].mean(axis=1, keepdims=True), axis=2).max(axis=1)
t = np.arange(len(r)) / r.fps
for k in range(0, len(r), 15):
    print(f"t = {t[k]:4.2f} s: hem height {height[k]:.3f} m, hem radius {swing[k]:.3f} m")

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    sys.exit(0)

fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
a.plot(t, height, label="hem height, m")
a.plot(t, swing, label="hem radius, m")
a.set_xlabel("time, s")
a.legend()
last = len(r) - 1
b.triplot(r.body[last, :, 2], r.body[last, :, 1], r.body_faces, lw=0.1, color="0.7")
b.triplot(r.garment[last, :, 2], r.garment[last, :, 1], r.faces, lw=0.3, color="tab:blue")
b.set_aspect("equal")
b.set_title(f"frame {last}, from the side")
out = sys.argv[1] if len(sys.argv) > 1 else "skirt_walk.png"
fig.savefig(out, dpi=120)
print("wrote", out)
