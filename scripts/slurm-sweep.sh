#!/usr/bin/env bash
# Runs a `jointsim batch` sweep (docs/batch.md) as a Slurm job array: task I of N runs
#   jointsim batch SWEEP.yaml -j CPUS --shard I/N -o OUTDIR
# then, once every task has ended, `jointsim batch SWEEP.yaml --collect -o OUTDIR` rebuilds OUTDIR/manifest.csv.
# OUTDIR must be on a file system that the compute nodes share with this machine.
#
# Usage: scripts/slurm-sweep.sh SWEEP.yaml -o OUTDIR [options] [-- SBATCH_ARGS...]
#   -o, --output-dir DIR     output folder of the sweep (required); Slurm's task logs go to DIR/slurm-logs/
#   -n, --shards N           array tasks (default 4; at most the number of runs)
#   -c, --cpus-per-task C    CPUs per task = runs at a time in each task (jointsim batch -j C; default 1)
#   -J, --job-name NAME      job name (default jointsim-<sweep name>)
#   --jointsim PATH          jointsim executable (default: $JOINTSIM, else `jointsim` on PATH, else
#                            build/jointsim of this checkout); must be reachable from the compute nodes
#   --sbatch-arg ARG         one extra sbatch argument (repeatable), e.g. --sbatch-arg=--time=01:00:00;
#                            SBATCH_ARGS after `--` are passed as well (after ours, so they take precedence)
#   --wait                   wait for the array, collect and check (the default)
#   --no-wait                only submit: print the job ID on stdout and exit; collect later with
#                            `jointsim batch SWEEP.yaml --collect -o OUTDIR` (or run this script again)
#   --poll SECONDS           squeue polling interval while waiting (default 2)
#   -h, --help               this text
#
# Exit status (waiting): 0 when every run of the collected manifest has status ok; 1 when some have not (they
# are listed; submitting the same command again resumes: runs already ok are skipped, the rest run again);
# 2 for bad arguments or a bad sweep file; 3 when Slurm fails (submission, squeue unreachable); 130/143 when
# interrupted, which also cancels the array (its runs end as "interrupted" and are repeated on resubmission).
#
# The cluster is whatever the Slurm clients find (SLURM_CONF or /etc/slurm/slurm.conf); for a private test
# cluster see scripts/slurm-cluster.sh. Waiting polls `squeue -j JOBID` (no accounting/sacct needed).
set -euo pipefail

usage() { sed -n '2,/^set -euo/{/^set -euo/d;s/^# \{0,1\}//;p}' "$0"; exit "${1:-2}"; }
log() { echo "slurm-sweep: $*" >&2; }
die() { local code="$1"; shift; log "$*"; exit "$code"; }

src="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
sweep="" outdir="" shards=4 cpus=1 name="" jointsim="${JOINTSIM:-}" wait=1 poll=2
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    -o|--output-dir) outdir="${2:?$1 needs a value}"; shift ;;
    --output-dir=*) outdir="${1#*=}" ;;
    -n|--shards) shards="${2:?$1 needs a value}"; shift ;;
    --shards=*) shards="${1#*=}" ;;
    -c|--cpus-per-task) cpus="${2:?$1 needs a value}"; shift ;;
    --cpus-per-task=*) cpus="${1#*=}" ;;
    -J|--job-name) name="${2:?$1 needs a value}"; shift ;;
    --job-name=*) name="${1#*=}" ;;
    --jointsim) jointsim="${2:?$1 needs a value}"; shift ;;
    --jointsim=*) jointsim="${1#*=}" ;;
    --sbatch-arg) extra+=("${2:?$1 needs a value}"); shift ;;
    --sbatch-arg=*) extra+=("${1#*=}") ;;
    --wait) wait=1 ;;
    --no-wait) wait=0 ;;
    --poll) poll="${2:?$1 needs a value}"; shift ;;
    --poll=*) poll="${1#*=}" ;;
    -h|--help) usage 0 ;;
    --) shift; extra+=("$@"); break ;;
    -*) log "unknown option $1"; usage ;;
    *) [ -z "$sweep" ] || { log "more than one sweep file: $sweep $1"; usage; }; sweep="$1" ;;
  esac
  shift
done
[ -n "$sweep" ] && [ -n "$outdir" ] || usage
[[ "$shards" =~ ^[1-9][0-9]*$ ]] || die 2 "-n must be a positive integer, not '$shards'"
[[ "$cpus" =~ ^[1-9][0-9]*$ ]] || die 2 "-c must be a positive integer, not '$cpus'"
[[ "$poll" =~ ^[0-9]+(\.[0-9]+)?$ ]] || die 2 "--poll must be a number of seconds, not '$poll'"
[ -f "$sweep" ] || die 2 "no sweep file $sweep"
command -v sbatch >/dev/null && command -v squeue >/dev/null || die 3 "sbatch/squeue not found (Slurm clients)"

# Absolute paths: the tasks start in another directory, possibly on another machine.
sweep="$(cd "$(dirname "$sweep")" && pwd)/$(basename "$sweep")"
mkdir -p "$outdir/slurm-logs"
outdir="$(cd "$outdir" && pwd)"
if [ -z "$jointsim" ]; then
  jointsim="$(command -v jointsim || echo "$src/build/jointsim")"
fi
case "$jointsim" in */*) jointsim="$(cd "$(dirname "$jointsim")" && pwd)/$(basename "$jointsim")" ;;
                     *) jointsim="$(command -v "$jointsim" || echo "$jointsim")" ;; esac
[ -x "$jointsim" ] || die 2 "no jointsim executable at $jointsim (build it or pass --jointsim)"

# Check the sweep before it waits in a queue: --collect parses it (exit 2 if bad), runs nothing, and writes
# OUTDIR/manifest.csv with every run (finished ones of an earlier submission included), which gives the count.
# (--collect exits 0, or 1 when some collected run failed, and 2 for a bad sweep file.)
collect() {
  local rc=0
  "$jointsim" batch "$sweep" --collect -o "$outdir" >/dev/null || rc=$?
  [ "$rc" -le 1 ] && [ -s "$outdir/manifest.csv" ] || return 2
}
collect || die 2 "bad sweep file $sweep (see above)"
runs=$(($(wc -l <"$outdir/manifest.csv") - 1))
[ "$runs" -ge 1 ] || die 2 "sweep $sweep has no runs"
if [ "$shards" -gt "$runs" ]; then
  log "$runs runs: using $runs array tasks instead of $shards"
  shards="$runs"
fi
if [ -z "$name" ]; then   # the sweep's name (`name:` in its `sweep:` block), else the file name
  name="$(awk '/^sweep:/ { s = 1; next } s && /^[^ #]/ { s = 0 } s && $1 == "name:" { gsub(/["\x27]/, "", $2); print $2; exit }' "$sweep")"
  name="jointsim-${name:-$(basename "$sweep" .yaml)}"
fi

# The batch script of every task. exec: jointsim batch is the task's main process and gets Slurm's SIGTERM on
# scancel or at the time limit, forwards it to its runs, which end as "interrupted" and resume on resubmission.
script="$outdir/slurm-logs/$name.sbatch"
{
  echo "#!/bin/bash"
  echo "# Written by scripts/slurm-sweep.sh: task I of the array runs shard I/$shards of the sweep."
  printf 'exec %q batch %q -j %q --shard "${SLURM_ARRAY_TASK_ID}/%q" -o %q\n' \
    "$jointsim" "$sweep" "$cpus" "$shards" "$outdir"
} >"$script"

submitted="$(sbatch --parsable --job-name="$name" --array="0-$((shards - 1))" --cpus-per-task="$cpus" \
  --ntasks=1 --nodes=1 --chdir="$outdir" --output="$outdir/slurm-logs/%x-%A_%a.out" \
  ${extra[@]+"${extra[@]}"} "$script")" || die 3 "sbatch failed"
jobid="${submitted%%;*}"                # --parsable prints JOBID or JOBID;CLUSTER
[[ "$jobid" =~ ^[0-9]+$ ]] || die 3 "unexpected sbatch output '$submitted'"
log "submitted job array $jobid: $runs runs in $shards tasks of $cpus CPU(s); logs in $outdir/slurm-logs/"
if [ "$wait" = 0 ]; then
  echo "$jobid"
  exit 0
fi

# Interrupted while waiting: cancel the array (the runs stop as "interrupted"; resubmitting resumes them).
cancel() {
  log "interrupted: cancelling job array $jobid"
  scancel "$jobid" 2>/dev/null || true
  exit "$1"
}
trap 'cancel 130' INT
trap 'cancel 143' TERM

# Wait until squeue lists no unfinished task of the array (by default squeue -j shows pending, running,
# completing, ... tasks but not ended ones; a job purged after MinJobAge is an "Invalid job id").
failing_since="" last=""
while :; do
  if out="$(squeue -h -j "$jobid" -o %T 2>&1)"; then
    failing_since=""
    [ -n "$out" ] || break
    now="$(sort <<<"$out" | uniq -c | awk '{printf "%s%s %s", (NR > 1 ? ", " : ""), $1, tolower($2)}')"
    [ "$now" = "$last" ] || log "job $jobid: $now"
    last="$now"
  elif grep -qi "invalid job id" <<<"$out"; then
    break
  else                                    # slurmctld unreachable: give it 2 minutes (a restart, a fail-over)
    failing_since="${failing_since:-$SECONDS}"
    [ $((SECONDS - failing_since)) -lt 120 ] || die 3 "squeue has failed for 2 minutes: $out"
  fi
  sleep "$poll" & wait $!                 # (in the background, so that a signal is handled at once)
done
trap - INT TERM

# How each task ended, while slurmctld still remembers (MinJobAge); for information only, the manifest decides.
ended="$(squeue -h -j "$jobid" -t all -o '%i %T' 2>/dev/null | grep -v ' COMPLETED$' || true)"
[ -z "$ended" ] || log "tasks that did not complete: $(tr '\n' ';' <<<"$ended" | sed 's/;$//; s/;/; /g')"

collect || die 1 "jointsim batch --collect -o $outdir failed"
manifest="$outdir/manifest.csv"
# Run names are folder-safe (no commas or quotes) and status is the second column.
bad="$(awk -F, 'NR > 1 && $2 != "ok" { print $1, $2 }' "$manifest")"
total=$(($(wc -l <"$manifest") - 1))
if [ -n "$bad" ]; then
  log "$(wc -l <<<"$bad") of $total runs not ok (resubmit the same command to resume them):"
  while read -r run status; do   # with the last line of the run's log, if it has one
    last="$(tail -n 1 "$outdir/$run/run.log" 2>/dev/null || true)"
    echo "  $run: $status${last:+ ($run/run.log: $last)}" >&2
  done <<<"$bad"
  exit 1
fi
log "all $total runs ok: $manifest"
