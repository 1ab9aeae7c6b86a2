#!/usr/bin/env python3
"""Where a recording's cloth over-stretches: the frames whose largest edge stretch passes a
limit, how many edges do, and whether those edges lie where the body presses on the cloth from
two sides (pinched between facing body surfaces, as under an arm swung against the chest).
Written for issue 53's captured stretches, which pass the dataset's default stretch gate (1.5)
rarely even at 12 substeps (docs/SURROGATE_ARMS.md, "Arm a38").

  python3 tools/edge_stretch_report.py [--limit 1.5] RECORDING.mcap ...

Stretch is an edge's length over its length in the recording's template, which is the rest
length the engine measures against (its recorded per-frame maximum is printed beside it as a
check). A vertex counts as pinched when two body vertices within 2 cm of it have normals more
than about 107 degrees apart. Needs the Python package (pip install ./python) and NumPy.
"""
import argparse

import numpy as np

import dit_garment as dg

PINCH_RADIUS_M = 0.02
FACING_COSINE = -0.3


def vertex_normals(vertices, faces):
    normals = np.zeros_like(vertices)
    face_normals = np.cross(vertices[faces[:, 1]] - vertices[faces[:, 0]],
                            vertices[faces[:, 2]] - vertices[faces[:, 0]])
    for corner in range(3):
        np.add.at(normals, faces[:, corner], face_normals)
    return normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)


def report(path, limit):
    rec = dg.read_recording(path)
    faces = rec.faces
    edges = np.unique(np.sort(np.concatenate(
        [faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1), axis=0)
    rest = np.linalg.norm(rec.template[edges[:, 0]] - rec.template[edges[:, 1]], axis=1)
    cloth = rec.garment.astype(np.float64)
    stretch = np.linalg.norm(cloth[:, edges[:, 0]] - cloth[:, edges[:, 1]], axis=2) / rest
    over = stretch > limit
    frames = np.nonzero(over.any(axis=1))[0]
    recorded = max((s["max_edge_stretch"] for s in rec.stats), default=float("nan"))
    print(f"{path}: max stretch {stretch.max():.3f} (recorded {recorded:.3f}), "
          f"99.9th percentile {np.quantile(stretch, 0.999):.3f}; "
          f"{len(frames)} of {len(cloth)} frames over {limit}, "
          f"at most {over.sum(axis=1).max()} of {len(edges)} edges in one")
    if len(frames) == 0:
        return
    body, body_faces = rec.posed_body()
    pinched, distances = 0, []
    for k in frames:
        points = np.asarray(body[k], dtype=np.float64)
        normals = vertex_normals(points, body_faces)
        for v in np.unique(edges[over[k]].ravel()):
            d = np.linalg.norm(points - cloth[k, v], axis=1)
            distances.append(d.min())
            near = normals[d < PINCH_RADIUS_M]
            if len(near) >= 2 and (near @ near.T).min() < FACING_COSINE:
                pinched += 1
    print(f"  their vertices (over frames): {len(distances)}, pinched between facing body "
          f"surfaces: {pinched}, median distance to the body {1e3 * np.median(distances):.1f} mm")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recordings", nargs="+")
    parser.add_argument("--limit", type=float, default=1.5)
    args = parser.parse_args()
    for path in args.recordings:
        report(path, args.limit)


if __name__ == "__main__":
    main()
