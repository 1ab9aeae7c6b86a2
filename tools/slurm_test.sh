#!/usr/bin/env bash
# A real Slurm run of dataset synthesis on this machine: installs Debian's Slurm and munge
# packages (needs root and apt), starts a single-node cluster on localhost (munged, slurmctld,
# slurmd), submits deploy/slurm/synth.sbatch as a 2-task array job for the tiny example spec,
# waits, merges, verifies and prints the stats. Stops the daemons on exit.
#
#   bash tools/slurm_test.sh            # uses target/release/dit-garment (built if missing)
#
# Output of a run on the project's machine: docs/DATASETS.md.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${DIT_GARMENT_BIN:-$root/target/release/dit-garment}
work=$(mktemp -d /tmp/dit-garment-slurm.XXXXXX)
echo "== work folder $work"
if [ ! -x "$bin" ]; then
  (cd "$root" && cargo build --release --quiet)
fi
if ! command -v slurmctld >/dev/null 2>&1 || ! command -v munged >/dev/null 2>&1; then
  echo "== installing slurm-wlm and munge (Debian packages)"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi
echo "== $(slurmctld -V)"

cleanup() {
  [ -f "$work/slurmd.pid" ] && kill "$(cat "$work/slurmd.pid")" 2>/dev/null || true
  [ -f "$work/slurmctld.pid" ] && kill "$(cat "$work/slurmctld.pid")" 2>/dev/null || true
  [ -f "$work/munged.pid" ] && kill "$(cat "$work/munged.pid")" 2>/dev/null || true
  # The work folder goes too, unless asked to keep it for a look (KEEP_WORK=1): once the
  # daemons have exited (they write their state until then), and never failing the run.
  if [ "${KEEP_WORK:-0}" != 1 ]; then
    for _ in $(seq 50); do
      pgrep -f "$work" >/dev/null 2>&1 || break
      sleep 0.1
    done
    rm -rf "$work" 2>/dev/null || true
  fi
}
trap cleanup EXIT

# munge: a fresh key and a daemon with its own socket.
mkdir -p "$work/munge"
dd if=/dev/urandom bs=1 count=1024 of="$work/munge/munge.key" status=none
chmod 400 "$work/munge/munge.key"
munged --key-file="$work/munge/munge.key" --socket="$work/munge/socket" \
  --pid-file="$work/munged.pid" --log-file="$work/munged.log" --seed-file="$work/munge/seed" --force
export MUNGE_SOCKET="$work/munge/socket"

host=$(hostname -s)
cpus=$(nproc)
mem=$(awk '/MemTotal/ {print int($2 / 1024 * 0.8)}' /proc/meminfo)
mkdir -p "$work/state" "$work/spool"
cat > "$work/slurm.conf" <<CONF
ClusterName=dit-garment-local
SlurmctldHost=$host
SlurmUser=root
AuthType=auth/munge
AuthInfo=socket=$work/munge/socket
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
SlurmctldPort=16817
SlurmdPort=16818
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
NodeName=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$work/slurm.conf"
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
for _ in $(seq 1 30); do
  if sinfo -h -o '%T' 2>/dev/null | grep -qE 'idle|mix|alloc'; then break; fi
  sleep 1
done
echo "== cluster:"; sinfo

"$bin" synth --example-spec tiny > "$work/tiny.toml"
job=$(sbatch --parsable --array=0-1 --cpus-per-task=1 --mem=2G --chdir="$work" \
  --export=ALL,DIT_GARMENT_BIN="$bin" "$root/deploy/slurm/synth.sbatch" "$work/tiny.toml" "$work/data")
echo "== submitted array job $job (2 tasks)"
squeue
start=$(date +%s)
while squeue -h -j "$job" 2>/dev/null | grep -q .; do
  if [ $(( $(date +%s) - start )) -gt 900 ]; then echo "job did not finish in 15 min"; exit 1; fi
  sleep 2
done
echo "== job finished after $(( $(date +%s) - start )) s; task logs:"
for f in "$work"/synth-"$job"_*.log; do echo "--- $(basename "$f")"; cat "$f"; done
echo "== merge, verify, stats"
"$bin" dataset merge "$work/data" "$work/data"
"$bin" dataset verify "$work/data"
"$bin" dataset stats "$work/data" --json "$work/stats.json"
echo "== ok: a real Slurm array job synthesized, merged and verified the tiny dataset"
