"""Reads a dit-garment recording with the public `mcap` package (pip install mcap numpy) and
prints what it holds; exits non-zero if the file is not a complete garment recording.

usage: python3 tests/readers/read_recording.py seq.mcap

An independent check of the format for the tests (the public `mcap` package only); users read
recordings with the Python package (`dit_garment.read_recording`, python/examples).
"""
import json
import sys

import numpy as np
from mcap.reader import make_reader


def read(path):
    meta, template, frames, stats, poses = None, {}, [], [], []
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages():
            topic = channel.topic
            if channel.message_encoding == "json":
                value = json.loads(message.data)
                if topic == "/sequence/meta":
                    meta = value
                elif topic == "/sim/stats":
                    stats.append(value)
                elif topic == "/body/pose":
                    poses.append(value)
                continue
            dtype = np.dtype(channel.metadata["dtype"]).newbyteorder("<")
            shape = json.loads(channel.metadata["shape"])
            array = np.frombuffer(message.data, dtype=dtype).reshape(shape)
            if topic.startswith("/garment/template/"):
                template[topic.rsplit("/", 1)[1]] = array
            elif topic == "/garment/vertices":
                frames.append(array)
    return meta, template, np.stack(frames), stats, poses


if __name__ == "__main__":
    meta, template, frames, stats, poses = read(sys.argv[1])
    assert meta is not None, "no /sequence/meta"
    assert frames.shape[1:] == template["positions"].shape, "frame and template shapes differ"
    assert np.isfinite(frames).all(), "non-finite vertex"
    assert len(stats) == len(frames) == len(poses) == meta["frames"], "frame counts differ"
    print(json.dumps({
        "garment": meta["garment"], "motion": meta["motion"], "frames": int(frames.shape[0]),
        "vertices": int(frames.shape[1]), "uvs": int(template["uvs"].shape[0]),
        "material": meta["material"], "pose_dim": len(poses[0]["pose"]),
        "max_penetration_m": max(s["max_penetration_m"] for s in stats),
    }))
