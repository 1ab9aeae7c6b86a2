"""Poses a garment through a motion with the shipped surrogate, simulates the same scene with
the engine, scores the prediction against it with the paper's metrics and writes both
recordings.

    python predict_and_score.py [GARMENT] [MOTION]
"""

import sys
import time

import dit_garment as dg

garment = sys.argv[1] if len(sys.argv) > 1 else "tshirt_oversized"
motion = sys.argv[2] if len(sys.argv) > 2 else "sway"
frames = 90

started = time.perf_counter()
truth = dg.simulate(garment=garment, motion=motion, frames=frames)
simulated_s = time.perf_counter() - started
started = time.perf_counter()
guess = dg.predict(garment=garment, motion=motion, frames=frames, guidance=5.0, seed=0)
predicted_s = time.perf_counter() - started
scores = dg.metrics(truth, guess)
print(f"{garment} through {motion}, {frames} frames")
print(f"  engine {simulated_s:.1f} s, surrogate {predicted_s:.1f} s")
for key in ("E_v", "E_CD_cm", "E_n", "E_c", "E_b", "E_d"):
    print(f"  {key:8} {scores[key]:.4f}")
truth.write("truth.mcap")
guess.write("prediction.mcap")
print("wrote truth.mcap and prediction.mcap (dit-garment view / render read them)")
