#!/usr/bin/env bash
# A single-node Slurm cluster on this machine, for tests and demos (Debian/Ubuntu, as root).
#
#   scripts/slurm/local-cluster.sh up       install slurm-wlm + munge if missing, write the
#                                           config, start munged, slurmctld, slurmd; wait until
#                                           the node takes jobs. Idempotent.
#   scripts/slurm/local-cluster.sh down     stop the daemons this script started and remove the
#                                           config it wrote (packages stay installed).
#   scripts/slurm/local-cluster.sh status   what runs, and sinfo.
#
# The node is this host with all its CPUs (ProctrackType=proctrack/linuxproc, TaskPlugin=task/none,
# no cgroups, no accounting), one partition "debug". State, logs and pid files live in
# $MOMENTLAB_SLURM_STATE (default /var/tmp/momentlab-slurm). An existing Slurm configuration that
# this script did not write is never touched: if it works, `up` just uses it.
# apt runs under `flock /tmp/apt.lock` so that parallel installers do not collide.
set -euo pipefail

STATE=${MOMENTLAB_SLURM_STATE:-/var/tmp/momentlab-slurm}
CONF=/etc/slurm/slurm.conf
MARK="# written by momentlab scripts/slurm/local-cluster.sh"
PKGS=(slurmctld slurmd slurm-client munge)

log() { echo "local-cluster: $*" >&2; }
die() { log "error: $*"; exit 1; }

need_root() { [ "$(id -u)" = 0 ] || die "run as root (it installs packages and starts daemons)"; }

pid_alive() { [ -f "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }

our_conf() { [ -f "$CONF" ] && head -n 1 "$CONF" | grep -qF "$MARK"; }

cluster_works() {
    command -v sinfo >/dev/null 2>&1 && timeout 10 scontrol ping 2>/dev/null | grep -q UP &&
        [ -n "$(timeout 10 sinfo -h -o '%T' 2>/dev/null | grep -E '^(idle|mixed|allocated)' | head -n 1)" ]
}

install() {
    local missing=()
    command -v slurmctld >/dev/null || missing+=(slurmctld)
    command -v slurmd >/dev/null || missing+=(slurmd)
    command -v sbatch >/dev/null || missing+=(slurm-client)
    command -v munged >/dev/null || missing+=(munge)
    [ ${#missing[@]} = 0 ] && return 0
    command -v apt-get >/dev/null || die "missing ${missing[*]} and no apt-get to install them"
    log "installing ${PKGS[*]} (apt, under flock /tmp/apt.lock)"
    export DEBIAN_FRONTEND=noninteractive
    if ! flock /tmp/apt.lock apt-get install -y -qq --no-install-recommends "${PKGS[@]}" >"$STATE/apt.log" 2>&1; then
        log "apt-get install failed; running apt-get update once and retrying"
        flock /tmp/apt.lock apt-get update -qq >>"$STATE/apt.log" 2>&1 || die "apt-get update failed (see $STATE/apt.log)"
        flock /tmp/apt.lock apt-get install -y -qq --no-install-recommends "${PKGS[@]}" >>"$STATE/apt.log" 2>&1 ||
            die "apt-get install ${PKGS[*]} failed (see $STATE/apt.log)"
    fi
}

start_munge() {
    if echo x | munge 2>/dev/null | unmunge >/dev/null 2>&1; then
        return 0 # a working munged (ours from an earlier `up`, or the system's)
    fi
    [ -s /etc/munge/munge.key ] || {
        log "creating /etc/munge/munge.key"
        if command -v mungekey >/dev/null; then mungekey --create --keyfile=/etc/munge/munge.key; else
            dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key 2>/dev/null; fi
        chown munge:munge /etc/munge/munge.key
        chmod 600 /etc/munge/munge.key
    }
    mkdir -p /run/munge /var/log/munge /var/lib/munge
    chown munge:munge /run/munge /var/log/munge /var/lib/munge
    log "starting munged"
    runuser -u munge -- /usr/sbin/munged --pid-file=/run/munge/munged.pid
    cp /run/munge/munged.pid "$STATE/munged.pid"
    for _ in $(seq 50); do
        echo x | munge 2>/dev/null | unmunge >/dev/null 2>&1 && return 0
        sleep 0.1
    done
    die "munged does not answer (see /var/log/munge/munged.log)"
}

write_conf() {
    local node host
    host=$(hostname -s)
    # slurmd -C: this machine's NodeName line (CPUs, sockets, cores, threads, RealMemory).
    node=$(slurmd -C | head -n 1)
    [[ "$node" == NodeName=* ]] || die "slurmd -C gave no node line: $node"
    mkdir -p /etc/slurm "$STATE/ctld" "$STATE/d"
    cat >"$CONF.tmp" <<EOF
$MARK
# Single-node test cluster; \`local-cluster.sh down\` removes this file.
ClusterName=momentlab
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
StateSaveLocation=$STATE/ctld
SlurmdSpoolDir=$STATE/d
SlurmctldPidFile=$STATE/slurmctld.pid
SlurmdPidFile=$STATE/slurmd.pid
SlurmctldLogFile=$STATE/slurmctld.log
SlurmdLogFile=$STATE/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/backfill
SchedulerParameters=bf_interval=2,sched_min_interval=200000
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
KillWait=5
MinJobAge=3600
InactiveLimit=0
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
    mv "$CONF.tmp" "$CONF"
}

up() {
    need_root
    mkdir -p "$STATE"
    if [ -f "$CONF" ] && ! our_conf; then
        cluster_works && { log "a Slurm cluster configured elsewhere ($CONF) is up; using it"; return 0; }
        die "$CONF exists and was not written by this script; not touching it"
    fi
    install
    start_munge
    write_conf
    if ! pid_alive "$STATE/slurmctld.pid"; then
        log "starting slurmctld"
        slurmctld || die "slurmctld did not start (see $STATE/slurmctld.log)"
    fi
    if ! pid_alive "$STATE/slurmd.pid"; then
        log "starting slurmd"
        slurmd || die "slurmd did not start (see $STATE/slurmd.log)"
    fi
    for _ in $(seq 60); do
        if cluster_works; then
            log "up: $(sinfo -h -o '%P %D node(s) %c CPUs %T' | head -n 1)"
            return 0
        fi
        # A node left down by an earlier run comes back here.
        scontrol update nodename="$(hostname -s)" state=resume >/dev/null 2>&1 || true
        sleep 1
    done
    die "the node does not become idle (see $STATE/slurmctld.log, $STATE/slurmd.log)"
}

stop_pid() { # name pidfile
    if pid_alive "$2"; then
        log "stopping $1"
        kill "$(cat "$2")" || true
        for _ in $(seq 50); do pid_alive "$2" || break; sleep 0.1; done
        pid_alive "$2" && kill -9 "$(cat "$2")" 2>/dev/null || true
    fi
    rm -f "$2"
}

down() {
    need_root
    if ! our_conf; then
        log "no cluster of this script to stop ($CONF not ours or absent)"
        return 0
    fi
    stop_pid slurmd "$STATE/slurmd.pid"
    stop_pid slurmctld "$STATE/slurmctld.pid"
    stop_pid munged "$STATE/munged.pid"
    rm -f "$CONF"
    rm -rf "$STATE/ctld" "$STATE/d"
    log "down (packages stay installed; logs in $STATE)"
}

status() {
    for d in munged slurmctld slurmd; do
        if pid_alive "$STATE/$d.pid"; then echo "$d: running (pid $(cat "$STATE/$d.pid"), started by this script)"; else echo "$d: not started by this script"; fi
    done
    if cluster_works; then sinfo; else echo "cluster: not answering"; return 1; fi
}

case "${1:-}" in
up) up ;;
down) down ;;
status) status ;;
*) echo "usage: $0 up|down|status" >&2; exit 2 ;;
esac
