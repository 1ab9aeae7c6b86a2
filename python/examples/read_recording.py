"""Prints what a recording holds (simulated, predicted or a dataset's).

    python read_recording.py RECORDING.mcap
"""

import sys

import numpy as np

import dit_garment as dg

r = dg.read_recording(sys.argv[1])
print(r)
print(f"  garment {r.garment.shape}, faces {r.faces.shape}, poses {r.poses.shape}, fps {r.fps}")
print(f"  material {r.material}, betas {np.round(r.betas, 3).tolist()}")
if r.stats:
    print(f"  deepest penetration {max(s['max_penetration_m'] for s in r.stats) * 1e3:.1f} mm")
