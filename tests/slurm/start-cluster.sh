#!/usr/bin/env bash
# Starts a one-node Slurm cluster on localhost for tests/slurm.rs: munged, slurmctld and
# slurmd, no cgroups (ProctrackType=proctrack/linuxproc, TaskPlugin=task/none, no
# cgroup.conf), the node's CPUs and memory as this machine has them. Idempotent: a cluster
# already answering is left alone. Needs root (run through sudo by tests/run.sh).
set -euo pipefail

if sinfo -h -o %T 2>/dev/null | grep -q -E "idle|mix|alloc"; then
    echo "slurm: a cluster is already running"
    exit 0
fi

conf=/etc/slurm/slurm.conf
cpus=$(nproc)
memory=$(($(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 - 512))
mkdir -p /etc/slurm /var/spool/slurmctld /var/spool/slurmd /var/log/slurm /run/munge
cat >"$conf" <<CONF
# Written by hprt's tests/slurm/start-cluster.sh: a one-node test cluster.
ClusterName=hprt-test
SlurmctldHost=localhost
SlurmUser=root
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MinJobAge=3600
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
NodeName=localhost CPUs=$cpus RealMemory=$memory State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF

# munge: a key readable by its user only, the daemon run as that user.
if [ ! -s /etc/munge/munge.key ]; then
    dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
fi
chown -R munge:munge /etc/munge /run/munge /var/lib/munge /var/log/munge 2>/dev/null || true
chmod 0400 /etc/munge/munge.key
if ! pgrep -x munged >/dev/null; then
    runuser -u munge -- /usr/sbin/munged
fi

pgrep -x slurmctld >/dev/null || /usr/sbin/slurmctld
pgrep -x slurmd >/dev/null || /usr/sbin/slurmd

for _ in $(seq 1 60); do
    if sinfo -h -o %T 2>/dev/null | grep -q -E "idle|mix|alloc"; then
        scontrol update nodename=localhost state=resume >/dev/null 2>&1 || true
        echo "slurm: one-node cluster up ($cpus CPUs)"
        exit 0
    fi
    sleep 1
done
echo "slurm: the cluster did not come up; its logs:" >&2
tail -n 20 /var/log/slurm/slurmctld.log /var/log/slurm/slurmd.log >&2 || true
exit 1
