#!/usr/bin/env bash
# The trainer's actors on MPI ranks (coopt/actor_ranks.hpp), on localhost.
#   ranks: `mpirun -np 3 comorph train` (a host and 2 actor ranks) writes the
#          episodes.csv and evaluations.csv of 2 simulation threads;
#   kill:  kill -9 of actor rank 1 stops the job with a message naming the
#          rank; `mpirun -np 3 comorph train --resume` then ends with the
#          uninterrupted run's episodes.csv.
# usage: mpi_actors.sh COMORPH_EXE SOURCE_DIR WORK_DIR ranks|kill
set -euo pipefail
exe=$1 src=$2 work=$3 case=$4
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1  # CI runs as root
mpi=(mpirun --oversubscribe -np 3)
config=$src/configs/ci.yaml
rm -rf "$work" && mkdir -p "$work"
fail() {
  echo "FAIL: $*" >&2
  exit 1
}
# evaluations.csv without its wall_s column (the only one that follows the timing).
without_wall() { cut -d, -f1,2,4- "$1"; }
rows_of() {
  if [ -f "$1" ]; then echo $(($(wc -l < "$1") - 1)); else echo 0; fi
}
job=
trap '[ -z "$job" ] || kill "$job" 2> /dev/null || true' EXIT  # no mpirun outlives a failed test

case $case in
  ranks)
    "$exe" train --config "$config" --set trainer.simulation_threads=2 --out "$work/threads" > "$work/threads.log" 2>&1 ||
      fail "the threads' run: $(tail -3 "$work/threads.log")"
    "${mpi[@]}" "$exe" train --config "$config" --out "$work/ranks" > "$work/ranks.log" 2>&1 ||
      fail "the ranks' run: $(tail -5 "$work/ranks.log")"
    cmp "$work/threads/episodes.csv" "$work/ranks/episodes.csv" || fail "episodes.csv differs between threads and ranks"
    cmp <(without_wall "$work/threads/evaluations.csv") <(without_wall "$work/ranks/evaluations.csv") ||
      fail "evaluations.csv differs between threads and ranks"
    [ "$(wc -l < "$work/ranks/episodes.csv")" -eq 7 ] || fail "the ranks' run did not write its 6 episodes"
    ;;
  kill)
    sets=(--set trainer.episodes=16)  # 18 episodes, a checkpoint every 2
    "$exe" train --config "$config" "${sets[@]}" --set trainer.simulation_threads=2 --out "$work/whole" \
      > "$work/whole.log" 2>&1 || fail "the uninterrupted run: $(tail -3 "$work/whole.log")"
    "${mpi[@]}" "$exe" train --config "$config" "${sets[@]}" --out "$work/killed" > "$work/killed.log" 2>&1 &
    job=$!
    # Row 3 follows the checkpoint after episode 2: a resume has a checkpoint.
    rows=0
    for _ in $(seq 2400); do
      rows=$(rows_of "$work/killed/episodes.csv")
      [ "$rows" -ge 3 ] && break
      sleep 0.05
    done
    [ "$rows" -ge 3 ] || fail "the ranks' run wrote no 3 episodes in 120 s"
    actor=
    for pid in $(pgrep -f -- "--out $work/killed"); do
      tr '\0' '\n' < "/proc/$pid/environ" 2> /dev/null | grep -qx OMPI_COMM_WORLD_RANK=1 && actor=$pid
    done
    [ -n "$actor" ] || fail "no process of actor rank 1 found"
    kill -9 "$actor"
    status=0
    wait "$job" || status=$?
    job=
    [ "$status" -ne 0 ] || fail "mpirun exited 0 after an actor rank was killed"
    grep -q "rank 1 .*exited on signal 9" "$work/killed.log" || fail "no message naming rank 1: $(tail -5 "$work/killed.log")"
    killed_rows=$(rows_of "$work/killed/episodes.csv")
    [ "$killed_rows" -lt 18 ] || fail "the run had finished before the kill"
    "${mpi[@]}" "$exe" train --resume "$work/killed" > "$work/resumed.log" 2>&1 ||
      fail "the resume: $(tail -5 "$work/resumed.log")"
    cmp "$work/whole/episodes.csv" "$work/killed/episodes.csv" ||
      fail "the resumed run's episodes.csv differs from the uninterrupted run's"
    echo "killed after $killed_rows of 18 episodes; $(head -1 "$work/resumed.log")"
    ;;
  *) fail "unknown case $case" ;;
esac
echo "mpi_actors $case: passed"
