#!/usr/bin/env python3
"""NumPy reference of the DiT-Garment forward pass (surrogate/src/model/), written from the
architecture in docs/SURROGATE.md, not from the Rust code: an independent check of the
model, and the way in for PyTorch users to the same weights (the names in model.safetensors are
PyTorch's: a Linear's weight is [out, in]).

  python3 tools/dit_reference.py --check RUN
      recomputes RUN/reference.safetensors's output from RUN/model.safetensors and
      RUN/config.toml; exits 0 when the largest difference is within 1e-4 of the output's
      largest magnitude, 1 otherwise (printing the largest difference).

Needs numpy and safetensors (pip install numpy safetensors); tomllib is Python 3.11+.
"""
import argparse
import math
import sys

import numpy as np
from safetensors.numpy import load_file

try:
    import tomllib
except ImportError:  # Python < 3.11
    tomllib = None

EPS_NORM = 1e-6
EPS_ATTENTION = 1e-8
FREQUENCY_DIM = 256


def read_config(path):
    text = open(path, "rb").read()
    if tomllib is None:
        raise SystemExit("dit_reference.py needs Python 3.11+ (tomllib)")
    config = tomllib.loads(text.decode())
    return config.get("model", config)


class Dit:
    def __init__(self, weights, config):
        self.w = {k: v.astype(np.float64) for k, v in weights.items()}
        self.c = config

    def linear(self, x, name, bias=True):
        y = x @ self.w[name + ".weight"].T
        if bias:
            y = y + self.w[name + ".bias"]
        return y

    @staticmethod
    def norm(x):
        mu = x.mean(-1, keepdims=True)
        var = ((x - mu) ** 2).mean(-1, keepdims=True)
        return (x - mu) / np.sqrt(var + EPS_NORM)

    @staticmethod
    def silu(x):
        return x / (1.0 + np.exp(-x))

    @staticmethod
    def timestep_features(s):
        half = FREQUENCY_DIM // 2
        freqs = np.exp(-math.log(10000.0) * np.arange(half) / half)
        args = (s * 1000.0)[:, None] * freqs[None, :]
        return np.concatenate([np.cos(args), np.sin(args)], axis=1)

    def linear_attention(self, x, name):
        b, n, c = x.shape
        h = self.c["heads"]
        d = c // h
        qkv = self.linear(x, name + ".qkv", bias=False).reshape(b, n, 3, h, d)
        q, k, v = (np.maximum(qkv[:, :, i].transpose(0, 2, 1, 3), 0.0) if i < 2
                   else qkv[:, :, i].transpose(0, 2, 1, 3) for i in range(3))
        kv = np.einsum("bhnd,bhne->bhde", k, v)
        num = q @ kv
        den = q @ k.sum(axis=2)[..., None]
        o = num / (den + EPS_ATTENTION)
        return self.linear(o.transpose(0, 2, 1, 3).reshape(b, n, c), name + ".proj")

    def cross_attention(self, x, cond, name):
        b, n, c = x.shape
        t = cond.shape[1]
        h = self.c["heads"]
        d = c // h
        q = self.linear(x, name + ".q").reshape(b, n, h, d).transpose(0, 2, 1, 3)
        kv = self.linear(cond, name + ".kv").reshape(b, t, 2, h, d)
        k = kv[:, :, 0].transpose(0, 2, 1, 3)
        v = kv[:, :, 1].transpose(0, 2, 1, 3)
        logits = q @ k.transpose(0, 1, 3, 2) / math.sqrt(d)
        logits = logits - logits.max(-1, keepdims=True)
        att = np.exp(logits)
        att = att / att.sum(-1, keepdims=True)
        o = (att @ v).transpose(0, 2, 1, 3).reshape(b, n, c)
        return self.linear(o, name + ".proj")

    def mix_ffn(self, x, name):
        b, n, _ = x.shape
        g = int(round(math.sqrt(n)))
        y = self.silu(self.linear(x, name + ".inverted"))
        ch = y.shape[2]
        grid = y.transpose(0, 2, 1).reshape(b, ch, g, g)
        padded = np.pad(grid, ((0, 0), (0, 0), (1, 1), (1, 1)))
        w = self.w[name + ".depthwise.weight"]  # [2H, 1, 3, 3]
        out = np.zeros_like(grid) + self.w[name + ".depthwise.bias"][None, :, None, None]
        for ky in range(3):
            for kx in range(3):
                out += w[None, :, 0, ky, kx, None, None] * padded[:, :, ky:ky + g, kx:kx + g]
        y = out.reshape(b, ch, n).transpose(0, 2, 1)
        hidden = ch // 2
        y = y[:, :, :hidden] * self.silu(y[:, :, hidden:])
        return self.linear(y, name + ".point")

    def forward(self, noisy, position, mask, s, conditions):
        cfg = self.c
        p = cfg["patch"]
        x = np.concatenate([noisy, position, mask], axis=1).astype(np.float64)
        b, ch, r, _ = x.shape
        g = r // p
        tokens = x.reshape(b, ch, g, p, g, p).transpose(0, 2, 4, 1, 3, 5).reshape(b, g * g, ch * p * p)
        h = self.linear(tokens, "patch_embed")
        t = self.linear(self.silu(self.linear(self.timestep_features(s.astype(np.float64)), "t_embed.fc1")),
                        "t_embed.fc2")
        t6 = self.linear(self.silu(t), "t_block").reshape(b, 6, -1)
        cond = self.linear(self.silu(self.linear(conditions.astype(np.float64), "cond_embed.fc1")),
                           "cond_embed.fc2").reshape(b, cfg["condition_tokens"], -1)
        for i in range(cfg["depth"]):
            name = f"blocks.{i}"
            m = t6 + self.w[name + ".table"][None]
            shift_a, scale_a, gate_a, shift_f, scale_f, gate_f = (m[:, k][:, None, :] for k in range(6))
            h = h + gate_a * self.linear_attention(self.norm(h) * (1 + scale_a) + shift_a, name + ".attn")
            h = h + self.cross_attention(h, cond, name + ".cross")
            h = h + gate_f * self.mix_ffn(self.norm(h) * (1 + scale_f) + shift_f, name + ".ffn")
        m = self.w["final_table"][None] + t[:, None, :]
        h = self.norm(h) * (1 + m[:, 1:2]) + m[:, 0:1]
        out = self.linear(h, "final_linear")
        return out.reshape(b, g, g, 3, p, p).transpose(0, 3, 1, 4, 2, 5).reshape(b, 3, r, r)


def check(run):
    config = read_config(f"{run}/config.toml")
    model = Dit(load_file(f"{run}/model.safetensors"), config)
    ref = load_file(f"{run}/reference.safetensors")
    out = model.forward(ref["noisy"], ref["position"], ref["mask"], ref["timestep"], ref["conditions"])
    expected = ref["output"].astype(np.float64)
    diff = np.abs(out - expected).max()
    scale = np.abs(expected).max()
    relative = diff / max(scale, 1e-30)
    print(f"largest difference {diff:.3e} over largest magnitude {scale:.3e}: relative {relative:.3e}")
    return 0 if relative <= 1e-4 else 1


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", metavar="RUN", required=True, help="a training run folder")
    args = parser.parse_args()
    sys.exit(check(args.check))


if __name__ == "__main__":
    main()
