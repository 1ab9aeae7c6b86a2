"""Reads the training tensors of `dit-garment dataset tensors` (checked against their
checksums, normalized as the trainer sees them) and prints every split's shapes.

    python read_tensors.py TENSORS
"""

import sys

import dit_garment as dg

t = dg.TensorShards(sys.argv[1] if len(sys.argv) > 1 else "tensors")
print(t)
for name, array in t.templates.items():
    print(f"  templates/{name}: {array.shape} {array.dtype}")
for split in t.splits:
    for name, array in t[split].items():
        print(f"  {split}/{name}: {array.shape} {array.dtype}")
