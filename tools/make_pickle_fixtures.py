"""Writes the pickle fixtures of motions/tests/fixtures/pickle (run from the repository root).

Each file is a 4D-Dress-style SMPL frame (`global_orient`, `body_pose`, `transl`, `betas` as
NumPy arrays) whose values follow a formula the Rust tests recompute, pickled the ways users'
files are: protocols 2, 4 and 5, float32 and float64, a Fortran-ordered array, and NumPy 1's
module names (`numpy.core`, as files written before NumPy 2 have them). Two hostile files: one
that would run a shell command, one holding a PyTorch tensor.
"""
import pathlib
import pickle

import numpy as np

OUT = pathlib.Path("motions/tests/fixtures/pickle")


def frame(k, dtype=np.float32):
    """Frame k of the fixture motion: value i of each array is (i + 1) * 0.01 * (k + 1)."""
    s = 0.01 * (k + 1)
    return {
        "global_orient": (np.arange(1, 4) * s).astype(dtype),
        "body_pose": (np.arange(1, 70) * s * 0.1).astype(dtype),
        "transl": (np.array([0.1, 0.9, -0.2]) + s).astype(dtype),
        "betas": (np.arange(1, 11) * -0.1).astype(dtype)[None, :],
    }


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    take = OUT / "take" / "SMPL"
    take.mkdir(parents=True, exist_ok=True)
    for k in range(3):
        with open(take / f"mesh-f{11 + k:05d}_smpl.pkl", "wb") as f:
            pickle.dump(frame(k), f, protocol=4)
    with open(OUT / "frame_p5_f64.pkl", "wb") as f:
        pickle.dump(frame(0, np.float64), f, protocol=5)
    p2 = pickle.dumps(frame(0, np.float64), protocol=2)
    (OUT / "frame_p2_f64.pkl").write_bytes(p2)
    (OUT / "frame_p2_numpy1.pkl").write_bytes(p2.replace(b"numpy._core", b"numpy.core"))
    mesh = {
        "vertices": np.asfortranarray(np.arange(12, dtype=np.float64).reshape(4, 3) * 0.5),
        "faces": np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64),
    }
    with open(OUT / "mesh_fortran.pkl", "wb") as f:
        pickle.dump(mesh, f, protocol=4)
    # 4D-Dress's extracted clothes: one mesh dict per label (a unit square, lifted by 1 m).
    square = {
        "vertices": np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=np.float32),
        "faces": np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32),
    }
    lifted = dict(square, vertices=square["vertices"] + np.float32([0, 0, 1]))
    with open(OUT / "cloth_two.pkl", "wb") as f:
        pickle.dump({"upper": square, "lower": lifted}, f, protocol=4)
    # A pickle that would run `echo pwned` if a reader executed it (never unpickled here).
    (OUT / "hostile_system.pkl").write_bytes(b"cos\nsystem\n(S'echo pwned'\ntR.")
    # What torch.save's inner pickle looks like: a tensor rebuilt by a torch function.
    (OUT / "hostile_torch.pkl").write_bytes(
        b"\x80\x02}q\x00X\x06\x00\x00\x00translq\x01ctorch._utils\n_rebuild_tensor_v2\nq\x02"
        b")Rq\x03s."
    )


if __name__ == "__main__":
    main()
