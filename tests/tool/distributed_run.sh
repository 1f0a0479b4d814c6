#!/usr/bin/env bash
# tessera run --distributed exact|block under mpirun, as a user runs it: 1, 2 and 3 ranks give the
# single-process state_hash on a cloth and an FEM bar; the summary names the ranks and what
# they exchanged; --out writes one frame set; bad input ends every rank with one line on
# stderr and exit code 2.
#   distributed_run.sh TESSERA MPIEXEC
set -uo pipefail
tessera=$1
mpiexec=$2
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
failures=0
fail() { echo "FAIL: $*" >&2; failures=$((failures + 1)); }
field() { /usr/bin/python3 -c "import json, sys; print(json.load(sys.stdin)[sys.argv[1]])" "$1"; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

for scene in "cloth:24x20 --frames 5" "bar:2x2x6 --frames 5 --solid-material strain_tetra"; do
  # shellcheck disable=SC2086
  one=$("$tessera" run $scene --json | field state_hash)
  [[ -n "$one" ]] || fail "no single-process hash for $scene"
  for ranks in 1 2 3; do
    # shellcheck disable=SC2086
    summary=$("$mpiexec" -q --oversubscribe -np "$ranks" "$tessera" run $scene --threads 1 \
                --distributed exact --json) || fail "$scene on $ranks ranks exited $?"
    hash=$(field state_hash <<< "$summary")
    [[ "$hash" == "$one" ]] || fail "$scene on $ranks ranks: state_hash $hash, one process $one"
    [[ $(field ranks <<< "$summary") == "$ranks" ]] || fail "$scene: ranks is not $ranks"
    ghosts=$(field ghost_particles <<< "$summary")
    if [[ $ranks -gt 1 ]]; then
      [[ $(field messages_per_iteration <<< "$summary") != "0.0" ]] || fail "$scene: no messages on $ranks ranks"
      [[ "$ghosts" != *"[0]"* ]] || fail "$scene: no ghosts on $ranks ranks ($ghosts)"
    fi
  done
done

# Block mode: one exchange per iteration instead of one per colour, residuals near exact's.
exact=$("$mpiexec" -q --oversubscribe -np 2 "$tessera" run cloth:32 --frames 10 --threads 1 --distributed exact --json)
block=$("$mpiexec" -q --oversubscribe -np 2 "$tessera" run cloth:32 --frames 10 --threads 1 --distributed block --json) \
  || fail "block mode exited $?"
[[ $(field distributed <<< "$block") == "block" ]] || fail "block: distributed is not block"
/usr/bin/python3 - "$exact" "$block" <<'PY' || fail "block mode: messages or residuals out of line"
import json, sys
exact, block = json.loads(sys.argv[1]), json.loads(sys.argv[2])
assert block["messages_per_iteration"] < exact["messages_per_iteration"] / 4, (block, exact)
assert block["residual_rms_final"] < 2 * exact["residual_rms_final"], (block, exact)
PY

# One frame set, written by rank 0.
"$mpiexec" -q --oversubscribe -np 2 "$tessera" run cloth:10x8 --frames 3 --threads 1 \
  --distributed exact --out "$work/frames" --json > "$work/summary.json" || fail "--out exited $?"
[[ -f "$work/frames/frames.pvd" && -f "$work/frames/frame_00003.vtu" ]] || fail "--out: frames missing"
[[ $(field files_written < "$work/summary.json") == "4" ]] || fail "--out: files_written is not 4 (frames 0 to 3)"

# Bad input: one line, exit code 2, whatever the number of ranks.
for args in "cloth:0x5 --distributed exact" "cloth:8 --distributed fast" \
            "cloth:8 --mode jacobi --distributed exact" "drape:8 --distributed exact"; do
  # shellcheck disable=SC2086
  timeout 120 "$mpiexec" -q --oversubscribe -np 3 "$tessera" run $args > "$work/out" 2> "$work/err"
  code=$?
  [[ $code -eq 2 ]] || fail "[$args] exit code $code, not 2"
  lines=$(grep -c '^tessera run: ' "$work/err")
  [[ $lines -eq 1 ]] || fail "[$args] $lines error lines: $(cat "$work/err")"
done

[[ $failures -eq 0 ]] && echo "distributed_run: all checks passed"
exit $((failures != 0))
