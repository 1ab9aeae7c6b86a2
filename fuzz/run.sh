#!/usr/bin/env bash
# Bounded fuzz smoke run of every loader (docs/RELIABILITY.md): seed corpora from the project's
# own outputs and ../shared/testdata, then `cargo +nightly fuzz run` for SECONDS per target.
# Needs the nightly toolchain, cargo-fuzz, python3 with numpy, and the dit-garment binary
# ($DIT_GARMENT_BIN). Prints one line per target: executions, seconds, corpus size, result.
# A crash leaves its input in fuzz/artifacts/<target>/ and makes this script fail.
set -euo pipefail
cd "$(dirname "$0")"
seconds="${1:-30}"
bin="${DIT_GARMENT_BIN:?set DIT_GARMENT_BIN to the dit-garment binary}"
targets=(recording obj ply pattern npz spec scene_config bvh model_run ensemble checkpoint pickle)
shared=../../shared/testdata
mkdir -p "${targets[@]/#/corpus/}"
seeds=$(mktemp -d)
trap 'rm -rf "$seeds"' EXIT

# Seeds: what the program writes and what users bring.
"$bin" simulate --quiet --frames 3 --blend-frames 1 --settle-frames 1 \
  --out "$seeds/seq.mcap" --obj-dir "$seeds/objs" >/dev/null
cp "$seeds/seq.mcap" corpus/recording/seed_simulated.mcap
cp "$(ls "$seeds"/objs/*.obj | head -1)" corpus/obj/seed_frame.obj
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\ng a\nf 1/1 2/2 3/3 4/4\n' \
  >corpus/obj/seed_quad.obj
"$bin" garments show tank_tight --pattern-out corpus/pattern/seed_tank_tight.json >/dev/null
"$bin" garments make tank_tight --edge-length 0.05 --out corpus/ply/seed_tank_tight.ply >/dev/null || true
printf 'ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n' \
  >corpus/ply/seed_quad.ply
"$bin" synth --example-spec tiny >corpus/spec/seed_tiny.toml
"$bin" simulate --print-config >corpus/scene_config/seed_default.toml
if [ -d "$shared" ]; then
  cp "$shared"/garmentcode/*.json corpus/pattern/ 2>/dev/null || true
  cp "$shared"/bodies/*.obj corpus/obj/ 2>/dev/null || true
fi
cp ../motions/tests/fixtures/pickle/*.pkl ../motions/tests/fixtures/pickle/take/SMPL/*.pkl \
  corpus/pickle/
# BVH: CMU's first clip cut to its hierarchy and a few frames (Debian's assimp-testmodels), and a
# two-joint file written here.
cmu=/usr/share/assimp/models/BVH/01_01.bvh
if [ -f "$cmu" ]; then
  awk '/^Frames:/{print "Frames: 3"; next} {print} /^Frame Time:/{n=NR} n&&NR>n+2{exit}' "$cmu" \
    >corpus/bvh/seed_cmu.bvh
fi
printf 'HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n JOINT Leg\n {\n  OFFSET 0 -1 0\n  CHANNELS 3 Xrotation Yrotation Zrotation\n  End Site\n  {\n   OFFSET 0 -1 0\n  }\n }\n}\nMOTION\nFrames: 2\nFrame Time: 0.0333333\n0 1 0 0 0 0 0 0 0\n0 1 0 0 0 0 10 0 0\n' \
  >corpus/bvh/seed_two_joints.bvh
python3 - corpus/npz <<'PY' || echo "note: python3 with numpy not found: no npz seeds"
import sys, numpy as np
out = sys.argv[1]
t = np.linspace(0, 1, 8)
np.savez(f"{out}/seed_amass.npz", poses=np.outer(t, np.ones(156)) * 0.1,
         trans=np.outer(t, [0.1, 0.0, 1.0]), mocap_framerate=np.array(60.0),
         betas=np.zeros(16), gender=np.array("female"))
np.savez_compressed(f"{out}/seed_compressed.npz", a=np.arange(12.0).reshape(3, 4),
                    b=np.asfortranarray(np.ones((2, 3), np.float32)))
PY

# Model folders: a tiny network trained here for 10 steps on the tiny dataset (its files joined
# by the separator line of fuzz_targets/folder.rs), as a run, an ensemble of two and a checkpoint
# (with and without its checksums).
tiny="$seeds/tiny"
"$bin" synth --example-spec tiny >"$seeds/tiny.toml"
"$bin" synth --spec "$seeds/tiny.toml" --out "$tiny/data" --quiet >/dev/null
"$bin" dataset tensors "$tiny/data" --out "$tiny/tensors" --resolution 32 \
  --target lbs_residual --quiet >/dev/null
printf '[model]\nwidth = 8\ndepth = 1\nheads = 2\nmlp_ratio = 1.0\ncondition_tokens = 1\n[training]\nsteps = 10\nbatch = 1\nwarmup_steps = 1\nlog_every = 5\nval_every = 10\ncheckpoint_every = 10\nval_frames = 2\n' \
  >"$seeds/tiny-model.toml"
"$bin" train --data "$tiny/tensors" --out "$tiny/run" --config "$seeds/tiny-model.toml" \
  --threads 1 --quiet >/dev/null
join_files() {
  python3 -c 'import sys; sys.stdout.buffer.write(b"\n@@next-file@@\n".join(open(p, "rb").read() for p in sys.argv[1:]))' "$@"
}
run_files=("$tiny/run/config.toml" "$tiny/run/tensors.json" "$tiny/run/model.safetensors")
ckpt="$tiny/run/checkpoint-00000010"
printf 'members = ["a", "b"]\n' >"$seeds/ensemble.toml"
join_files "${run_files[@]}" >corpus/model_run/seed_tiny
join_files "$seeds/ensemble.toml" "${run_files[@]}" "${run_files[@]}" >corpus/ensemble/seed_pair
checkpoint_files=("$tiny/run/checkpoint.json" "$ckpt/config.toml" "$ckpt/state.json" \
  "$ckpt/model.bpk" "$ckpt/optim.bpk" "$ckpt/ema.bpk" "$tiny/run/log.jsonl")
join_files "${checkpoint_files[@]}" "$ckpt/checksums.json" >corpus/checkpoint/seed_checked
join_files "${checkpoint_files[@]}" >corpus/checkpoint/seed_unchecked

status=0
printf '%-14s %12s %8s %8s  %s\n' target executions seconds corpus result
for t in "${targets[@]}"; do
  log=$(mktemp)
  if cargo +nightly fuzz run "$t" "corpus/$t" -- \
      -max_total_time="$seconds" -rss_limit_mb=2048 -max_len=262144 -print_final_stats=1 \
      >"$log" 2>&1; then
    result=ok
  else
    result="CRASH (see fuzz/artifacts/$t)"
    status=1
    tail -n 40 "$log"
  fi
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  printf '%-14s %12s %8s %8s  %s\n' "$t" "${runs:-?}" "$seconds" "$(ls "corpus/$t" | wc -l)" "$result"
  rm -f "$log"
done
exit $status
