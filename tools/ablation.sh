#!/usr/bin/env bash
# The surrogate's ablation protocol (docs/SURROGATE_ARMS.md, "The ablation"): one dataset
# (specs/shipped.toml), one fresh held-out set (specs/heldout.toml), every arm trained the
# same steps on one thread from the configuration in tools/ablation/ARM.toml, then scored by
# `evaluate` on training sequences, test_garment, test_motion and the shipped `test` split
# (unseen shape and material too), and on the held-out set's paper-like `test` split.
#
#   tools/ablation.sh tensors DATA OUT          # both tensor sets (zscore and bounded conditions)
#   tools/ablation.sh tensors-designs DESIGNS OUT   # bounded tensors of specs/designs.toml's data (a5_*)
#   tools/ablation.sh tensors-nearest DESIGNS OUT   # the same with the nearest-body inputs (a6_*)
#   tools/ablation.sh tensors-kinds KINDS OUT       # bounded tensors of specs/kinds.toml's data (a7_*)
#   tools/ablation.sh tensors-window8 DESIGNS OUT   # designs.toml's tensors with an 8-frame pose window (a8_*)
#   tools/ablation.sh tensors-motions MOTIONS OUT   # bounded tensors of specs/motions.toml's data (a9_*)
#   tools/ablation.sh tensors-SPEC DATA OUT         # the same of specs/SPEC.toml's data, SPEC one of
#     random14 (a10_*), random_wide (a11_*, a15_*, a16_*), random21 (a12_*), random28 (a13_*), union (a14_*)
#   tools/ablation.sh train ARM OUT             # trains OUT/runs/ARM (resumes a killed run)
#   tools/ablation.sh evaluate ARM DATA HELDOUT OUT [THREADS]   # OUT/eval/ARM-{shipped,heldout}.json
#     (DATA: the arm's own dataset, whose `train` split it trained on; its test splits are
#     shipped.toml's for a0-a8, while a9-a14's specs draw their own: score those on
#     designs.toml's data for the shipped splits)
#   tools/ablation.sh baselines DATA HELDOUT OUT                # the no-learning rows, once
#
# Environment: DIT_GARMENT_BIN (default target/release/dit-garment), ABLATION_STEPS (500, as
# measured in docs/SURROGATE_ARMS.md: 6-7 minutes of one core at batch 8), ABLATION_SEQUENCES (2
# per shipped split, as measured).
set -euo pipefail
bin=${DIT_GARMENT_BIN:-target/release/dit-garment}
steps=${ABLATION_STEPS:-500}
per_split=${ABLATION_SEQUENCES:-2}
here=$(cd "$(dirname "$0")" && pwd)

tensors_of() {
  case "$1" in
    a0_* | a1_* | a2_*) echo zscore ;;
    a5_*) echo designs ;;
    a6_*) echo nearest ;;
    a7_*) echo kinds ;;
    a8_*) echo window8 ;;
    a9_*) echo motions ;;
    a10_*) echo random14 ;;
    a11_* | a15_* | a16_*) echo random_wide ;;
    a12_*) echo random21 ;;
    a13_*) echo random28 ;;
    a14_*) echo union ;;
    *) echo bounded ;;
  esac
}

case "${1:-}" in
  tensors)
    data=$2 out=$3
    for c in zscore bounded; do
      [ -f "$out/tensors-$c/manifest.json" ] ||
        "$bin" dataset tensors "$data" --out "$out/tensors-$c" --target lbs_residual --conditions "$c" --quiet
    done
    ;;
  tensors-designs | tensors-nearest | tensors-kinds | tensors-window8 | tensors-motions | tensors-random14 | tensors-random_wide | tensors-random21 | tensors-random28 | tensors-union)
    # Bounded lbs_residual tensors of the arm's dataset; the kind adds its one flag.
    kind=${1#tensors-} data=$2 out=$3
    extra=()
    case "$kind" in
      nearest) extra=(--body-nearest) ;;
      window8) extra=(--window 8) ;;
    esac
    [ -f "$out/tensors-$kind/manifest.json" ] ||
      "$bin" dataset tensors "$data" --out "$out/tensors-$kind" --target lbs_residual --conditions bounded \
        "${extra[@]}" --quiet
    ;;
  train)
    arm=$2 out=$3
    run="$out/runs/$arm"
    resume=()
    [ -f "$run/checkpoint.json" ] && resume=(--resume)
    [ -f "$run/summary.json" ] && { echo "$arm: trained"; exit 0; }
    "$bin" train --data "$out/tensors-$(tensors_of "$arm")" --out "$run" \
      --config "$here/ablation/$arm.toml" --steps "$steps" --threads 1 --quiet "${resume[@]}"
    ;;
  evaluate)
    arm=$2 data=$3 heldout=$4 out=$5 threads=${6:-1}
    mkdir -p "$out/eval"
    "$bin" evaluate --model "$out/runs/$arm" --data "$data" --splits train,test_garment,test_motion,test \
      --max-sequences "$per_split" --baselines "" --threads "$threads" --quiet \
      --json "$out/eval/$arm-shipped.json" --report "$out/eval/$arm-shipped"
    "$bin" evaluate --model "$out/runs/$arm" --data "$heldout" --splits test --baselines "" \
      --threads "$threads" --quiet --json "$out/eval/$arm-heldout.json" --report "$out/eval/$arm-heldout"
    ;;
  baselines)
    data=$2 heldout=$3 out=$4
    mkdir -p "$out/eval"
    "$bin" evaluate --model none --data "$data" --splits train,test_garment,test_motion,test \
      --max-sequences "$per_split" --baselines lbs,lbs_nearest,floor,rest --quiet \
      --json "$out/eval/baselines-shipped.json" --report "$out/eval/baselines-shipped"
    "$bin" evaluate --model none --data "$heldout" --splits test --baselines lbs,lbs_nearest,floor,rest \
      --quiet --json "$out/eval/baselines-heldout.json" --report "$out/eval/baselines-heldout"
    ;;
  *)
    # The usage: the comment block at the top of this file.
    awk 'NR > 1 && !/^#/ { exit } NR > 1' "$0"
    exit 2
    ;;
esac
