"""Datasets from Python: a synth folder's sequences, the training tensors, and the PyTorch
dataset over them (where torch is installed)."""

import importlib.util
import json
import os

import numpy as np
import pytest

import dit_garment as dg


def test_dataset_yields_a_dict_of_arrays_per_sequence(tiny_dataset):
    manifest = [json.loads(line) for line in (tiny_dataset / "manifest.jsonl").read_text().splitlines()]
    for split in ("train", "test", "test_garment", "test_motion"):
        ds = dg.Dataset(tiny_dataset, split=split)
        expected = [m["id"] for m in manifest if m["split"] == split and m["status"] == "ok"]
        assert [s["id"] for s in ds.sequences] == expected
        assert len(ds) == len(expected)
    train = dg.Dataset(tiny_dataset)
    assert len(train) >= 1
    item = train[0]
    assert set(item) >= {"garment", "body", "poses", "betas", "translation", "material", "faces", "id"}
    frames, vertices = item["garment"].shape[:2]
    assert item["garment"].shape == (frames, vertices, 3)
    assert item["body"].shape[0] == frames and item["body"].shape[2] == 3
    assert item["poses"].shape == (frames, 24, 3) and item["translation"].shape == (frames, 3)
    assert item["faces"].max() == vertices - 1
    same = dg.read_recording(tiny_dataset / manifest[[m["id"] for m in manifest].index(item["id"])]["file"])
    np.testing.assert_array_equal(item["garment"], same.garment)
    assert [s["id"] for s in train] == [s["id"] for s in train.sequences]
    with pytest.raises(IndexError):
        train[len(train)]


def test_tensor_shards_hold_the_normalized_frames(tiny_tensors):
    t = dg.TensorShards(tiny_tensors)
    manifest = json.loads((tiny_tensors / "manifest.json").read_text())
    assert t.resolution == manifest["resolution"]
    assert t.manifest["condition_dim"] == manifest["condition_dim"]
    assert "train" in t.splits
    train = t["train"]
    n, r = len(train["template_index"]), t.resolution
    assert train["targets"].shape == (n, 3, r, r) and train["targets"].dtype == np.float32
    assert train["conditions"].shape == (n, manifest["condition_dim"])
    assert t.templates["position_maps"].shape == (len(manifest["templates"]), 3, r, r)
    # Normalized with the train statistics: the train targets have about zero mean, unit spread
    # inside the charts.
    inside = t.templates["inside"][train["template_index"], 0] > 0.5
    per_channel = train["targets"].transpose(1, 0, 2, 3)[:, inside]
    assert np.abs(per_channel.mean(axis=1)).max() < 0.1
    assert np.abs(per_channel.std(axis=1) - 1).max() < 0.1
    # The same frames as an independent safetensors reader, normalized by hand.
    if importlib.util.find_spec("safetensors") is None:
        pytest.skip("the public safetensors package is not installed")
    from safetensors.numpy import load_file

    shard = load_file(tiny_tensors / manifest["splits"]["train"]["shards"][0]["file"])
    stats = manifest["normalization"]["targets"]
    mean = np.array(stats["mean"], dtype=np.float32)[None, :, None, None]
    std = np.array(stats["std"], dtype=np.float32)[None, :, None, None]
    first = len(shard["targets"])
    np.testing.assert_allclose(train["targets"][:first], (shard["targets"] - mean) / std, rtol=1e-5, atol=1e-5)


def test_the_torch_dataset_batches_windows(tiny_dataset):
    if importlib.util.find_spec("torch") is None:
        if os.environ.get("DIT_GARMENT_REQUIRE_TORCH"):
            pytest.fail("torch was installed for these tests and cannot be imported")
        pytest.skip("torch is not installed (no CPU wheel could be installed here)")
    import torch
    from torch.utils.data import DataLoader

    from dit_garment.torch import SequenceDataset

    whole = SequenceDataset(tiny_dataset)
    assert len(whole) == len(dg.Dataset(tiny_dataset))
    assert isinstance(whole[0]["garment"], torch.Tensor)
    windows = SequenceDataset(tiny_dataset, window=4)
    frames = whole[0]["garment"].shape[0]
    assert len(windows) == sum(s["frames"] - 3 for s in windows.sequences.sequences)
    batch = next(iter(DataLoader(windows, batch_size=2, shuffle=False)))
    assert batch["garment"].shape[:2] == (2, 4) and batch["poses"].shape == (2, 4, 24, 3)
    torch.testing.assert_close(batch["garment"][1], whole[0]["garment"][1:5])
    assert frames >= 4
