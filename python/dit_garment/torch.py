"""PyTorch datasets over the project's data (imported only when ``torch`` is installed).

    from torch.utils.data import DataLoader
    from dit_garment.torch import SequenceDataset
    loader = DataLoader(SequenceDataset("data/train", window=8), batch_size=4, shuffle=True)
"""

from __future__ import annotations

import os

import numpy as np
import torch
from torch.utils.data import Dataset as _TorchDataset

from . import Dataset

__all__ = ["SequenceDataset"]

_ARRAYS = ("garment", "body", "poses", "betas", "translation", "faces")


class SequenceDataset(_TorchDataset):
    """The sequences of a ``synth`` dataset split as tensors: each item a dict of ``garment``
    ``(frames, V, 3)``, ``body`` ``(frames, B, 3)``, ``poses`` ``(frames, 24, 3)``,
    ``betas``, ``translation`` ``(frames, 3)``, ``material`` ``(3,)`` (k_s, rho, k_b),
    ``faces`` ``(T, 3)`` and ``id``.

    With ``window=W`` an item is a run of ``W`` consecutive frames instead of a whole
    sequence (every start of every sequence is an item), so items batch together when the
    sequences share a template. Sequences are read when first indexed and kept (``cache``).
    """

    def __init__(
        self,
        folder: str | os.PathLike,
        split: str = "train",
        window: int | None = None,
        *,
        cache: bool = True,
        body_model: str | os.PathLike | None = None,
    ):
        if window is not None and window < 1:
            raise ValueError(f"window = {window}: must be at least 1 frame")
        self.sequences = Dataset(folder, split, body_model=body_model)
        self.window = window
        self.cache = cache
        self._read: dict[int, dict] = {}
        frames = [int(s["frames"]) for s in self.sequences.sequences]
        if window is None:
            self.index = [(i, 0) for i in range(len(frames))]
        else:
            self.index = [(i, s) for i, n in enumerate(frames) for s in range(max(0, n - window + 1))]

    def _sequence(self, i: int) -> dict:
        if i in self._read:
            return self._read[i]
        item = self.sequences[i]
        tensors = {name: torch.from_numpy(np.asarray(item[name])) for name in _ARRAYS}
        m = item["material"]
        tensors["material"] = torch.tensor([m["k_s"], m["rho"], m["k_b"]], dtype=torch.float64)
        tensors["id"] = item["id"]
        if self.cache:
            self._read[i] = tensors
        return tensors

    def __len__(self) -> int:
        return len(self.index)

    def __getitem__(self, index: int) -> dict:
        i, start = self.index[index]
        seq = self._sequence(i)
        if self.window is None:
            return dict(seq)
        end = start + self.window
        out = dict(seq)
        for name in ("garment", "body", "poses", "translation"):
            out[name] = seq[name][start:end]
        out["start"] = start
        return out
