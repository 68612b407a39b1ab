#!/usr/bin/env bash
# Usage: check_slurm.sh KERGS WORK_DIR   (run from the source tree)
# scripts/slurm/kergs.sbatch without Slurm: it parses (bash -n), then runs as a chain of jobs with a fake srun and a fake
# sbatch on PATH. The fake srun runs kergs (1 rank) and, as Slurm's --signal does before the time limit, sends it SIGUSR1
# once it has printed 8 step lines; the fake sbatch runs the submitted file at once as the next job. 30 steps of
# confine500 must take several jobs (each but the last stopped with status 4 and submitting the next, the last done),
# and leave the results file of one uninterrupted 30-step run: the same statistics and snapshots, bit for bit (scripts/compare_results.py), as a run
# without stops. Each job checkpoints every quarter of its time limit (a fake squeue gives it). A job whose kergs fails (status 1) ends the chain without resubmitting.
set -uo pipefail
kergs=$(cd "$(dirname "$1")" && pwd)/$(basename "$1") work=$2
script=scripts/slurm/kergs.sbatch
fail=0
check() { # check STATUS WHAT
  if [ "$1" -eq 0 ]; then echo "ok   $2"; else echo "FAIL $2"; fail=1; fi
}
rm -rf "$work" && mkdir -p "$work/bin"
work=$(cd "$work" && pwd)

bash -n "$script"
check $? "bash -n $script"

cat > "$work/bin/srun" << 'EOF'
#!/usr/bin/env bash
# fake srun: runs the command, and sends SIGUSR1 once it printed FAKE_STOP_AFTER step lines (Slurm's --signal)
echo "srun $*" >> "$FAKE_SBATCH_LOG.srun"
log=$(mktemp)
"$@" > "$log" 2>&1 &
pid=$!
signalled=0
while kill -0 "$pid" 2> /dev/null; do
  if [ $signalled -eq 0 ] && [ "$(grep -c '^step ' "$log")" -ge "${FAKE_STOP_AFTER:-8}" ]; then
    kill -USR1 "$pid"
    signalled=1
  fi
  sleep 0.05
done
wait "$pid"
status=$?
cat "$log"
rm -f "$log"
exit $status
EOF
cat > "$work/bin/sbatch" << 'EOF'
#!/usr/bin/env bash
# fake sbatch: records the submission, applies --export=ALL,NAME=VALUE,..., and runs the file as the next job
echo "sbatch $*" >> "$FAKE_SBATCH_LOG"
for a in "$@"; do
  case $a in --export=*) IFS=, read -r -a kv <<< "${a#--export=}"; for x in "${kv[@]}"; do [ "$x" = ALL ] || export "${x?}"; done ;; esac
done
file=${*: -1}
cp "$file" "$FAKE_SBATCH_LOG.job" # the running copy, as Slurm's spool file
SLURM_JOB_ID=$((SLURM_JOB_ID + 1)) bash "$FAKE_SBATCH_LOG.job"
echo "job status $?" >> "$FAKE_SBATCH_LOG"
exit 0 # submitted
EOF
cat > "$work/bin/squeue" << 'EOF'
#!/usr/bin/env bash
echo "1-02:00:00" # fake squeue -o %l: the job's time limit, 26 hours
EOF
chmod +x "$work/bin/srun" "$work/bin/sbatch" "$work/bin/squeue"

export PATH="$work/bin:$PATH" FAKE_SBATCH_LOG="$work/sbatch.log" SLURM_JOB_ID=1 SLURM_SUBMIT_DIR=$PWD
: > "$FAKE_SBATCH_LOG"
KERGS=$kergs KERGS_CHECKPOINT="$work/chain.checkpoint.h5" KERGS_ARGS="-steps 30 -output $work/chain.h5 -output_every 5" \
  bash "$script" > "$work/chain.log" 2>&1
status=$?
cat "$work/chain.log" | grep '^kergs'
jobs=$(grep -cE '^kergs.sbatch: job [0-9]+ of the chain (starts|continues)' "$work/chain.log")
stops=$(grep -c 'stopped by SIGUSR1, exit status 4' "$work/chain.log")
submitted=$(grep -c '^sbatch ' "$FAKE_SBATCH_LOG")
check $([ $status -eq 0 ] && [ "$jobs" -ge 3 ] && [ "$stops" -eq $((jobs - 1)) ] && [ "$submitted" -eq $((jobs - 1)) ] &&
  grep -q 'the run is done (job '"$jobs"' of the chain)' "$work/chain.log" && ! grep -q 'job status [^0]' "$FAKE_SBATCH_LOG"; echo $?) \
  "30 steps in a chain of $jobs jobs: $stops stopped by SIGUSR1 with status 4, $submitted submissions, the last job done, every job's status 0"
grep -q "KERGS_CHAIN=$jobs" "$FAKE_SBATCH_LOG"
check $? "the jobs are numbered in the chain (KERGS_CHAIN)"
check $([ "$(grep -c -- '-checkpoint_seconds 23400' "$FAKE_SBATCH_LOG.srun")" -eq "$jobs" ]; echo $?) \
  "every job checkpoints every quarter of its time limit (squeue: 1-02:00:00, -checkpoint_seconds 23400)"

"$kergs" -options_file cases/confine500.opts -steps 30 -output "$work/straight.h5" -output_every 5 -quiet > "$work/straight.log" 2>&1
check $? "the same 30 steps without a stop"
/usr/bin/python3 scripts/compare_results.py "$work/chain.h5" "$work/straight.h5" > "$work/compare.log" 2>&1
rc=$?
tail -n 3 "$work/compare.log"
check $rc "the chain's results file is the uninterrupted run's, bit for bit (scripts/compare_results.py)"

# a failing job (an unknown option) ends the chain
: > "$FAKE_SBATCH_LOG"
KERGS=$kergs KERGS_CHECKPOINT="$work/bad.checkpoint.h5" KERGS_ARGS="-steps 20 -output $work/bad.h5 -no_such_option 1" \
  bash "$script" > "$work/bad.log" 2>&1
status=$?
check $([ $status -ne 0 ] && [ $status -ne 4 ] && [ ! -s "$FAKE_SBATCH_LOG" ] && grep -q 'the chain stops' "$work/bad.log"; echo $?) \
  "a job whose kergs fails (status $status) submits nothing"
exit $fail
