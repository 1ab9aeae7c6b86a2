#!/usr/bin/env bash
# Runs the same commands through two builds of dit-garment and compares their outputs byte for
# byte (JSON less timings and paths): for refactors that must not change results.
#   tools/compare_binaries.sh OLD_BINARY NEW_BINARY WORK_DIR   (WORK_DIR is emptied)
# Needs ../shared/testdata (a GarmentCode pattern), Debian's assimp-testmodels (a CMU clip) and
# Python's json. Prints DIFF or MISSING per file that differs, then the count compared.
set -u
old=$(realpath "$1") new=$(realpath "$2") work=$3
rm -rf "$work"; mkdir -p "$work"; work=$(realpath "$work")
clip=/usr/share/assimp/models/BVH/01_01.bvh
cd "$(dirname "$0")/.."
export WORK="$work"
for which in old new; do
  bin=${!which}; o=$work/$which; mkdir -p $o
  export DIT_GARMENT_CACHE=$o/cache
  $bin synth --spec specs/tiny.toml --out $o/tiny --jobs 2 --quiet > $o/synth.txt 2>&1
  $bin dataset tensors $o/tiny --out $o/tensors --quiet > /dev/null 2>&1
  $bin simulate --garment tshirt_regular --motion walk:duration=0.7 --betas 0.5,-0.3 --out $o/sim.mcap --quiet > /dev/null 2>&1
  $bin garments make ../shared/testdata/garmentcode/shirt_mean_specification.json --out $o/shirt.obj > /dev/null 2>&1
  $bin predict --model surrogate/ensemble --config-from $o/sim.mcap --out $o/pred.mcap --quiet > /dev/null 2>&1
  $bin evaluate --model surrogate/ensemble --data $o/tiny --baselines lbs,floor --json $o/eval.json --quiet > /dev/null 2>&1
  $bin motions show $clip --json $o/show.json > /dev/null 2>&1
  $bin uv tank_tight --out $o/uv --json $o/uv.json > /dev/null 2>&1
done
cd $work
for f in $(cd old && find . -type f ! -path './cache/*' | sort); do
  if [ ! -f new/$f ]; then echo "MISSING in new: $f"; continue; fi
  case $f in
    *.json|*.jsonl)
      python3 - "$f" <<'PY' || echo "DIFF $f"
import json,os,sys
f=sys.argv[1]
def load(p):
    t=open(p).read()
    try: return [json.loads(t)]
    except Exception: return [json.loads(l) for l in t.splitlines() if l.strip()]
# Timings, and the model's folder (a builtin model resolves inside each build's source tree).
T={'fps','frames_per_s','sequences_per_hour','wall','timings','run','members'}
def strip(x):
    if isinstance(x,dict): return {k:strip(v) for k,v in x.items() if k not in T and not k.endswith('_s') and 'fps' not in k}
    if isinstance(x,list): return [strip(v) for v in x]
    if isinstance(x,str):
        for side in ('old','new'):
            x=x.replace(os.environ['WORK']+'/'+side+'/', 'WORK/')
        return x
    return x
a,b=strip(load('old/'+f)),strip(load('new/'+f))
sys.exit(0 if a==b else 1)
PY
      ;;
    *.txt) ;; # printouts carry timings
    *) cmp -s old/$f new/$f || echo "DIFF $f";;
  esac
done
echo "compared $(cd old && find . -type f ! -path './cache/*' | wc -l) files"
