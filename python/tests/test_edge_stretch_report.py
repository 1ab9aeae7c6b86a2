"""tools/edge_stretch_report.py (docs/SURROGATE_ARMS.md, "Arm a38"): its stretch agrees with the
engine's recorded maximum, and it tells cloth pressed between two facing body surfaces from
cloth near one."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

import dit_garment as dg

TOOL = Path(__file__).resolve().parents[2] / "tools" / "edge_stretch_report.py"


@pytest.fixture(scope="module")
def tool():
    spec = importlib.util.spec_from_file_location("edge_stretch_report", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def square():
    """A 0.5 m square cloth of two triangles, and the same stretched twice along x."""
    template = np.array([[0, 0, 0], [0.5, 0, 0], [0.5, 0.5, 0], [0, 0.5, 0]], dtype=np.float64)
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    stretched = template * np.array([2.0, 1.0, 1.0])
    return template, faces, np.stack([template, stretched])


def plane(z, facing_up):
    """A grid of body vertices over the stretched cloth at height z, its normal up or down."""
    xs, ys = np.meshgrid(np.linspace(0, 1, 11), np.linspace(0, 0.5, 6))
    vertices = np.stack([xs.ravel(), ys.ravel(), np.full(xs.size, z)], axis=1)
    faces = []
    for j in range(5):
        for i in range(10):
            a, b, c, d = j * 11 + i, j * 11 + i + 1, (j + 1) * 11 + i + 1, (j + 1) * 11 + i
            faces += [[a, b, c], [a, c, d]] if facing_up else [[a, c, b], [a, d, c]]
    return vertices, np.array(faces)


def body_of(*planes):
    vertices, faces, offset = [], [], 0
    for v, f in planes:
        vertices.append(v)
        faces.append(f + offset)
        offset += len(v)
    return np.concatenate(vertices), np.concatenate(faces)


def test_cloth_between_two_facing_surfaces_is_pinched_and_beside_one_is_not(tool):
    template, faces, cloth = square()
    sandwich = body_of(plane(-0.01, True), plane(0.01, False))
    below = body_of(plane(-0.01, True))
    for (body, body_faces), pinched in ((sandwich, True), (below, False)):
        frames = np.stack([body, body])
        m = tool.measure(cloth, template, faces, frames, body_faces, limit=1.5)
        assert m["max_stretch"] == pytest.approx(2.0)
        # the two edges along x at 2.0 and the diagonal at sqrt(1.25 / 0.5) = 1.58
        assert m["frames_over"] == 1 and m["max_edges_over"] == 3 and m["edges"] == 5
        assert m["vertices_over"] == 4
        assert m["pinched"] == (4 if pinched else 0)
        assert m["median_distance_m"] == pytest.approx(0.01)


def test_nothing_over_the_limit_reports_no_frames(tool):
    template, faces, cloth = square()
    body, body_faces = body_of(plane(-0.01, True))
    m = tool.measure(cloth, template, faces, np.stack([body, body]), body_faces, limit=2.5)
    assert m["frames_over"] == 0 and m["vertices_over"] == 0 and m["pinched"] == 0


def test_its_stretch_is_the_engines_recorded_maximum(tool):
    rec = dg.simulate(frames=6)
    body, body_faces = rec.posed_body()
    m = tool.measure(rec.garment, rec.template, rec.faces, body, body_faces)
    recorded = max(s["max_edge_stretch"] for s in rec.stats)
    assert m["max_stretch"] == pytest.approx(recorded, rel=1e-5)
