#!/bin/sh
# A distributed bake through a real single-node Slurm cluster (bake/dist/DIST.md): munged,
# slurmctld and slurmd on localhost with a generated slurm.conf in a temporary folder, started
# and stopped here; `lbk plan --sbatch` submits the units as a job array and the merge as a job
# that depends on it; the container must equal `lbk bake`'s byte for byte.
# usage: slurm_dist.sh LBK   exit 0 passed, 77 skipped (not root and Slurm not installed), else failed.
set -u
LBK=$(readlink -f "$1")
PKGS="munge slurmd slurmctld slurm-client"
missing=""
for p in $PKGS; do dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing="$missing $p"; done
if [ -n "$missing" ]; then
  if [ "$(id -u)" != 0 ]; then
    echo "SKIPPED: Slurm is not installed ($missing) and this is not root: apt-get install -y$missing (or make deps)"
    exit 77
  fi
  echo "installing$missing"
  { apt-get update -qq || true; } && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $missing >/dev/null || exit 1
fi
if [ "$(id -u)" != 0 ]; then
  echo "SKIPPED: the single-node cluster runs its daemons as root (SlurmUser=root); run as root"
  exit 77
fi

T=$(mktemp -d /tmp/lbk-slurm-XXXXXX)
chmod 755 "$T"
cleanup() {
  for f in slurmd slurmctld munged; do
    [ -f "$T/$f.pid" ] && kill "$(cat "$T/$f.pid")" 2>/dev/null
  done
  sleep 1
  for f in slurmd slurmctld munged; do
    [ -f "$T/$f.pid" ] && kill -9 "$(cat "$T/$f.pid")" 2>/dev/null
  done
  rm -rf "$T"
}
trap cleanup EXIT INT TERM
fail() { echo "FAIL: $*"; for l in "$T"/*.log; do [ -f "$l" ] && { echo "== $l"; tail -n 20 "$l"; }; done; exit 1; }

# ports of our own, so a Slurm already running on this machine is left alone
base=$(( 20000 + $$ % 20000 ))
host=$(hostname -s)
cpus=$(nproc)
mkdir -p "$T/state" "$T/spool" "$T/munge"
chmod 700 "$T/munge"
dd if=/dev/urandom of="$T/munge/munge.key" bs=1024 count=1 2>/dev/null && chmod 400 "$T/munge/munge.key"
munged --force --key-file="$T/munge/munge.key" --socket="$T/munge/munge.sock" --pid-file="$T/munged.pid" \
  --log-file="$T/munged.log" --seed-file="$T/munge/seed" || fail "munged did not start"
cat > "$T/slurm.conf" <<CONF
ClusterName=lbktest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$base
SlurmdPort=$((base + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$T/munge/munge.sock
CredType=cred/munge
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/slurmctld.log
SlurmdLogFile=$T/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
SlurmdTimeout=60
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=lbk Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$T/slurm.conf"
slurmctld -f "$SLURM_CONF" || fail "slurmctld did not start"
slurmd -f "$SLURM_CONF" || fail "slurmd did not start"
i=0
until sinfo -h -o '%T' 2>/dev/null | grep -q idle; do
  i=$((i + 1)); [ $i -gt 60 ] && fail "the node never became idle: $(sinfo 2>&1)"; sleep 1
done
echo "cluster up: $(sinfo -h -o '%P %D %T %c')"

scene=tests/fuzz/sets_scene.gltf
opts="--samples 32 --target-error none --texel-density 2 --seed 5"
"$LBK" bake $scene -o "$T/local.lbk" $opts --threads 2 -q || fail "local bake"
"$LBK" plan $scene -o "$T/level.lbk" --plan "$T/plan.json" --units 3 --sbatch "$T/bake.sh" $opts >/dev/null || fail "plan"
SBATCH_FLAGS="--cpus-per-task=1" LBK="$LBK" sh "$T/bake.sh" > "$T/submit.log" 2>&1 || fail "sbatch: $(cat "$T/submit.log")"
cat "$T/submit.log"
i=0
while [ -n "$(squeue -h 2>/dev/null)" ]; do
  i=$((i + 1)); [ $i -gt 600 ] && fail "jobs still queued after 600 s: $(squeue)"; sleep 1
done
[ -f "$T/level.lbk" ] || fail "the merge job wrote no container: $(cat "$T"/level.lbk.parts/*.log 2>/dev/null | tail -n 20)"
ls "$T/level.lbk.parts/"
cmp "$T/local.lbk" "$T/level.lbk" || fail "the Slurm bake differs from the local bake"
echo "3 units on Slurm + merge, $(wc -c < "$T/level.lbk") bytes, byte-identical to lbk bake"

# a level of one transport run: 4 units share its radiosity caches through the plan's cache
# folder (DIST.md §Shared caches), the array's tasks computing the bounces between them
scene=scenes/cornell_box/CornellBox-Original.gltf
opts="--samples 64 --target-error none --texel-density 4 --seed 5"
"$LBK" bake $scene -o "$T/cornell.lbk" $opts --threads 2 -q || fail "local bake of the Cornell box"
"$LBK" plan $scene -o "$T/box.lbk" --plan "$T/box.json" --units 4 --sbatch "$T/box.sh" $opts >/dev/null || fail "plan"
SBATCH_FLAGS="--cpus-per-task=1" UNIT_FLAGS="--threads 1" LBK="$LBK" sh "$T/box.sh" > "$T/submit.log" 2>&1 || fail "sbatch: $(cat "$T/submit.log")"
i=0
while [ -n "$(squeue -h 2>/dev/null)" ]; do
  i=$((i + 1)); [ $i -gt 600 ] && fail "jobs still queued after 600 s: $(squeue)"; sleep 1
done
[ -f "$T/box.lbk" ] || fail "the merge job wrote no container: $(cat "$T"/box.lbk.parts/*.log 2>/dev/null | tail -n 20)"
cmp "$T/cornell.lbk" "$T/box.lbk" || fail "the shared-cache Slurm bake differs from the local bake"
ls -d "$T"/box.lbk.cache-* 2>/dev/null && fail "the merge left the shared cache folder"
computed=$(cat "$T"/box.lbk.parts/unit-*.log | awk '/cache shares computed/ {c += $6; u++} END {print u + 0, c + 0}')
[ "${computed%% *}" = 4 ] && [ "${computed#* }" -gt 0 ] || fail "the units shared no cache: $(cat "$T"/box.lbk.parts/unit-*.log)"
echo "units, cache shares computed: $computed"
echo "ok: 3 units on Slurm + merge; 4 units sharing the Cornell box's caches + merge; both byte-identical to lbk bake"
