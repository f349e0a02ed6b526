#!/usr/bin/env bash
# A single-node Slurm on this Debian machine, a sharded `surfmotion batch`
# through a real job array, `batch merge`, and the check that the merged
# report equals one unsharded run's (same clips, same outputs byte for byte).
#
# usage: scripts/slurm-local.sh [WORKDIR]       (as root; WORKDIR default /tmp/surfmotion-slurm)
#   SHARDS=4                 tasks of the array (sbatch --array=0-$((SHARDS-1)))
#   LIB=DIR                  the clip folder (default ../shared/data/mocap/cmu-amc/02)
#   TARGET="--db DIR"        the batch's target (default: samba_db, made in WORKDIR)
#   BIN=PATH                 the binary (default target/release/surfmotion)
#   PORT=16817               slurmctld's port (slurmd takes PORT+1)
#   KEEP=1                   leave the daemons running at the end
#
# Everything Slurm needs lives in WORKDIR: slurm.conf (SLURM_CONF points the
# commands at it), state and spool folders, logs, and a munged of its own
# (own key and socket), so nothing under /etc is written and an installed
# Slurm is left alone. Only the packages come from the distribution
# (slurm-wlm, munge: installed with apt-get when sbatch is missing).
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
W=$(realpath -m "${1:-/tmp/surfmotion-slurm}")
SHARDS=${SHARDS:-4}
S=${SURFMOTION_DATA:-$repo/../shared/data}
LIB=${LIB:-$S/mocap/cmu-amc/02}
BIN=$(realpath "${BIN:-$repo/target/release/surfmotion}")
say() { printf '== %s\n' "$*"; }
die() { printf 'slurm-local: %s\n' "$*" >&2; exit 1; }

[ "$(id -u)" = 0 ] || die "run as root (it installs packages and starts slurmctld, slurmd and munged)"
[ -x "$BIN" ] || die "$BIN: no binary (cargo build --release)"
[ -d "$LIB" ] || die "$LIB: no clip folder (set LIB or SURFMOTION_DATA)"

if ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
  say "installing slurm-wlm and munge (apt-get)"
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi

mkdir -p "$W"/{munge,state,spool,log}
chmod 700 "$W/munge"
stop() {
  for p in "$W/slurmd.pid" "$W/slurmctld.pid" "$W/munge/munged.pid"; do
    [ -s "$p" ] && kill "$(cat "$p")" 2>/dev/null || true
    rm -f "$p"
  done
}
stop
trap '[ "${KEEP:-0}" = 1 ] || stop' EXIT

say "munged (key and socket in $W/munge)"
[ -s "$W/munge/munge.key" ] || mungekey --create --keyfile="$W/munge/munge.key" --bits=1024
chmod 400 "$W/munge/munge.key"
munged --force --key-file="$W/munge/munge.key" --socket="$W/munge/munge.socket" \
  --pid-file="$W/munge/munged.pid" --log-file="$W/log/munged.log" --seed-file="$W/munge/munged.seed"

host=$(hostname -s)
node=$(slurmd -C | head -1 | sed 's/ UpTime.*//')
export SLURM_CONF=$W/slurm.conf
cat > "$SLURM_CONF" <<EOF
# written by surfmotion scripts/slurm-local.sh: one node, local only
ClusterName=surfmotion-local
SlurmctldHost=$host
SlurmctldPort=${PORT:-16817}
SlurmdPort=$((${PORT:-16817} + 1))
AuthType=auth/munge
AuthInfo=socket=$W/munge/munge.socket
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$W/state
SlurmdSpoolDir=$W/spool
SlurmctldPidFile=$W/slurmctld.pid
SlurmdPidFile=$W/slurmd.pid
SlurmctldLogFile=$W/log/slurmctld.log
SlurmdLogFile=$W/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
$node State=UNKNOWN
PartitionName=local Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF

say "slurmctld and slurmd ($SLURM_CONF)"
slurmctld -c -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
for _ in $(seq 60); do
  sinfo -h -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)' && break
  sleep 1
done
sinfo -h -o '%T' | grep -qE '^(idle|mixed|allocated)' || {
  tail -20 "$W/log/slurmctld.log" "$W/log/slurmd.log" >&2
  die "the node did not come up (logs above)"
}
sinfo

if [ -z "${TARGET:-}" ]; then
  if [ ! -f "$W/samba_db/character.toml" ] || [ ! -d "$W/samba_db/cache" ]; then
    say "the samba database ($W/samba_db)"
    "$BIN" db init "$W/samba_db" --mesh "$S/4d/samba/samba.obj" \
      --sequence dance="$S/4d/samba/samba.pc2" \
      --landmarks "$repo/tests/fixtures/samba.landmarks.json" --force
    "$BIN" db build "$W/samba_db"
  fi
  TARGET="--db $W/samba_db"
fi

rm -rf "$W/sharded" "$W/whole"
last=$((SHARDS - 1))
say "sbatch --array=0-$last: $(find -L "$LIB" -type f \( -iname '*.bvh' -o -iname '*.amc' -o -iname '*.fbx' \) | wc -l) clips of $LIB, one shard per task"
t0=$(date +%s)
# No --shard: each task reads SLURM_ARRAY_TASK_ID/_MIN/_COUNT itself.
sbatch --wait --array=0-"$last" --cpus-per-task=1 --job-name=surfmotion-batch \
  --output="$W/log/batch-%A_%a.out" \
  --wrap="$BIN batch $TARGET --mocap-dir $LIB -o $W/sharded --format pc2 --jobs 1" \
  || { tail -n 5 "$W"/log/batch-*.out >&2; die "a task of the array failed (its log above)"; }
t1=$(date +%s)
grep -h "from the Slurm array" "$W"/log/batch-*.out | sort
say "the array took $((t1 - t0)) s; batch merge"
"$BIN" batch merge "$W/sharded"

say "one unsharded run, for comparison"
t0=$(date +%s)
env -u SLURM_ARRAY_TASK_ID "$BIN" batch $TARGET --mocap-dir "$LIB" -o "$W/whole" --format pc2 --jobs 1 >/dev/null
t1=$(date +%s)
say "the unsharded run took $((t1 - t0)) s"

say "comparing the merged report with the unsharded one"
view() { # the clips of a report with what each produced, outputs relative to its folder
  jq -S --arg d "$2/" '[.outcomes[] | {clip, output: (.output | ltrimstr($d)), status, frames, error_cm, warnings, reason}]' "$1"
}
view "$W/sharded/batch.json" "$W/sharded" > "$W/merged.view.json"
view "$W/whole/batch.json" "$W/whole" > "$W/whole.view.json"
diff -u "$W/whole.view.json" "$W/merged.view.json" || die "the merged report differs from the unsharded run's (diff above)"
n=$(jq length "$W/whole.view.json")
( cd "$W/whole" && find . -type f \( -name '*.pc2' -o -name '*.obj' \) | sort | xargs sha256sum ) > "$W/whole.sha256"
( cd "$W/sharded" && sha256sum -c --quiet "$W/whole.sha256" ) || die "outputs differ (above)"
extra=$(cd "$W/sharded" && find . -type f \( -name '*.pc2' -o -name '*.obj' \) | wc -l)
[ "$extra" = "$(wc -l < "$W/whole.sha256")" ] || die "the sharded folder holds $extra outputs, the unsharded $(wc -l < "$W/whole.sha256")"
say "OK: $n clips, $(wc -l < "$W/whole.sha256") output files byte-identical; shards: $(jq -r '.merged_from | length' "$W/sharded/batch.json"), report $W/sharded/batch.html"
