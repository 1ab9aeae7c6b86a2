"""Garment dynamics on SMPL-compatible bodies, from Python.

The projective-dynamics cloth engine (``simulate``), the DiT-Garment surrogate (``predict``),
the paper's metrics (``metrics``), the body model (``body``), garment templates
(``template``) and the datasets (``Dataset``, ``TensorShards``), all running in the
project's Rust crates; long calls release the GIL. Arrays are NumPy arrays with the batch
(frame) dimension first; units are metres, seconds and radians, y up, the body facing +z.

    import dit_garment as dg
    truth = dg.simulate(garment="skirt", motion="walk", frames=60)
    guess = dg.predict(garment="skirt", motion="walk", frames=60)
    print(truth.garment.shape, dg.metrics(truth, guess)["E_v"])

Errors are ``OSError`` (a file that is missing, unreadable or foreign, named),
``ValueError`` (a bad value, named) or ``RuntimeError`` (the solver or the model failed
numerically), with the command line's one-line messages.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Mapping, Sequence

import numpy as np

from . import _native
from ._native import COMMIT, Recording, TensorShards, read_recording

__version__: str = _native.__version__

__all__ = [
    "COMMIT",
    "Dataset",
    "Recording",
    "TensorShards",
    "body",
    "garment_names",
    "metrics",
    "predict",
    "read_recording",
    "simulate",
    "template",
]

PathLike = str | os.PathLike


def _path(value: PathLike | None) -> str | None:
    return None if value is None else os.fspath(value)


def _scene(
    garment: str | PathLike,
    motion: str | PathLike,
    frames: int | None,
    material: Mapping[str, float] | None,
    betas: Sequence[float] | None,
    body_model: PathLike | None,
    blend_frames: int | None,
    settle_frames: int | None,
) -> dict:
    if material is not None and not isinstance(material, Mapping):
        raise ValueError("material: must be a dict with keys k_s, rho, k_b")
    return {
        "garment": os.fspath(garment),
        "motion": os.fspath(motion),
        "frames": frames,
        "material": None if material is None else {str(k): float(v) for k, v in material.items()},
        "betas": None if betas is None else [float(b) for b in np.asarray(betas, dtype=np.float64).ravel()],
        "body_model": _path(body_model),
        "blend_frames": blend_frames,
        "settle_frames": settle_frames,
    }


def simulate(
    garment: str | PathLike = "skirt",
    motion: str | PathLike = "walk",
    frames: int | None = None,
    material: Mapping[str, float] | None = None,
    betas: Sequence[float] | None = None,
    *,
    body_model: PathLike | None = None,
    blend_frames: int | None = None,
    settle_frames: int | None = None,
    config: PathLike | None = None,
    **solver: float | int | bool,
) -> Recording:
    """Simulates a garment on a body through a motion with the engine; the command line's
    ``simulate`` with the same scene writes the same bytes.

    garment: a library design (``garment_names()``), a variant ``NAME~K``/``~wK``/``~dK``,
        ``skirt``, a template OBJ with UVs on the canonical body, or a GarmentCode pattern
        ``.json``.
    motion: a built-in motion (``walk``, ``kick:speed=1.2``, ``random:seed=3``), an
        AMASS-style ``.npz``, a BVH file, or SMPL fits in pickles (a ``.pkl`` or a folder of
        them, such as a 4D-Dress take's ``SMPL/``; read without running them), optionally
        ``:start=S,duration=D``.
    frames: output frames (default: the motion's length, blend-in and settling included).
    material: ``{"k_s": N/m, "rho": kg/m^2, "k_b": N m}``, any subset.
    betas: shape coefficients (default zeros).
    body_model: an SMPL-format ``.npz`` body model (default: the licence-free body).
    config: a scene configuration TOML (``simulate --print-config``); the arguments go over it.
    solver: ``friction``, ``substeps``, ``iterations``, ``acceleration``, ``self_contact``,
        ``self_contact_distance``, ``self_friction``, ``body_vertices`` (record the body's
        vertices).
    """
    scene = _scene(garment, motion, frames, material, betas, body_model, blend_frames, settle_frames)
    return _native.simulate(scene, _path(config), dict(solver))


def predict(
    model: str | PathLike = "builtin",
    garment: str | PathLike = "skirt",
    motion: str | PathLike = "walk",
    frames: int | None = None,
    material: Mapping[str, float] | None = None,
    betas: Sequence[float] | None = None,
    guidance: float = 5.0,
    seed: int = 0,
    *,
    steps: int | None = None,
    body_model: PathLike | None = None,
    blend_frames: int | None = None,
    settle_frames: int | None = None,
    body_vertices: bool = False,
) -> Recording:
    """Poses a garment through a motion with a trained DiT-Garment surrogate (no simulation):
    the same bodies the engine would simulate for the same scene, so ``metrics`` scores the
    two frame by frame.

    model: ``builtin`` (the shipped ensemble, inside this package), ``builtin-single`` (its
        first network), or a run or ensemble folder from ``dit-garment train``.
    guidance: intersection-guidance weight (0 turns it off).
    seed: seed of the initial noise.
    steps: sampler steps (default: the model's own).
    Other arguments as in ``simulate``.
    """
    scene = _scene(garment, motion, frames, material, betas, body_model, blend_frames, settle_frames)
    return _native.predict(
        scene, os.fspath(model), float(guidance), int(seed), steps, bool(body_vertices)
    )


def metrics(
    truth: Recording, prediction: Recording, *, seed: int = 0, body_model: PathLike | None = None
) -> dict:
    """Scores ``prediction`` against ``truth`` (the same template) every 5th frame with the
    paper's metrics, as ``dit-garment compare`` does: ``E_v`` (cm), ``E_CD`` (100 m^2),
    ``E_CD_cm``, ``E_n``, ``E_c`` (% of surface samples inside the body), ``E_c_vertex``,
    ``E_b`` (rad), ``E_s``, ``E_d`` (cm), with ``frames_scored``, ``frames``, ``jitter`` and
    ``jitter_truth`` (cm).
    """
    return _native.metrics(truth, prediction, int(seed), _path(body_model))


def body(
    betas: Sequence[float] | None = None,
    poses: np.ndarray | None = None,
    translation: np.ndarray | None = None,
    model: PathLike | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The body model shaped by ``betas`` and posed: returns ``(vertices, faces)``.

    poses: SMPL axis-angle, ``(24, 3)``, ``(72,)`` or a batch ``(frames, 24, 3)`` /
        ``(frames, 72)`` (default: the canonical A-pose's zeros, one frame).
    translation: ``(3,)`` or ``(frames, 3)`` (default zeros).
    Vertices are float64 ``(V, 3)`` for one pose or ``(frames, V, 3)`` for a batch; faces
    int64 ``(T, 3)``.
    """
    single = poses is None or np.asarray(poses).ndim == 1 or np.asarray(poses).shape == (24, 3)
    p = np.zeros((1, 24, 3)) if poses is None else np.asarray(poses, dtype=np.float64)
    p = np.ascontiguousarray(p.reshape(-1, 24, 3))
    t = np.zeros((p.shape[0], 3)) if translation is None else np.asarray(translation, dtype=np.float64)
    t = np.ascontiguousarray(np.broadcast_to(t.reshape(-1, 3), (p.shape[0], 3)))
    b = [] if betas is None else [float(x) for x in np.asarray(betas, dtype=np.float64).ravel()]
    vertices, faces = _native.body(b, p, t, _path(model))
    return (vertices[0] if single else vertices), faces


def template(
    garment: str | PathLike, model: PathLike | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A garment's template on the canonical body: ``(vertices, faces, uv)`` with vertices
    float64 ``(V, 3)``, faces int64 ``(T, 3)`` and the UV of every triangle corner float64
    ``(T, 3, 2)`` (a UV layout has seams, so UVs are per corner). ``garment`` as in
    ``simulate``: a library design, a variant, ``skirt``, a template OBJ or a pattern file.
    """
    return _native.template(os.fspath(garment), _path(model))


def garment_names() -> list[str]:
    """The built-in skirt and the design library's garments (each also takes variants)."""
    return _native.garment_names()


class Dataset(Sequence):
    """The sequences of one split of a ``dit-garment synth`` dataset folder that passed their
    gates, in manifest order; each item is a dict of NumPy arrays: ``garment`` float32
    ``(frames, V, 3)``, ``body`` float32 ``(frames, B, 3)`` (posed from the recorded
    parameters where the recording carries no body), ``poses`` ``(frames, 24, 3)``,
    ``betas``, ``translation`` ``(frames, 3)``, ``material`` (dict), ``faces`` ``(T, 3)``,
    ``id`` (str), with ``garment_name`` and ``motion``.
    """

    def __init__(self, folder: PathLike, split: str = "train", *, body_model: PathLike | None = None):
        self.folder = os.fspath(folder)
        self.split = split
        self.body_model = _path(body_model)
        self.sequences: list[dict] = _native.dataset_sequences(self.folder, split)

    def __len__(self) -> int:
        return len(self.sequences)

    def __getitem__(self, index: int) -> dict:  # type: ignore[override]
        if not isinstance(index, (int, np.integer)):
            raise TypeError("Dataset indices are integers")
        if index < 0:
            index += len(self)
        if not 0 <= index < len(self):
            raise IndexError(f"sequence {index} of {len(self)}")
        info = self.sequences[index]
        r = read_recording(info["file"])
        if r.body is not None:
            bodies, body_faces = r.body, r.body_faces
        else:
            bodies, body_faces = r.posed_body(self.body_model)
        return {
            "id": info["id"],
            "garment_name": info["garment"],
            "motion": info["motion"],
            "garment": r.garment,
            "body": bodies,
            "body_faces": body_faces,
            "poses": r.poses,
            "betas": r.betas,
            "frame_betas": r.frame_betas,
            "translation": r.translation,
            "material": dict(r.material),
            "faces": r.faces,
        }

    def __iter__(self) -> Iterator[dict]:
        for i in range(len(self)):
            yield self[i]

    def __repr__(self) -> str:
        return f"Dataset({self.folder!r}, split={self.split!r}, {len(self)} sequences)"
