"""Reads a synth dataset into a PyTorch DataLoader and fits a toy model for a few steps: a
per-vertex MLP from a window of body poses to the garment's displacement from its template
(a stand-in for a real model; the point is the data path).

    dit-garment synth --example-spec tiny > tiny.toml
    dit-garment synth --spec tiny.toml --out tiny
    python torch_dataloader.py tiny
"""

import sys

import torch
from torch.utils.data import DataLoader

from dit_garment.torch import SequenceDataset

folder = sys.argv[1] if len(sys.argv) > 1 else "tiny"
window = 4
data = SequenceDataset(folder, split="train", window=window)
print(f"{len(data)} windows of {window} frames from {len(data.sequences)} sequences")
loader = DataLoader(data, batch_size=8, shuffle=True)

first = data[0]
vertices = first["garment"].shape[1]
model = torch.nn.Sequential(
    torch.nn.Linear(window * 72 + 3, 256), torch.nn.SiLU(), torch.nn.Linear(256, vertices * 3)
)
optimizer = torch.optim.Adam(model.parameters(), lr=1e-3)

def batches(steps):
    """`steps` batches, over as many epochs as that takes."""
    while True:
        for batch in loader:
            if steps == 0:
                return
            steps -= 1
            yield batch


for step, batch in enumerate(batches(40)):
    poses = batch["poses"].flatten(1).float()
    root = batch["translation"][:, -1].float()
    garment = batch["garment"][:, -1].float()
    target = (garment - garment.mean(dim=1, keepdim=True)).flatten(1)
    loss = torch.nn.functional.mse_loss(model(torch.cat([poses, root], dim=1)), target)
    optimizer.zero_grad()
    loss.backward()
    optimizer.step()
    if step % 10 == 0 or step == 39:
        print(f"step {step:3}: loss {loss.item():.6f}")
