#!/usr/bin/env bash
# `cellsim sweep --slurm --submit` on a real Slurm: a throw-away single-node cluster on
# this machine, then the same sweep run locally, and the two tables compared.
#
#   1. installs Debian's slurm-wlm and munge if missing (apt-get, with sudo when not root);
#   2. starts a private munged (its own key, socket and logs in a temporary directory: a
#      munged already running here is neither used nor disturbed) and a slurmctld and a
#      slurmd as the current user, configured by a slurm.conf written into that directory
#      (one node, this host, its CPUs as `slurmd -C` reports them; no accounting, no
#      cgroups, no systemd);
#   3. submits two sweeps at once: cases/sweeps/fast-flat.ron (6 points, 2 of them
#      invalid) as a job array of 3 tasks of 2 points (`--shard-size 2`), and
#      cases/sweeps/fast-3d.ron (one point of the coarse 3-D cell, meshed by gmsh in the
#      task, into a cache of its own) as an array of one task; checks that each batch
#      script asks for an estimated --time and --mem; waits for both (10 min at most),
#      then `cellsim sweep collect` on each;
#   4. runs the same sweeps without Slurm and checks that both sweep.csv of each are
#      identical except for the wall_seconds column (the wall time of each run, the one
#      value that depends on the run and not on the computation; every number is printed
#      with all its digits, so "identical" means the same doubles) and that every point's
#      timeseries.csv is byte for byte the same;
#   5. stops every daemon it started (on failure too) and removes the temporary directory.
#
# Prints the Slurm task logs and the daemons' logs when something fails.
# Environment: CARGO (default cargo), SLURM_TEST_TIMEOUT (seconds, default 600),
# SLURM_TEST_KEEP=1 keeps the temporary directory.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
t_start=$(date +%s)
log() { echo "slurm-test: $*"; }

# --- packages ----------------------------------------------------------------------------
sudo=""
[ "$(id -u)" = 0 ] || sudo=sudo
missing=""
for p in slurm-wlm munge; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" ||
        missing="$missing $p"
done
if [ -n "$missing" ]; then
    log "installing:$missing"
    $sudo apt-get update -qq
    # Debian's packages try to start their services; without an init system that only
    # prints a warning.
    $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        $missing >/dev/null
fi
PATH="$PATH:/usr/sbin:/sbin"
for c in munged slurmctld slurmd sbatch squeue sinfo scontrol scancel; do
    command -v "$c" >/dev/null || { log "$c not found after installing slurm-wlm and munge"; exit 1; }
done

# --- cellsim ----------------------------------------------------------------------------
${CARGO:-cargo} build --release --quiet
bin=$(realpath "${CARGO_TARGET_DIR:-target}/release/cellsim")

# --- the cluster -------------------------------------------------------------------------
tmp=$(mktemp -d /tmp/cellsim-slurm.XXXXXX)
mkdir -p "$tmp/munge" "$tmp/state" "$tmp/spool" "$tmp/log"
# munged wants its socket's directories searchable by everyone and writable by it only.
chmod 755 "$tmp" "$tmp/munge"
pids=()
job=""
ok=0

show_logs() {
    for f in "$tmp"/cluster-*/slurm/*.out; do
        [ -f "$f" ] && { echo "----- $f"; cat "$f"; }
    done
    for f in "$tmp"/log/*.log; do
        [ -f "$f" ] && { echo "----- $f (last 40 lines)"; tail -n 40 "$f"; }
    done
}

cleanup() {
    local rc=$?
    set +e
    if [ "$ok" != 1 ]; then
        log "FAILED (exit status $rc); logs:"
        show_logs
    fi
    if [ -n "$job" ]; then
        # shellcheck disable=SC2086 # the job ids, one word each
        timeout 10 scancel $job 2>/dev/null
        # Let the job's processes end before their slurmd does.
        for _ in $(seq 1 20); do
            [ -z "$(timeout 10 squeue -h -j "${job// /,}" 2>/dev/null)" ] && break
            sleep 0.5
        done
    fi
    # Daemons in the reverse order of their start: slurmd, slurmctld, munged.
    for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
        kill "${pids[i]}" 2>/dev/null
    done
    for p in "${pids[@]}"; do
        for _ in $(seq 1 50); do
            kill -0 "$p" 2>/dev/null || break
            sleep 0.1
        done
        kill -0 "$p" 2>/dev/null && kill -9 "$p" 2>/dev/null
        wait "$p" 2>/dev/null
    done
    if [ "${SLURM_TEST_KEEP:-0}" = 1 ]; then
        log "kept $tmp"
    else
        rm -rf "$tmp"
    fi
    exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# munged: a key of its own (mungekey is munge >= 0.5.14; dd otherwise).
key="$tmp/munge/munge.key"
mungekey --create --keyfile="$key" 2>/dev/null ||
    dd if=/dev/urandom of="$key" bs=1024 count=1 status=none
chmod 400 "$key"
socket="$tmp/munge/munge.socket"
munged --foreground --key-file="$key" --socket="$socket" \
    --pid-file="$tmp/munge/munged.pid" --log-file="$tmp/log/munged.log" \
    --seed-file="$tmp/munge/munged.seed" 2>"$tmp/log/munged-stderr.log" &
pids+=($!)
for _ in $(seq 1 50); do
    [ -S "$socket" ] && break
    sleep 0.1
done
munge --socket="$socket" -n </dev/null | unmunge --socket="$socket" >/dev/null ||
    { log "munged does not answer on $socket"; exit 1; }

# Two free TCP ports for slurmctld and slurmd (6817 and 6818 unless taken).
port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
port=6817
while ! { port_free "$port" && port_free $((port + 1)); }; do
    port=$((port + 2))
done

host=$(hostname -s)
user=$(id -un)
# The node as slurmd sees the hardware (CPUs, sockets, cores, threads), with RealMemory
# 80 % of what it sees (at most 8 GB), so that the node is never drained for having less
# and the batch scripts' estimated --mem fits.
conf=$(slurmd -C 2>/dev/null | grep -m1 '^NodeName=' || true)
hw=$(echo "$conf" | sed -e 's/^NodeName=[^ ]* //' -e 's/ *RealMemory=[0-9]*//' -e 's/ *UpTime=.*//')
[ -n "$hw" ] || hw="CPUs=$(nproc)"
mem=$(echo "$conf" | sed -n 's/.*RealMemory=\([0-9]*\).*/\1/p')
[ -n "$mem" ] || mem=$(awk '/^MemTotal:/ {print int($2 / 1024)}' /proc/meminfo)
mem=$((mem * 8 / 10))
((mem <= 8000)) || mem=8000
cat >"$tmp/slurm.conf" <<EOF
# Single-node test cluster written by scripts/slurm-test.sh.
ClusterName=cellsim-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
SwitchType=switch/none
MpiDefault=none
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
KillWait=5
MailProg=/bin/true
MinJobAge=300
NodeName=$host NodeAddr=127.0.0.1 $hw RealMemory=$mem State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$tmp/slurm.conf"

slurmctld -D -i -f "$SLURM_CONF" >"$tmp/log/slurmctld-stderr.log" 2>&1 &
pids+=($!)
slurmd -D -N "$host" -f "$SLURM_CONF" >"$tmp/log/slurmd-stderr.log" 2>&1 &
pids+=($!)

# The node idle within 60 s.
state=""
for _ in $(seq 1 120); do
    state=$(sinfo -h -n "$host" -o '%T' 2>/dev/null || true)
    [ "$state" = idle ] && break
    for p in "${pids[@]}"; do
        kill -0 "$p" 2>/dev/null || { log "a daemon (pid $p) exited"; exit 1; }
    done
    sleep 0.5
done
[ "$state" = idle ] || { log "node $host not idle after 60 s (state: '${state:-none}')"; exit 1; }
t_cluster=$(date +%s)
log "cluster up in $((t_cluster - t_start)) s: node $host ($hw), slurmctld on port $port"

# --- the sweeps on Slurm -----------------------------------------------------------------
# name, sweep file, shard size. The 3-D point meshes with gmsh into a cold cache of its own.
names=(flat 3d)
files=(cases/sweeps/fast-flat.ron cases/sweeps/fast-3d.ron)
sizes=(2 1)
export CELLSIM_CACHE="$tmp/cache"
jobs=()
t_submit=$(date +%s)
for i in "${!names[@]}"; do
    out=$("$bin" sweep "${files[i]}" --out "$tmp/cluster-${names[i]}" --slurm \
        --shard-size "${sizes[i]}" --submit)
    echo "$out"
    id=$(echo "$out" | sed -n 's/^submitted batch job \([0-9][0-9]*\)$/\1/p')
    [ -n "$id" ] || { log "no job id in the output of --submit"; exit 1; }
    jobs+=("$id")
    job="${jobs[*]}"
    script="$tmp/cluster-${names[i]}/sweep.sbatch"
    [ "$(grep -cE '^#SBATCH --(time|mem)=' "$script")" = 2 ] ||
        { log "$script: no estimated --time and --mem:"; cat "$script"; exit 1; }
    log "${files[i]}: job $id, asked $(grep -E '^#SBATCH --(time|mem)=' "$script" |
        sed 's/^#SBATCH //' | paste -sd' ' -)"
done

timeout=${SLURM_TEST_TIMEOUT:-600}
last=""
while :; do
    # All the arrays' tasks, finished ones included (kept MinJobAge = 300 s).
    tasks=$(squeue -h -j "$(echo "${jobs[*]}" | tr ' ' ,)" --states=all -o '%i %T %M %l' 2>/dev/null |
        sort -V || true)
    # Printed when a task's state changes (not its run time).
    line=$(echo "$tasks" | awk '{print $1, $2}' | tr '\n' ' ' | sed 's/ *$//')
    [ "$line" != "$last" ] && log "$(($(date +%s) - t_submit)) s: $line"
    last=$line
    if [ -n "$tasks" ] && ! echo "$tasks" | grep -qE ' (PENDING|CONFIGURING|RUNNING|COMPLETING|SUSPENDED|REQUEUED|RESIZING) '; then
        break
    fi
    if (($(date +%s) - t_submit > timeout)); then
        log "jobs ${jobs[*]} not done after $timeout s"
        exit 1
    fi
    sleep 1
done
t_done=$(date +%s)
n_tasks=$(echo "$tasks" | wc -l)
if echo "$tasks" | grep -vq ' COMPLETED '; then
    log "jobs ${jobs[*]}: some tasks did not complete:"
    echo "$tasks"
    exit 1
fi
for n in "${names[@]}"; do
    "$bin" sweep collect "$tmp/cluster-$n"
done

# --- the same sweeps without Slurm, and the comparison ------------------------------------
t_local=$(date +%s)
for i in "${!names[@]}"; do
    "$bin" sweep "${files[i]}" --out "$tmp/local-${names[i]}" --quiet
done
t_local_done=$(date +%s)

# sweep.csv without its wall_seconds column. Fields are split as CSV (a quoted field may
# hold commas).
without_wall() {
    awk '
    function split_csv(line, f,    n, i, c, q, cur) {
        n = 0; cur = ""; q = 0
        for (i = 1; i <= length(line); i++) {
            c = substr(line, i, 1)
            if (c == "\"") q = !q
            if (c == "," && !q) { f[++n] = cur; cur = "" } else cur = cur c
        }
        f[++n] = cur
        return n
    }
    {
        n = split_csv($0, f)
        if (NR == 1) for (i = 1; i <= n; i++) if (f[i] == "wall_seconds") k = i
        if (!k) { print "no wall_seconds column" > "/dev/stderr"; exit 1 }
        s = ""
        for (i = 1; i <= n; i++) if (i != k) s = s (s == "" ? "" : ",") f[i]
        print s
    }' "$1"
}
rows=0
series=0
for n in "${names[@]}"; do
    without_wall "$tmp/cluster-$n/sweep.csv" >"$tmp/cluster-$n.csv"
    without_wall "$tmp/local-$n/sweep.csv" >"$tmp/local-$n.csv"
    rows=$((rows + $(wc -l <"$tmp/local-$n.csv") - 1))
    finished=$(grep -c ',finished,' "$tmp/local-$n.csv" || true)
    if ! diff -u "$tmp/local-$n.csv" "$tmp/cluster-$n.csv"; then
        log "$n: sweep.csv differs between the local run (-) and the Slurm array (+)"
        exit 1
    fi
    compared=0
    for f in "$tmp/local-$n"/points/*/timeseries.csv; do
        g="$tmp/cluster-$n/points/$(basename "$(dirname "$f")")/timeseries.csv"
        cmp -s "$f" "$g" || { log "$g differs from $f"; exit 1; }
        compared=$((compared + 1))
    done
    [ "$finished" -gt 0 ] && [ "$compared" = "$finished" ] ||
        { log "$n: expected $finished timeseries.csv, compared $compared"; exit 1; }
    series=$((series + compared))
done

ok=1
log "summary:"
echo "  jobs ${jobs[*]}: $n_tasks array tasks (state, run time, time limit: $(echo "$tasks" | awk '{print $1 " " $2 " " $3 " " $4}' | paste -sd, - | sed 's/,/, /g'))"
echo "  arrays: $((t_done - t_submit)) s from submission to the last task's end; local runs: $((t_local_done - t_local)) s"
echo "  sweep.csv: $rows rows identical to the local runs' except wall_seconds;" \
    "$series timeseries.csv identical"
echo "  total: $(($(date +%s) - t_start)) s (cluster start $((t_cluster - t_start)) s)"
