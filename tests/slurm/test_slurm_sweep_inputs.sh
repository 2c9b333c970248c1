#!/usr/bin/env bash
# scripts/slurm-sweep.sh with hostile input (issue 26), without a cluster: fake sbatch, squeue and scancel on PATH
# (sbatch records its arguments and prints a job ID; squeue shows the array as ended) and a fake jointsim whose
# --collect writes a crafted OUTDIR/manifest.csv. Checks:
#   a. the manifest is read as RFC 4180 CSV: quoted fields with commas, doubled quotes, newlines (an override) and
#      CRLF line ends are one record each: the runs are counted right (shards, "all N runs ok", exit 0), and the
#      runs not ok are listed exactly (exit 1); a manifest that is no CSV is refused; a run name that is not a
#      safe name never makes the script read a file outside OUTDIR;
#   b. a % in the output folder is doubled in sbatch's --output (a file name pattern: "%%" is a literal %) and
#      kept in --chdir (a plain path); a folder with a backslash (no pattern can express it) is refused (exit 2),
#      nothing written, nothing submitted;
#   c. a job name that is not a safe name (-J ../../x, .x, a%x, a/b, 129 characters, empty, missing) is refused
#      with one line naming the option, exit 2, before anything is written or submitted; the default name made
#      from an unsafe file name is made safe.
# Whether Slurm itself then writes the task logs into such a folder: tests/slurm/test_slurm_sweep.sh (steps f-h).
# Usage: tests/slurm/test_slurm_sweep_inputs.sh [REPOSITORY_ROOT]
# Prints one PASS/FAIL line per check and exits 1 if any failed. About 2 s. KEEP_TMP=1 keeps the temporary folder.
set -uo pipefail

[ $# -le 1 ] || { sed -n '2,/^set -uo/{/^set -uo/d;s/^# \{0,1\}//;p}' "$0" >&2; exit 2; }
repo="$(cd "${1:-$(dirname "$0")/../..}" && pwd)"
sweep_sh="$repo/scripts/slurm-sweep.sh"

failures=0
pass() { echo "PASS: $*"; }
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
check() { local what="$1"; shift; if "$@"; then pass "$what"; else fail "$what"; fi; }

tmp="$(mktemp -d "${TMPDIR:-/tmp}/jointsim_slurm_inputs.XXXXXX")"
tmp="$(cd "$tmp" && pwd)"
cleanup() { if [ "${KEEP_TMP:-0}" = 1 ]; then echo "kept $tmp"; else rm -rf "$tmp"; fi; }
trap cleanup EXIT

# --- fake Slurm clients and jointsim ---------------------------------------------------------------------------
mkdir -p "$tmp/bin"
cat >"$tmp/bin/sbatch" <<'EOF'
#!/bin/bash
# Records its arguments, one per line as printf %q writes them, and "submits" job 4242.
printf '%q\n' "$@" >"$FAKE_DIR/sbatch.args"
echo 4242
EOF
cat >"$tmp/bin/squeue" <<'EOF'
#!/bin/bash
exit 0   # no task of the array left (and none remembered)
EOF
cat >"$tmp/bin/scancel" <<'EOF'
#!/bin/bash
exit 0
EOF
cat >"$tmp/bin/jointsim" <<'EOF'
#!/bin/bash
# batch SWEEP --collect -o DIR: DIR/manifest.csv := $FAKE_MANIFEST. Anything else: nothing.
collect=0 dir=""
while [ $# -gt 0 ]; do
  case "$1" in --collect) collect=1 ;; -o) dir="$2"; shift ;; esac
  shift
done
if [ "$collect" = 1 ]; then cp "$FAKE_MANIFEST" "$dir/manifest.csv" || exit 2; fi
exit 0
EOF
chmod +x "$tmp/bin/"*
export PATH="$tmp/bin:$PATH" FAKE_DIR="$tmp"
printf 'sweep:\n  name: inputs\n  experiment: whatever.yaml\n' >"$tmp/sweep.yaml"

# sweep MANIFEST SWEEP ARGS...: runs slurm-sweep.sh SWEEP ARGS (fake jointsim, -n 4) with MANIFEST as what
# --collect writes; its stderr in $tmp/err, exit status in rc, sbatch's arguments (if called) in $tmp/sbatch.args.
sweep() {
  local manifest="$1"; shift
  rm -f "$tmp/sbatch.args"
  FAKE_MANIFEST="$manifest" timeout 60 bash "$sweep_sh" --jointsim "$tmp/bin/jointsim" -n 4 --poll 0 "$@" \
    >"$tmp/out" 2>"$tmp/err"
  rc=$?
}
# sbatch_arg NAME: the value of sbatch's --NAME=VALUE as the script passed it (printf %q decoded by eval).
sbatch_arg() {
  local line value
  while IFS= read -r line; do
    eval "value=$line"
    case "$value" in "--$1="*) printf '%s' "${value#*=}"; return 0 ;; esac
  done <"$tmp/sbatch.args"
  return 1
}
has_line() { grep -qxF -- "$1" "$tmp/err"; }   # stderr has this exact line
show() { sed 's/^/    | /' "$tmp/err"; }

header='run,status,wall_time_s,sim_time_s,real_time_factor,output_dir,overrides,jointsim_version,git_commit,started_utc,inputs,fault_type,fault_joint,fault_severity,fault_onset_s,design,seed'

# --- a. the manifest as CSV ------------------------------------------------------------------------------------
# Three runs, all ok, in 9 lines: an override value with newlines, commas and quotes (r1; one of its lines reads
# like a record of a run "line3" that failed), quoted run and status (r2), a joint name with a comma, CRLF ends.
{
  printf '%s\r\n' "$header"
  printf 'r1,ok,0.1,0.5,5,r1,"duration=0.5; experiment.description=line1\nline2, ""quoted""\nline3,failed,0\n",0.1.0,abc,2026-11-23T10:02:11Z,"/x.yaml=xxh3:1",,,,,,\r\n'
  printf '"r2","ok",0.1,0.5,5,r2,"duration=0.5",0.1.0,abc,2026-11-23T10:02:11Z,"/x.yaml=xxh3:1",sensor_bias,"a,b",0.001,0,,\r\n'
  printf 'r3,ok,0.1,0.5,5,r3,"a=""\n""",0.1.0,abc,2026-11-23T10:02:11Z,"",,,,,,\r\n'
} >"$tmp/all_ok.csv"
sweep "$tmp/all_ok.csv" "$tmp/sweep.yaml" -o "$tmp/a1"
[ $rc = 0 ] || show
check "a. 3 runs in 9 lines (quoted newlines, commas, \"\", CRLF), all ok: exit 0 (exit $rc)" [ $rc = 0 ]
check "a. ... counted as 3 runs: 3 array tasks instead of 4, 'all 3 runs ok'" \
  eval 'has_line "slurm-sweep: 3 runs: using 3 array tasks instead of 4" && grep -q "all 3 runs ok" "$tmp/err" \
        && [ "$(sbatch_arg array)" = 0-2 ]'

# Five runs, three not ok: r2 (error, with a run.log), r4 (pending), and one named ../outside (failed), whose
# "run.log" outside OUTDIR must not be read; multi-line fields around them.
mkdir -p "$tmp/a2/r2" "$tmp/outside"
printf 'loading\nerror: unknown key +note\n' >"$tmp/a2/r2/run.log"
echo "must not be shown" >"$tmp/outside/run.log"
{
  echo "$header"
  printf 'r1,ok,0.1,0.5,5,r1,"x=1\nr9,error,\n",0.1.0,abc,t,"",,,,,,\n'
  printf 'r2,error,0,0,0,r2,"+note=a\nb, ""c""",,,,"",,,,,,\n'
  printf 'r3,ok,0.1,0.5,5,r3,"y=2",0.1.0,abc,t,"",backlash_add,"j,k",0.001,0,,\n'
  printf 'r4,pending,0,0,0,r4,"z=\n\n3",,,,"",,,,,,\n'
  printf '../outside,failed,0,0,0,../outside,"",,,,"",,,,,,\n'
} >"$tmp/some_bad.csv"
sweep "$tmp/some_bad.csv" "$tmp/sweep.yaml" -o "$tmp/a2"
[ $rc = 1 ] || show
check "a. 5 runs, 3 not ok: exit 1 (exit $rc)" [ $rc = 1 ]
listed="$(grep '^  ' "$tmp/err")"
expected="  r2: error (r2/run.log: error: unknown key +note)
  r4: pending (not started; see the task logs in $tmp/a2/slurm-logs/)
  ../outside: failed"
check "a. ... '3 of 5 runs not ok' and exactly r2, r4, ../outside listed (no run.log outside OUTDIR read)" \
  eval 'has_line "slurm-sweep: 3 of 5 runs not ok (resubmit the same command to resume them):" \
        && [ "$listed" = "$expected" ]'
[ "$listed" = "$expected" ] || { echo "    listed:"; echo "$listed" | sed 's/^/    | /'; }

printf '%s\nr1,ok,0,0,0,r1,"unterminated\n' "$header" >"$tmp/broken.csv"
sweep "$tmp/broken.csv" "$tmp/sweep.yaml" -o "$tmp/a3"
check "a. a manifest with an unclosed quote is refused before submission (exit $rc, nothing submitted)" \
  eval '[ $rc = 2 ] && grep -q "as CSV" "$tmp/err" && [ ! -e "$tmp/sbatch.args" ]'

# --- b. special characters in the output folder ----------------------------------------------------------------
printf '%s\nr1,ok,0,0,0,r1,"",,,,"",,,,,,\nr2,ok,0,0,0,r2,"",,,,"",,,,,,\n' "$header" >"$tmp/two_ok.csv"
pct="$tmp/pct 100%x%j%%5a%/out"
sweep "$tmp/two_ok.csv" "$tmp/sweep.yaml" -o "$pct"
[ $rc = 0 ] || show
check "b. output folder with %x, %j, %%, %5a, a trailing % and a space: exit 0 (exit $rc)" [ $rc = 0 ]
out_arg="$(sbatch_arg output)"
want="${pct//%/%%}/slurm-logs/%x-%A_%a.out"
check "b. ... sbatch --output has every % of the folder doubled ($out_arg)" [ "$out_arg" = "$want" ]
check "b. ... sbatch --chdir is the folder as it is" [ "$(sbatch_arg chdir)" = "$pct" ]
check "b. ... the batch script is in the folder's slurm-logs/" [ -f "$pct/slurm-logs/jointsim-inputs.sbatch" ]

sweep "$tmp/two_ok.csv" "$tmp/sweep.yaml" -o "$tmp/back\\slash/out"
check "b. output folder with a backslash: exit 2 with a message naming -o (exit $rc)" \
  eval '[ $rc = 2 ] && [ "$(wc -l <"$tmp/err")" = 1 ] && grep -q -- "-o/--output-dir" "$tmp/err"'
check "b. ... nothing written, nothing submitted" eval '[ ! -e "$tmp/back\\slash" ] && [ ! -e "$tmp/sbatch.args" ]'

# --- c. job names ----------------------------------------------------------------------------------------------
long="$(printf 'a%.0s' {1..129})"
for bad in ../../x .x -x a%x a/b "a b" $'a\nb' "$long" ""; do
  rm -rf "$tmp/c"
  sweep "$tmp/two_ok.csv" "$tmp/sweep.yaml" -o "$tmp/c/out" -J "$bad"
  shown="$(printf %q "$bad")"
  check "c. -J ${shown:0:40}: exit 2, one line naming the option, nothing written or submitted (exit $rc)" \
    eval '[ $rc = 2 ] && [ "$(wc -l <"$tmp/err")" = 1 ] && grep -q -- "-J" "$tmp/err" \
          && [ ! -e "$tmp/c" ] && [ ! -e "$tmp/x" ] && [ ! -e "$tmp/x.sbatch" ] && [ ! -e "$tmp/sbatch.args" ]'
done
rm -rf "$tmp/c"
sweep "$tmp/two_ok.csv" "$tmp/sweep.yaml" -o "$tmp/c/out" --job-name=../../x
check "c. --job-name=../../x: exit 2, nothing written (exit $rc)" eval '[ $rc = 2 ] && [ ! -e "$tmp/c" ]'
sweep "$tmp/two_ok.csv" "$tmp/sweep.yaml" -o "$tmp/c/out" -J
check "c. -J without a value: exit 2 (bad arguments; exit $rc)" eval '[ $rc = 2 ] && [ ! -e "$tmp/c" ]'
sweep "$tmp/two_ok.csv" "$tmp/sweep.yaml" -o "$tmp/c/out" -J "ok_Name-1.2"
check "c. -J ok_Name-1.2 accepted (exit $rc)" \
  eval '[ $rc = 0 ] && [ "$(sbatch_arg job-name)" = ok_Name-1.2 ] && [ -f "$tmp/c/out/slurm-logs/ok_Name-1.2.sbatch" ]'

# The default name comes from the sweep's name, else from its file name, which may hold anything.
printf 'runs:\n  - name: r1\n' >"$tmp/my sweep%x.yaml"
sweep "$tmp/two_ok.csv" "$tmp/my sweep%x.yaml" -o "$tmp/c2"
check "c. default job name from the file 'my sweep%x.yaml' made safe: jointsim-my_sweep_x (exit $rc)" \
  eval '[ $rc = 0 ] && [ "$(sbatch_arg job-name)" = jointsim-my_sweep_x ] \
        && [ -f "$tmp/c2/slurm-logs/jointsim-my_sweep_x.sbatch" ]'

echo "slurm sweep input test: $failures failure(s)"
[ "$failures" = 0 ]
