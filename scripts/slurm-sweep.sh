#!/usr/bin/env bash
# Runs a `jointsim batch` sweep (docs/batch.md) as a Slurm job array: task I of N runs
#   jointsim batch SWEEP.yaml -j CPUS --shard I/N -o OUTDIR
# then, once every task has ended, `jointsim batch SWEEP.yaml --collect -o OUTDIR` rebuilds OUTDIR/manifest.csv.
# OUTDIR must be on a file system that the compute nodes share with this machine.
#
# Usage: scripts/slurm-sweep.sh SWEEP.yaml -o OUTDIR [options] [-- SBATCH_ARGS...]
#   -o, --output-dir DIR     output folder of the sweep (required); Slurm's task logs go to DIR/slurm-logs/
#                            (any path without a backslash, which Slurm's --output cannot express)
#   -n, --shards N           array tasks (default 4; at most the number of runs)
#   -c, --cpus-per-task C    CPUs per task = runs at a time in each task (jointsim batch -j C; default 1)
#   -J, --job-name NAME      job name (default jointsim-<sweep name>): 1 to 128 letters, digits, '.', '-', '_',
#                            not starting with '.' or '-' (it names the files DIR/slurm-logs/NAME.sbatch, NAME-*.out)
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
unset CDPATH                          # (cd DIR must not print or go to a CDPATH folder)

usage() { sed -n '2,/^set -euo/{/^set -euo/d;s/^# \{0,1\}//;p}' "$0"; exit "${1:-2}"; }
log() { echo "slurm-sweep: $*" >&2; }
die() { local code="$1"; shift; log "$*"; exit "$code"; }

src="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
sweep="" outdir="" shards=4 cpus=1 name="" name_given=0 jointsim="${JOINTSIM:-}" wait=1 poll=2
extra=()
# An option's value: present and not empty (else exit 2, as for any bad argument; bash's ${2:?} exits 1).
need() { [ "$1" -ge 2 ] && [ -n "$3" ] || die 2 "$2 needs a value"; }
while [ $# -gt 0 ]; do
  case "$1" in   # --opt=VALUE as --opt VALUE (split at the first '=': --sbatch-arg=--time=1:00:00 keeps its own)
    --output-dir=*|--shards=*|--cpus-per-task=*|--job-name=*|--jointsim=*|--sbatch-arg=*|--poll=*)
      set -- "${1%%=*}" "${1#*=}" "${@:2}" ;;
  esac
  case "$1" in
    -o|--output-dir) need $# "$1" "${2-}"; outdir="$2"; shift ;;
    -n|--shards) need $# "$1" "${2-}"; shards="$2"; shift ;;
    -c|--cpus-per-task) need $# "$1" "${2-}"; cpus="$2"; shift ;;
    -J|--job-name) need $# "$1" "${2-}"; name="$2" name_given=1; shift ;;
    --jointsim) need $# "$1" "${2-}"; jointsim="$2"; shift ;;
    --sbatch-arg) need $# "$1" "${2-}"; extra+=("$2"); shift ;;
    --wait) wait=1 ;;
    --no-wait) wait=0 ;;
    --poll) need $# "$1" "${2-}"; poll="$2"; shift ;;
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

# A safe name (the rule of jointsim's sweep and run names): 1 to 128 letters, digits, '.', '-', '_', not starting
# with '.' or '-'. The job name becomes a file name (OUTDIR/slurm-logs/NAME.sbatch, and %x in the task logs'
# names): anything else could leave the output folder (-J ../../x) or change the name (%, /). (LC_ALL=C: in other
# locales [A-Za-z] may match more than ASCII letters.)
safe_name() { local LC_ALL=C; [[ "$1" =~ ^[A-Za-z0-9_][A-Za-z0-9._-]{0,127}$ ]]; }
if [ "$name_given" = 1 ] && ! safe_name "$name"; then
  die 2 "-J/--job-name must be 1 to 128 letters, digits, '.', '-', '_', not starting with '.' or '-':" \
    "$(printf %q "$name")"
fi
[ -f "$sweep" ] || die 2 "no sweep file $sweep"

# The output folder as the tasks will see it: absolute (they start elsewhere, possibly on another machine), with
# . and .. resolved as cd would. Slurm's --output is a file name pattern in which % is special (escaped below) and
# in which a backslash anywhere turns every pattern off and is dropped, so a folder with a backslash cannot be
# given to Slurm: refused before anything is written.
# (Relative to $PWD, the logical working directory, as cd would; `&& echo .`: keep a trailing newline of a name.)
case "$outdir" in /*) ;; *) outdir="$PWD/$outdir" ;; esac
outdir="$(realpath -m -s -- "$outdir" && echo .)" || die 2 "-o/--output-dir: no usable path $(printf %q "$outdir")"
outdir="${outdir%$'\n.'}"
case "$outdir" in
  *\\*) die 2 "-o/--output-dir: Slurm cannot write task logs below a path with a backslash: $(printf %q "$outdir")" ;;
esac
command -v sbatch >/dev/null && command -v squeue >/dev/null || die 3 "sbatch/squeue not found (Slurm clients)"

# Absolute paths: the tasks start in another directory, possibly on another machine.
sweep="$(cd "$(dirname "$sweep")" && pwd)/$(basename "$sweep")"
mkdir -p -- "$outdir/slurm-logs"
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

# The runs of OUTDIR/manifest.csv, one line "RUN<US>STATUS" per run in manifest order (US: the unit separator
# \037; control characters of those two fields, US included, shown as '?'). The manifest is RFC 4180 CSV: any
# field may be quoted, and a quoted field may hold commas, doubled quotes and newlines (an override value with a
# newline, a joint name with a comma), so a line is not a record. A record ends at the end of a line with an even
# number of quotes up to there (a "" pair inside a quoted field counts 2); only the fields up to run and status
# (found by name in the header) are split. Fails (status 1, a message on stderr) when the file is no such CSV.
# awk only: no Python on the submit host.
manifest_runs() {
  awk '
    function split_csv(rec, need, f,   n, i, len, c, q, cur) {   # fields 1..need of a record into f
      n = 0; cur = ""; q = 0; len = length(rec)
      for (i = 1; i <= len; i++) {
        c = substr(rec, i, 1)
        if (q) {
          if (c == "\"") { if (substr(rec, i + 1, 1) == "\"") { cur = cur c; i++ } else q = 0 }
          else cur = cur c
        } else if (c == "\"") q = 1
        else if (c == ",") { f[++n] = cur; cur = ""; if (n >= need) return n }
        else cur = cur c
      }
      f[++n] = cur
      return n
    }
    function shown(s) { gsub(/[[:cntrl:]]/, "?", s); return s }
    { rec = open ? rec "\n" $0 : $0
      if (gsub(/"/, "\"") % 2) open = !open   # (gsub counts the quotes of this line)
      if (open) next                         # the record goes on in the next line
      sub(/\r$/, "", rec)                    # (CRLF line ends)
      if (rec == "") next
      if (!header) {
        header = 1; n = split_csv(rec, 1e9, h)
        for (i = 1; i <= n; i++) { if (h[i] == "run" && !rc) rc = i; if (h[i] == "status" && !sc) sc = i }
        if (!rc || !sc) { print "no run and status columns in the header: " rec > "/dev/stderr"; bad = 1; exit 1 }
        need = rc > sc ? rc : sc
        next
      }
      delete f; split_csv(rec, need, f)
      print shown(f[rc]) "\037" shown(f[sc]) }
    END {
      if (bad) exit 1
      if (open) { print "a quoted field is not closed at the end of the file" > "/dev/stderr"; exit 1 }
      if (!header) { print "no header" > "/dev/stderr"; exit 1 }
    }' "$1"
}

# Reads OUTDIR/manifest.csv into total (its number of runs) and the arrays bad_runs and bad_status (the runs whose
# status is not ok). (US, not a tab, between the fields: read keeps an empty field then.)
read_manifest() {
  local out run status
  out="$(manifest_runs "$outdir/manifest.csv")" || return 1
  total=0 bad_runs=() bad_status=()
  [ -n "$out" ] || return 0
  while IFS=$'\037' read -r run status; do
    total=$((total + 1))
    [ "$status" = ok ] || { bad_runs+=("$run"); bad_status+=("$status"); }
  done <<<"$out"
}

collect || die 2 "bad sweep file $sweep (see above)"
read_manifest || die 2 "cannot read $outdir/manifest.csv as CSV (see above)"
runs="$total"
[ "$runs" -ge 1 ] || die 2 "sweep $sweep has no runs"
if [ "$shards" -gt "$runs" ]; then
  log "$runs runs: using $runs array tasks instead of $shards"
  shards="$runs"
fi
if [ "$name_given" = 0 ]; then   # the sweep's name (`name:` in its `sweep:` block), else the file name
  name="$(awk '/^sweep:/ { s = 1; next } s && /^[^ #]/ { s = 0 } s && $1 == "name:" { gsub(/["\x27]/, "", $2); print $2; exit }' "$sweep")"
  name="jointsim-${name:-$(basename "$sweep" .yaml)}"
  # Made safe (see safe_name; the file name may hold anything): other characters as '_', at most 128.
  name="$(LC_ALL=C; n="${name//[^A-Za-z0-9._-]/_}"; echo "${n:0:128}")"
fi
safe_name "$name" || die 2 "job name $(printf %q "$name") not safe (pass -J NAME)"   # (cannot happen)

# The batch script of every task. exec: jointsim batch is the task's main process and gets Slurm's SIGTERM on
# scancel or at the time limit, forwards it to its runs, which end as "interrupted" and resume on resubmission.
script="$outdir/slurm-logs/$name.sbatch"
{
  echo "#!/bin/bash"
  echo "# Written by scripts/slurm-sweep.sh: task I of the array runs shard I/$shards of the sweep."
  printf 'exec %q batch %q -j %q --shard "${SLURM_ARRAY_TASK_ID}/%q" -o %q\n' \
    "$jointsim" "$sweep" "$cpus" "$shards" "$outdir"
} >"$script"

# --output is a file name pattern (%x job name, %A job, %a task; "%%" is a literal %): a % of the folder doubled, or
# Slurm would expand it (OUTDIR a%jb: logs into a<jobid>b/, which does not exist, and every task fails to start).
# --chdir is a plain path. (A backslash, which no pattern can express, was refused above.)
submitted="$(sbatch --parsable --job-name="$name" --array="0-$((shards - 1))" --cpus-per-task="$cpus" \
  --ntasks=1 --nodes=1 --chdir="$outdir" --output="${outdir//%/%%}/slurm-logs/%x-%A_%a.out" \
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
# With Slurm's reason, e.g. "12_0 FAILED (JobLaunchFailure)" when a task could not even start.
ended="$(squeue -h -j "$jobid" -t all -o '%i %T %r' 2>/dev/null \
  | awk '$2 != "COMPLETED" { r = $0; sub(/^[^ ]+ [^ ]+ */, "", r)
                            print $1, $2 (r == "" || r == "None" ? "" : " (" r ")") }' \
  || true)"
[ -z "$ended" ] || log "tasks that did not complete: $(tr '\n' ';' <<<"$ended" | sed 's/;$//; s/;/; /g')"

collect || die 1 "jointsim batch --collect -o $outdir failed"
manifest="$outdir/manifest.csv"
read_manifest || die 1 "cannot read $manifest as CSV (see above)"
if [ "${#bad_runs[@]}" -gt 0 ]; then
  log "${#bad_runs[@]} of $total runs not ok (resubmit the same command to resume them):"
  for i in "${!bad_runs[@]}"; do
    run="${bad_runs[i]}" status="${bad_status[i]}"
    # With the last line of the run's log, if it has one (only below OUTDIR: run names are safe names); a run
    # still pending was started by no task (see the task logs, and the reasons above).
    last=""
    if safe_name "$run"; then last="$(tail -n 1 "$outdir/$run/run.log" 2>/dev/null || true)"; fi
    if [ -n "$last" ]; then
      echo "  $run: $status ($run/run.log: $last)" >&2
    elif [ "$status" = pending ]; then
      echo "  $run: pending (not started; see the task logs in $outdir/slurm-logs/)" >&2
    else
      echo "  $run: $status" >&2
    fi
  done
  exit 1
fi
log "all $total runs ok: $manifest"
