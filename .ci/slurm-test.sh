#!/usr/bin/env bash
# A real single-node Slurm cluster on localhost, and examples/slurm/render.sbatch submitted to it
# as a 4-task job array. Passes only if the frames on disk are complete (`rayreel status` exits
# 0), byte-identical to a single-process render, and each array task rendered its own disjoint
# share. Slurm's own job state is printed for diagnosis but never trusted.
#
#   bash .ci/slurm-test.sh                       # builds rayreel in release first
#   RAYREEL=/path/to/rayreel bash .ci/slurm-test.sh   # uses that binary (tests/slurm.rs does this)
#
# Needs root and Debian/Ubuntu (installs slurmctld slurmd slurm-client munge if sbatch is
# missing). No systemd needed: munged, slurmctld and slurmd are started here and only those
# processes are stopped on exit.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)

TASKS=4
FRAMES=48
SIZE=160x90
start_time=$SECONDS

log() { echo "slurm-test: $*" >&2; }

result=FAIL
pids=()
work=""
cleanup() {
  local rc=$?
  for pid in "${pids[@]}"; do
    kill "$pid" 2>/dev/null || true
  done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
  done
  if [[ $result == PASS && $rc == 0 ]]; then
    [[ -n $work ]] && rm -rf "$work"
    echo "slurm-test: PASS ($((SECONDS - start_time)) s)"
  else
    [[ -n $work ]] && log "scratch directory kept for inspection: $work"
    echo "slurm-test: FAIL"
    ((rc != 0)) || rc=1
  fi
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

fail() {
  log "FAIL: $*"
  exit 1
}

[[ $(id -u) == 0 ]] || fail "must run as root (it starts munged, slurmctld and slurmd)"

# --- 1. packages --------------------------------------------------------------------------
if ! command -v sbatch >/dev/null || ! command -v slurmctld >/dev/null \
  || ! command -v slurmd >/dev/null || ! command -v munged >/dev/null; then
  log "installing slurmctld slurmd slurm-client munge"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends slurmctld slurmd slurm-client munge >/dev/null
fi

work=$(mktemp -d /tmp/rayreel-slurm.XXXXXX)
chmod 755 "$work"
mkdir -p "$work/etc" "$work/state" "$work/spool" "$work/log"

# --- 2. munge -----------------------------------------------------------------------------
if munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
  log "munged already running; using it"
else
  install -d -o munge -g munge -m 0755 /run/munge
  install -d -o munge -g munge -m 0700 /etc/munge /var/log/munge
  install -d -o munge -g munge -m 0711 /var/lib/munge
  if [[ ! -s /etc/munge/munge.key ]]; then
    log "creating /etc/munge/munge.key"
    if command -v mungekey >/dev/null; then
      mungekey --create --keyfile=/etc/munge/munge.key --force
    else
      dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=1024 status=none
    fi
  fi
  chown munge:munge /etc/munge/munge.key
  chmod 0400 /etc/munge/munge.key
  # A stale socket or pid file from a killed munged makes a new one refuse to start.
  rm -f /run/munge/munged.pid /run/munge/munge.socket.2 /run/munge/munge.socket.2.lock
  setpriv --reuid=munge --regid=munge --init-groups /usr/sbin/munged --foreground \
    >"$work/log/munged.log" 2>&1 &
  pids+=($!)
  for _ in $(seq 50); do
    munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break
    sleep 0.2
  done
  munge -n | unmunge >/dev/null || {
    cat "$work/log/munged.log" >&2
    fail "munged did not start"
  }
fi

# --- 3. slurm.conf and the daemons --------------------------------------------------------
host=$(hostname -s)
cpus=$(nproc)
mem_mb=$(awk '/^MemTotal:/ { printf "%d", $2 / 1024 * 0.9 }' /proc/meminfo)
export SLURM_CONF="$work/etc/slurm.conf"
cat >"$SLURM_CONF" <<EOF
ClusterName=rayreel-ci
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CryptoType=crypto/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SwitchType=switch/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
SlurmdParameters=config_overrides
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
MinJobAge=30
KillWait=5
Waittime=0
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=ci Nodes=$host Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
EOF

diagnostics() {
  log "--- slurm.conf"; cat "$SLURM_CONF" >&2
  log "--- sinfo";  sinfo -N -l 2>&1 | sed 's/^/  /' >&2 || true
  log "--- sinfo -R"; sinfo -R 2>&1 | sed 's/^/  /' >&2 || true
  log "--- squeue"; squeue -a 2>&1 | sed 's/^/  /' >&2 || true
  for f in "$work"/log/*.log; do
    log "--- $f (tail)"; tail -n 40 "$f" | sed 's/^/  /' >&2
  done
}

slurmctld -D -i -f "$SLURM_CONF" >>"$work/log/slurmctld.out" 2>&1 &
pids+=($!)
ctld_pid=$!
slurmd -D -f "$SLURM_CONF" >>"$work/log/slurmd.out" 2>&1 &
pids+=($!)
slurmd_pid=$!

log "waiting for node $host to be idle"
state=""
for _ in $(seq 120); do
  kill -0 "$ctld_pid" 2>/dev/null || { diagnostics; fail "slurmctld exited"; }
  kill -0 "$slurmd_pid" 2>/dev/null || { diagnostics; fail "slurmd exited"; }
  state=$(sinfo -h -n "$host" -o %T 2>/dev/null || true)
  [[ $state == idle ]] && break
  sleep 0.5
done
[[ $state == idle ]] || { diagnostics; fail "node $host not idle after 60 s (state: '${state:-none}')"; }
log "cluster up after $((SECONDS - start_time)) s: node $host idle, $cpus CPUs"

# --- 4. rayreel ---------------------------------------------------------------------------
if [[ -z ${RAYREEL:-} ]]; then
  log "building rayreel (release)"
  cargo build --release --quiet
  RAYREEL="$repo/target/release/rayreel"
fi
[[ -x $RAYREEL ]] || fail "RAYREEL=$RAYREEL is not an executable"
RAYREEL=$(realpath "$RAYREEL")
export RAYREEL

cp sequences/orbit.yaml "$work/orbit.yaml"
seq_file="$work/orbit.yaml"
job=(--size "$SIZE" --frames "0-$((FRAMES - 1))")

# --- 5. the one-line submission, then wait for the queue to empty -------------------------
jobid=$(sbatch --parsable --array=0-$((TASKS - 1)) --cpus-per-task=1 --chdir="$work" \
  examples/slurm/render.sbatch "$seq_file" "${job[@]}" --output "$work/out/frame_####.png")
jobid=${jobid%%;*}
log "submitted job array $jobid ($TASKS tasks)"

deadline=$((SECONDS + 300))
while squeue -h -j "$jobid" 2>/dev/null | grep -q .; do
  ((SECONDS < deadline)) || { diagnostics; scancel "$jobid" || true; fail "job $jobid still queued after 5 min"; }
  kill -0 "$ctld_pid" 2>/dev/null || { diagnostics; fail "slurmctld exited while the job ran"; }
  sleep 1
done
log "job $jobid left the queue; Slurm says:"
scontrol show job "$jobid" 2>/dev/null | grep -E 'JobId=|JobState=' | sed 's/^/  /' >&2 || true

# --- 6. verify the files, not Slurm's word ------------------------------------------------
problems=0
bad() { log "FAIL: $*"; problems=$((problems + 1)); }

# Each array task ran: its log exists, holds JSON progress and its own disjoint share.
all_frames=()
for ((t = 0; t < TASKS; t++)); do
  tlog="$work/rayreel-${jobid}_$t.log"
  if [[ ! -s $tlog ]]; then
    bad "task $t left no log ($tlog)"
    continue
  fi
  json=$(grep -c '^{"event": ' "$tlog" || true)
  written=$(grep -c '"status": "written"' "$tlog" || true)
  log "task $t: $json JSON lines, $written frames written"
  ((json > 0)) || bad "task $t log has no JSON progress lines"
  ((written == FRAMES / TASKS)) || bad "task $t wrote $written frames, expected $((FRAMES / TASKS))"
  mapfile -t mine < <(sed -n 's/.*"frame": \([0-9]*\),.*"status": "written".*/\1/p' "$tlog")
  all_frames+=("${mine[@]}")
  # --shard auto gives task t (of N) frames t, t+N, t+2N, ...
  foreign=()
  for f in "${mine[@]}"; do
    ((f % TASKS == t)) || foreign+=("$f")
  done
  ((${#foreign[@]} == 0)) || bad "task $t wrote ${#foreign[@]} frames outside its share (frames $t, $((t + TASKS)), ...): ${foreign[*]:0:5} ..."
done
dupes=$(printf '%s\n' "${all_frames[@]}" | sort -n | uniq -d | tr '\n' ' ')
[[ -z $dupes ]] || bad "frames written by more than one task: $dupes"
count=$(printf '%s\n' "${all_frames[@]}" | sort -nu | grep -c . || true)
((count == FRAMES)) || bad "the tasks wrote $count distinct frames, expected $FRAMES"

# `rayreel status` with the render's flags is the final check.
if "$RAYREEL" status "$seq_file" "${job[@]}" --output "$work/out/frame_####.png" >"$work/status.txt" 2>&1; then
  log "status: $(head -n 1 "$work/status.txt")"
else
  cat "$work/status.txt" >&2
  bad "rayreel status exited non-zero"
fi

# Byte-identical to one process rendering the same command.
"$RAYREEL" render "$seq_file" "${job[@]}" --output "$work/ref/frame_####.png" --quiet \
  || bad "the single-process reference render failed"
n=0
for ref in "$work"/ref/frame_*.png; do
  name=$(basename "$ref")
  if cmp -s "$ref" "$work/out/$name"; then
    n=$((n + 1))
  else
    bad "$name differs from the single-process render (or is missing)"
  fi
done
((n == FRAMES)) || bad "$n of $FRAMES frames identical to the single-process render"
extra=$(find "$work/out" -mindepth 1 ! -name 'frame_*.png' | head -n 5)
[[ -z $extra ]] || bad "leftover files in the output directory: $extra"

if ((problems)); then
  diagnostics
  for f in "$work"/rayreel-*.log; do log "--- $f"; sed 's/^/  /' "$f" >&2; done
  fail "$problems problem(s)"
fi
log "$FRAMES frames from $TASKS array tasks: status 0, all identical to the single-process render"
result=PASS
