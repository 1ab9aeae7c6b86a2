"""The body model, templates, prediction and metrics."""

import numpy as np
import pytest

import dit_garment as dg


def test_body_is_posed_in_a_batch():
    vertices, faces = dg.body()
    assert vertices.shape[1] == 3 and faces.shape[1] == 3 and faces.max() == len(vertices) - 1
    poses = np.zeros((3, 24, 3))
    poses[1, 16, 2] = -1.0  # the left shoulder down
    batch, _ = dg.body(poses=poses, translation=[0.0, 0.0, 1.0])
    assert batch.shape == (3, len(vertices), 3)
    np.testing.assert_allclose(batch[0], vertices + [0.0, 0.0, 1.0])
    assert not np.allclose(batch[1], batch[0])
    taller, _ = dg.body(betas=[2.0])
    assert not np.allclose(taller, vertices)


def test_template_matches_the_recordings_mesh():
    vertices, faces, uv = dg.template("skirt")
    r = dg.simulate(frames=1)
    np.testing.assert_allclose(vertices, r.template)
    np.testing.assert_array_equal(faces, r.faces)
    assert uv.shape == (len(faces), 3, 2)
    np.testing.assert_allclose(uv, r.uv[r.uv_faces])
    assert "tank_tight" in dg.garment_names()


@pytest.fixture(scope="module")
def pair():
    truth = dg.simulate(frames=12)
    guess = dg.predict(frames=12, model="builtin-single", guidance=0.0)
    return truth, guess


def test_predict_poses_the_same_bodies(pair):
    truth, guess = pair
    assert guess.garment.shape == truth.garment.shape
    assert np.isfinite(guess.garment).all()
    np.testing.assert_allclose(guess.poses, truth.poses)
    assert guess.config["garment"] == "skirt" == guess.meta["garment"]
    assert guess.meta["predicted"]["model"] == "builtin-single"
    assert guess.meta["predicted"]["settings"]["guidance"]["weight"] == 0.0
    assert "predicted" not in truth.meta
    assert guess.stats == []


def test_predict_is_seeded():
    a = dg.predict(frames=3, seed=4)
    b = dg.predict(frames=3, seed=4)
    assert a.to_bytes() == b.to_bytes()


def test_metrics_are_the_compare_commands(pair, cli, tmp_path):
    truth, guess = pair
    scores = dg.metrics(truth, guess)
    assert {"E_v", "E_CD", "E_n", "E_c", "E_b", "E_s", "E_d"} <= set(scores)
    assert scores["frames_scored"] == 3 and scores["E_v"] > 0
    same = dg.metrics(truth, truth)
    assert same["E_v"] == 0.0 and same["E_CD"] == 0.0
    a, b, j = tmp_path / "a.mcap", tmp_path / "b.mcap", tmp_path / "c.json"
    truth.write(a)
    guess.write(b)
    cli("compare", a, b, "--json", j)
    import json

    expected = json.loads(j.read_text())
    for key in ("E_v", "E_CD", "E_n", "E_c", "E_b", "E_s", "E_d"):
        assert scores[key] == pytest.approx(expected[key], rel=1e-12, abs=1e-15), key
