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
than about 107 degrees apart. Needs the Python package (pip install ./python) and NumPy;
`measure` works on plain arrays (python/tests/test_edge_stretch_report.py checks it against
the engine's recorded maximum and on cloth between two facing planes and beside one).
"""
import argparse

import numpy as np

PINCH_RADIUS_M = 0.02
FACING_COSINE = -0.3


def vertex_normals(vertices, faces):
    normals = np.zeros_like(vertices)
    face_normals = np.cross(vertices[faces[:, 1]] - vertices[faces[:, 0]],
                            vertices[faces[:, 2]] - vertices[faces[:, 0]])
    for corner in range(3):
        np.add.at(normals, faces[:, corner], face_normals)
    return normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)


def edges_of(faces):
    """The mesh's undirected edges, each once, as (E, 2) vertex indices."""
    pairs = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    return np.unique(np.sort(pairs, axis=1), axis=0)


def measure(cloth, template, faces, body, body_faces, limit=1.5):
    """Edge stretch of `cloth` (frames, V, 3) against `template` (V, 3) over the mesh `faces`,
    and where it passes `limit`, beside `body` (frames, B, 3) with `body_faces`. Returns a dict:
    `max_stretch`, `p999_stretch`, `frames_over`, `max_edges_over` (in one frame), `edges`,
    `vertices_over` ((frame, vertex) pairs of the edges over the limit), `pinched` (those
    between two facing body surfaces) and `median_distance_m` (to the nearest body vertex)."""
    edges = edges_of(faces)
    rest = np.linalg.norm(template[edges[:, 0]] - template[edges[:, 1]], axis=1)
    cloth = np.asarray(cloth, dtype=np.float64)
    stretch = np.linalg.norm(cloth[:, edges[:, 0]] - cloth[:, edges[:, 1]], axis=2) / rest
    over = stretch > limit
    frames = np.nonzero(over.any(axis=1))[0]
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
    return {
        "max_stretch": float(stretch.max()),
        "p999_stretch": float(np.quantile(stretch, 0.999)),
        "frames_over": len(frames),
        "max_edges_over": int(over.sum(axis=1).max()),
        "edges": len(edges),
        "vertices_over": len(distances),
        "pinched": pinched,
        "median_distance_m": float(np.median(distances)) if distances else float("nan"),
    }


def report(path, limit):
    import dit_garment as dg

    rec = dg.read_recording(path)
    body, body_faces = rec.posed_body()
    m = measure(rec.garment, rec.template, rec.faces, body, body_faces, limit)
    recorded = max((s["max_edge_stretch"] for s in rec.stats), default=float("nan"))
    print(f"{path}: max stretch {m['max_stretch']:.3f} (recorded {recorded:.3f}), "
          f"99.9th percentile {m['p999_stretch']:.3f}; "
          f"{m['frames_over']} of {len(rec.garment)} frames over {limit}, "
          f"at most {m['max_edges_over']} of {m['edges']} edges in one")
    if m["frames_over"]:
        print(f"  their vertices (over frames): {m['vertices_over']}, pinched between facing "
              f"body surfaces: {m['pinched']}, median distance to the body "
              f"{1e3 * m['median_distance_m']:.1f} mm")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recordings", nargs="+")
    parser.add_argument("--limit", type=float, default=1.5)
    args = parser.parse_args()
    for path in args.recordings:
        report(path, args.limit)


if __name__ == "__main__":
    main()
