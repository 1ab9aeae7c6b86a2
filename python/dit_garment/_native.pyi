"""Type stubs of the extension module (the work behind ``dit_garment``'s functions)."""

import os
from typing import Any

import numpy as np
import numpy.typing as npt

__version__: str
COMMIT: str

class Recording:
    """A garment recording as NumPy arrays; ``write`` gives back the engine's MCAP bytes."""

    garment: npt.NDArray[np.float32]
    faces: npt.NDArray[np.int64]
    template: npt.NDArray[np.float64]
    uv: npt.NDArray[np.float64]
    uv_faces: npt.NDArray[np.int64]
    body: npt.NDArray[np.float32] | None
    body_faces: npt.NDArray[np.int64] | None
    poses: npt.NDArray[np.float64]
    translation: npt.NDArray[np.float64]
    betas: npt.NDArray[np.float64]
    frame_betas: npt.NDArray[np.float64]
    fps: float
    material: dict[str, float]
    config: dict[str, Any] | None
    meta: dict[str, Any] | None
    stats: list[dict[str, Any]]
    path: str
    @property
    def frames(self) -> int: ...
    def posed_body(
        self, model: str | os.PathLike | None = None
    ) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.int64]]: ...
    def write(self, path: str | os.PathLike) -> None: ...
    def to_bytes(self) -> bytes: ...
    def __len__(self) -> int: ...

class TensorShards:
    """The training tensors of ``dit-garment dataset tensors``, checked and normalized."""

    def __init__(self, folder: str | os.PathLike) -> None: ...
    @property
    def folder(self) -> str: ...
    @property
    def resolution(self) -> int: ...
    @property
    def splits(self) -> list[str]: ...
    @property
    def manifest(self) -> dict[str, Any]: ...
    @property
    def templates(self) -> dict[str, npt.NDArray[np.float32]]: ...
    def split(self, name: str) -> dict[str, np.ndarray]: ...
    def __getitem__(self, name: str) -> dict[str, np.ndarray]: ...

def read_recording(path: str | os.PathLike) -> Recording: ...
def simulate(
    inputs: dict[str, Any], config: str | None = None, solver: dict[str, Any] | None = None
) -> Recording: ...
def predict(
    inputs: dict[str, Any],
    model: str,
    guidance: float,
    seed: int,
    steps: int | None = None,
    body_vertices: bool = False,
) -> Recording: ...
def body(
    betas: list[float],
    poses: npt.NDArray[np.float64],
    translation: npt.NDArray[np.float64],
    model: str | None = None,
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]: ...
def template(
    garment: str, model: str | None = None
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64], npt.NDArray[np.float64]]: ...
def metrics(
    truth: Recording, prediction: Recording, seed: int = 0, model: str | None = None
) -> dict[str, float]: ...
def dataset_sequences(folder: str | os.PathLike, split: str) -> list[dict[str, Any]]: ...
def garment_names() -> list[str]: ...
