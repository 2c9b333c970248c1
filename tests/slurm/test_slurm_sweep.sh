#!/usr/bin/env bash
# End-to-end test of scripts/slurm-sweep.sh on a real (private, one-node) Slurm cluster started with
# scripts/slurm-cluster.sh in a temporary folder:
#   a. start the cluster (stopped again on any exit, by the PIDs it recorded);
#   b. run a 6-run fault sweep as a job array of 3 tasks;
#   c. run the same sweep locally (jointsim batch -j 2): same manifest (run, status, labels, ...) and byte-identical
#      CSV logs;
#   d. cancel one array task while its second run is running (its first run has finished), check that the collected
#      manifest reports that run as not ok, resubmit, and check that only the missing run ran again (the other
#      runs' files unchanged, the resubmitted tasks skipped them) and that the final manifest is all ok;
#   f. (issue 26) a sweep whose overrides hold newlines, commas and quotes (multi-line quoted fields of the
#      manifest), in an output folder named with %x, %j, %%, %5a, a trailing % and a space (Slurm's --output file
#      name patterns): counted right, all ok (exit 0), the task logs in that folder's slurm-logs/;
#   g. (issue 26) such a sweep with a run in error: exit 1 and exactly that run listed;
#   h. (issue 26) -J ../../x and an output folder with a backslash: exit 2, nothing written, no job submitted;
#   e. stop the cluster and check that its daemons are gone.
# Usage: tests/slurm/test_slurm_sweep.sh JOINTSIM_EXECUTABLE [REPOSITORY_ROOT]
# Needs root, munge and slurm-wlm (slurmctld, slurmd, client commands); prints SKIP and exits 77 without them.
# The same input checks without a cluster: tests/slurm/test_slurm_sweep_inputs.sh.
# Prints one PASS/FAIL line per check and exits 1 if any failed. About 20 s on 2 cores; every wait is bounded so
# that the whole test ends within TEST_TIMEOUT seconds (default 170) plus the cluster's shutdown.
# KEEP_TMP=1 keeps the temporary folder.
set -uo pipefail

[ $# -ge 1 ] && [ $# -le 2 ] || { sed -n '2,/^set -uo/{/^set -uo/d;s/^# \{0,1\}//;p}' "$0" >&2; exit 2; }
repo="$(cd "${2:-$(dirname "$0")/../..}" && pwd)"
jointsim_arg="$1"

if [ "$(id -u)" != 0 ]; then echo "SKIP: the private Slurm cluster needs root"; exit 77; fi
for tool in munged slurmctld slurmd sbatch squeue scancel sinfo ss; do
  command -v "$tool" >/dev/null || { echo "SKIP: '$tool' not installed (munge, slurm-wlm, iproute2)"; exit 77; }
done

failures=0
pass() { echo "PASS: $*"; }
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
check() { local what="$1"; shift; if "$@"; then pass "$what"; else fail "$what"; fi; }
t0=$SECONDS
deadline=$((t0 + ${TEST_TIMEOUT:-170}))
left() { local s=$((deadline - SECONDS)); echo $((s > 1 ? s : 1)); }   # seconds until the deadline

tmp="$(mktemp -d "${TMPDIR:-/tmp}/jointsim_slurm.XXXXXX")"
tmp="$(cd "$tmp" && pwd -P)"          # as the daemons' command lines name it
cluster="$tmp/cluster"
cleanup() {
  "$repo/scripts/slurm-cluster.sh" stop "$cluster" >/dev/null 2>&1 || true
  if [ "${KEEP_TMP:-0}" = 1 ]; then echo "kept $tmp"; else rm -rf "$tmp"; fi
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# A private copy of the executable: a rebuild during the test cannot change or remove it under the jobs. (The
# binary may be missing for a moment while it is being relinked: wait a little for it.)
for ((i = 0; i < 60; i++)); do [ -x "$jointsim_arg" ] && break; sleep 1; done
cp "$jointsim_arg" "$tmp/jointsim" && "$tmp/jointsim" --help >/dev/null 2>&1 \
  || { echo "FAIL: no working jointsim executable at $jointsim_arg"; exit 1; }
js="$tmp/jointsim"

# --- a. cluster ------------------------------------------------------------------------------------------------
if ! out="$("$repo/scripts/slurm-cluster.sh" start "$cluster" 2>&1)"; then
  echo "$out"
  fail "a. private Slurm cluster starts (node idle)"
  exit 1
fi
export SLURM_CONF="$cluster/slurm.conf"
pids=()
for d in munged slurmctld slurmd; do pids+=("$(cat "$cluster/$d.pid")"); done
pass "a. private Slurm cluster starts (node idle; munged/slurmctld/slurmd pids ${pids[*]})"

# --- b. sweep as a job array ------------------------------------------------------------------------------------
experiment="$repo/config/experiments/ur5_excitation.yaml"
cat >"$tmp/small.yaml" <<EOF
# Six short runs after config/sweeps/ur5_faults.yaml: nominal and one fault of five types.
sweep:
  name: slurm_small
  experiment: $experiment
  set: {robot: ../robots/ur5_drives_elastic.yaml, duration: 0.5, log_rate: 100}
runs:
  - name: nominal
faults:
  - {type: gear_stiffness_scale,   joints: [elbow_joint], values: [0.6]}
  - {type: backlash_add,           joints: [shoulder_lift_joint], values: [1.0e-3]}
  - {type: coulomb_friction_scale, joints: [shoulder_pan_joint], values: [2.0]}
  - {type: torque_constant_scale,  joints: [wrist_1_joint], values: [0.8]}
  - {type: sensor_bias,            joints: [wrist_2_joint], values: [-1.0e-3]}
EOF
sweep_slurm() { timeout "$(left)" "$repo/scripts/slurm-sweep.sh" "$@" -n 3 -c 1 --jointsim "$js" --poll 0.5; }
sweep_slurm "$tmp/small.yaml" -o "$tmp/slurm" 2>"$tmp/sweep_b.log"
rc=$?
[ $rc = 0 ] || cat "$tmp/sweep_b.log"
check "b. slurm-sweep.sh: 6 runs in 3 array tasks, all ok (exit $rc)" [ $rc = 0 ]
tasks=$(find "$tmp/slurm/slurm-logs" -name '*.out' | wc -l)
check "b. 3 array tasks wrote their logs to OUTDIR/slurm-logs/ ($tasks)" [ "$tasks" = 3 ]

# --- c. same results as a local batch ---------------------------------------------------------------------------
timeout "$(left)" "$js" batch "$tmp/small.yaml" -j 2 -o "$tmp/local" >/dev/null 2>&1
check "c. local jointsim batch -j 2 of the same sweep, all ok" [ $? = 0 ]

# The manifest columns that do not depend on where and when a run executed (not wall times, start times).
columns() {
  awk -v want="run,status,output_dir,overrides,fault_type,fault_joint,fault_severity,fault_onset_s,design,seed" '
    function split_csv(line, f,   n, i, c, q, cur) {   # RFC 4180 fields: quotes, "" inside quotes
      n = 0; cur = ""; q = 0
      for (i = 1; i <= length(line); i++) {
        c = substr(line, i, 1)
        if (q) {
          if (c == "\"") { if (substr(line, i + 1, 1) == "\"") { cur = cur c; i++ } else q = 0 }
          else cur = cur c
        } else if (c == "\"") q = 1
        else if (c == ",") { f[++n] = cur; cur = "" }
        else cur = cur c
      }
      f[++n] = cur
      return n
    }
    NR == 1 { n = split_csv($0, h); for (i = 1; i <= n; i++) col[h[i]] = i; k = split(want, w, ",") }
    { split_csv($0, f); line = ""
      for (i = 1; i <= k; i++) line = line (i > 1 ? " | " : "") (w[i] in col ? f[col[w[i]]] : "<missing " w[i] ">")
      print line }' "$1"
}
if diff <(columns "$tmp/local/manifest.csv") <(columns "$tmp/slurm/manifest.csv") >"$tmp/manifest.diff"; then
  pass "c. manifest.csv equal to the local one (run, status, output_dir, overrides, labels; $(($(wc -l <"$tmp/local/manifest.csv") - 1)) runs)"
else
  cat "$tmp/manifest.diff"; fail "c. manifest.csv equal to the local one"
fi
csv_bad=0 csv_n=0
for f in "$tmp"/local/*/*.csv; do
  rel="${f#"$tmp/local/"}"
  csv_n=$((csv_n + 1))
  cmp -s "$f" "$tmp/slurm/$rel" || { echo "  differs or missing: $rel"; csv_bad=$((csv_bad + 1)); }
done
check "c. per-run CSV logs byte-identical to the local run ($csv_n files)" [ "$csv_n:$csv_bad" = 6:0 ]

# --- d. cancel a task mid-run, resubmit: only the missing run runs again ----------------------------------------
# Explicit runs, so that one can be slow: with 3 shards, task 1 runs r1-stiffness (0.5 s simulated) and then
# r4-slow (600 s simulated, several seconds of wall time). The task is cancelled once r1-stiffness is ok and r4-slow
# has started; Slurm's SIGTERM makes r4-slow end as "interrupted".
cat >"$tmp/resume.yaml" <<EOF
sweep:
  name: slurm_resume
  experiment: $experiment
  set: {robot: ../robots/ur5_drives_elastic.yaml, duration: 0.5, log_rate: 100}
runs:
  - name: r0-nominal
  - name: r1-stiffness
    faults: [{type: gear_stiffness_scale, joint: elbow_joint, value: 0.6}]
  - name: r2-backlash
    faults: [{type: backlash_add, joint: shoulder_lift_joint, value: 1.0e-3}]
  - name: r3-friction
    faults: [{type: coulomb_friction_scale, joint: shoulder_pan_joint, value: 2.0}]
  - name: r4-slow
    set: {duration: 600, log_rate: 1}
  - name: r5-bias
    faults: [{type: sensor_bias, joint: wrist_2_joint, value: -1.0e-3}]
EOF
out2="$tmp/resume"
jobid="$(sweep_slurm "$tmp/resume.yaml" -o "$out2" --no-wait 2>"$tmp/sweep_d1.log")"
[[ "$jobid" =~ ^[0-9]+$ ]] || { cat "$tmp/sweep_d1.log"; fail "d. submission with --no-wait prints the job ID"; exit 1; }

ok_status() { grep -q '"status": "ok"' "$1" 2>/dev/null; }
wait_until() {  # wait_until SECONDS COMMAND...: poll every 0.1 s, at most SECONDS and not past the deadline
  local until_s=$((SECONDS + $1)); shift
  [ $until_s -le $deadline ] || until_s=$deadline
  until "$@"; do [ $SECONDS -lt $until_s ] || return 1; sleep 0.1; done
}
started() { ok_status "$out2/r1-stiffness/summary.json" && [ -e "$out2/r4-slow/run.log" ]; }
queue_empty() { [ -z "$(squeue -h -j "$jobid" 2>/dev/null)" ]; }
if wait_until 60 started; then
  scancel "${jobid}_1"
  pass "d. task ${jobid}_1 cancelled after its first run finished, during its second"
else
  fail "d. task ${jobid}_1 reached its second run within 60 s"
fi
wait_until 60 queue_empty || fail "d. job array $jobid ended within 60 s of the cancel"
timeout "$(left)" "$js" batch "$tmp/resume.yaml" --collect -o "$out2" >/dev/null 2>&1
status_of() { awk -F, -v r="$1" '$1 == r { print $2 }' "$out2/manifest.csv"; }
not_ok="$(awk -F, 'NR > 1 && $2 != "ok" { printf "%s%s=%s", (n++ ? " " : ""), $1, $2 }' "$out2/manifest.csv")"
# (interrupted: SIGTERM reached the run; another status if the cancel came in between or killed it outright)
check "d. after the cancel exactly r4-slow is not ok (${not_ok:-all ok})" eval '[[ "$not_ok" =~ ^r4-slow=[a-z]+$ ]]'
done_runs=(r0-nominal r1-stiffness r2-backlash r3-friction r5-bias)
fingerprint() {  # content hashes and modification times of the finished runs' files
  local r
  for r in "${done_runs[@]}"; do
    (cd "$out2/$r" && sha256sum summary.json ./*.csv run.log && stat -c '%n %.9Y' summary.json ./*.csv run.log) | sed "s|^|$r |"
  done
}
fingerprint >"$tmp/before.txt"
sweep_slurm "$tmp/resume.yaml" -o "$out2" 2>"$tmp/sweep_d2.log"
rc=$?
[ $rc = 0 ] || cat "$tmp/sweep_d2.log"
check "d. resubmission: every run of the collected manifest ok (exit $rc)" [ $rc = 0 ]
fingerprint >"$tmp/after.txt"
if diff "$tmp/before.txt" "$tmp/after.txt" >/dev/null; then
  pass "d. the 5 runs finished before the cancel were not run again (summary.json, CSV, run.log unchanged)"
else
  diff "$tmp/before.txt" "$tmp/after.txt"; fail "d. the runs finished before the cancel were not run again"
fi
# The resubmitted tasks' own account: 5 runs skipped as already ok, r4-slow complete now.
second="$(grep -o 'submitted job array [0-9]*' "$tmp/sweep_d2.log" | awk '{print $4}')"
skipped=$(cat "$out2"/slurm-logs/*-"${second:-none}"_*.out 2>/dev/null \
  | sed -n 's/.* \([0-9]*\) skipped (already ok).*/\1/p' | awk '{s += $1} END {print s + 0}')
check "d. the resubmitted array (job $second) skipped 5 runs" [ "$skipped" = 5 ]
check "d. r4-slow complete after the resubmission (600 s simulated)" \
  grep -Eq '"sim_time_s": 600(\.0*)?,' "$out2/r4-slow/summary.json"

# --- f. quoted manifest fields, % in the output folder ----------------------------------------------------------
# (In this unquoted here-document \n and \" reach the YAML file, whose double-quoted strings read them as a newline
# and a quote.) The manifest's overrides field of q0-multiline spans 3 lines; one of them reads like a record.
cat >"$tmp/quoted.yaml" <<EOF
sweep:
  name: slurm_quoted
  experiment: $experiment
  set: {robot: ../robots/ur5_drives_elastic.yaml, duration: 0.2, log_rate: 100}
runs:
  - name: q0-multiline
    set: {experiment.description: "line1\nline2, \"quoted\"\nline3,failed,0"}
  - name: q1-plain
  - name: q2-commas
    set: {experiment.description: "a,b,,c"}
EOF
pct="$tmp/out 100%x%j%%5a%"
sweep_slurm "$tmp/quoted.yaml" -o "$pct" 2>"$tmp/sweep_f.log"
rc=$?
[ $rc = 0 ] || cat "$tmp/sweep_f.log"
check "f. 3 runs with multi-line, comma and quote overrides into '${pct#"$tmp/"}': all ok (exit $rc)" [ $rc = 0 ]
check "f. ... counted as 3 runs (3 tasks, 'all 3 runs ok')" \
  eval 'grep -q ": 3 runs in 3 tasks" "$tmp/sweep_f.log" && grep -q "all 3 runs ok" "$tmp/sweep_f.log"'
job_f="$(grep -o 'submitted job array [0-9]*' "$tmp/sweep_f.log" | awk '{print $4}')"
logs_f="$(cd "$pct/slurm-logs" 2>/dev/null && ls -- *.out 2>/dev/null | tr '\n' ' ')"
want_f=""
for i in 0 1 2; do want_f+="jointsim-slurm_quoted-${job_f}_$i.out "; done
check "f. ... the 3 task logs in the folder's slurm-logs/ ($logs_f)" [ "$logs_f" = "$want_f" ]

# --- g. a run in error among multi-line fields ------------------------------------------------------------------
cat >"$tmp/quoted_bad.yaml" <<EOF
sweep:
  name: slurm_quoted_bad
  experiment: $experiment
  set: {robot: ../robots/ur5_drives_elastic.yaml, duration: 0.2, log_rate: 100}
runs:
  - name: g0-ok
    set: {experiment.description: "one\ntwo,error\nthree"}
  - name: g1-bad
    set: {+no_such_key: "x\ny, \"z\""}
EOF
sweep_slurm "$tmp/quoted_bad.yaml" -o "$tmp/quoted_bad" 2>"$tmp/sweep_g.log"
rc=$?
listed="$(grep '^  ' "$tmp/sweep_g.log" | sed 's/ (.*//')"
check "g. 2 runs, g1-bad in error (an override key that does not exist): exit 1 (exit $rc)" [ $rc = 1 ]
check "g. ... '1 of 2 runs not ok' and exactly g1-bad listed (${listed//$'\n'/; })" \
  eval 'grep -q "1 of 2 runs not ok" "$tmp/sweep_g.log" && [ "$listed" = "  g1-bad: error" ]'
[ "$listed" = "  g1-bad: error" ] || cat "$tmp/sweep_g.log"

# --- h. a job name or an output folder Slurm cannot take: refused before anything happens -----------------------
last_job() { squeue -h -t all -o %F 2>/dev/null | sort -n | tail -n 1; }
jobs_before="$(last_job)"
sweep_slurm "$tmp/small.yaml" -o "$tmp/h/out" -J ../../x 2>"$tmp/sweep_h1.log"
rc=$?
check "h. -J ../../x: exit 2 with one line naming the option (exit $rc: $(head -n 1 "$tmp/sweep_h1.log"))" \
  eval '[ $rc = 2 ] && [ "$(wc -l <"$tmp/sweep_h1.log")" = 1 ] && grep -q -- "-J" "$tmp/sweep_h1.log"'
sweep_slurm "$tmp/small.yaml" -o "$tmp/h\\x/out" 2>"$tmp/sweep_h2.log"
rc=$?
check "h. output folder with a backslash: exit 2 (exit $rc: $(head -n 1 "$tmp/sweep_h2.log"))" [ $rc = 2 ]
check "h. ... nothing written, no job submitted (last job ${jobs_before:-none} before and after)" \
  eval '[ ! -e "$tmp/h" ] && [ ! -e "$tmp/x.sbatch" ] && [ ! -e "$tmp/h\\x" ] && [ "$(last_job)" = "$jobs_before" ]'

# --- e. stop the cluster ---------------------------------------------------------------------------------------
"$repo/scripts/slurm-cluster.sh" stop "$cluster" 2>/dev/null
alive=""
for p in "${pids[@]}"; do
  # Gone, or (PID reused) no longer a process of this cluster.
  if [ -r "/proc/$p/cmdline" ] && tr '\0' ' ' <"/proc/$p/cmdline" | grep -qF "$cluster/"; then alive+=" $p"; fi
done
check "e. cluster stopped: daemons ${pids[*]} gone${alive:+ (still running:$alive)}" [ -z "$alive" ]
# Nor any job process (jointsim runs from the private copy) outlives the cluster.
leftover="$(pgrep -f -- "$tmp/" | tr '\n' ' ')"
check "e. no process of the test left${leftover:+ (pids $leftover)}" [ -z "$leftover" ]

echo "slurm sweep test: $failures failure(s), $((SECONDS - t0)) s"
[ "$failures" = 0 ]
