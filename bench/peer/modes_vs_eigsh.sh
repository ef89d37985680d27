#!/usr/bin/env bash
# The paper's soft-base machine refined to N plate elements per side (N = 164: 206,514 DOF;
# N = 365: 1,009,296 DOF), lowest 20 modes: `meid modes` as a user runs it (assembly, solve,
# checks, outputs; CPU time (user + system), wall time and peak memory by /usr/bin/time -v),
# then SciPy `eigsh`
# (ARPACK shift-invert, SuperLU) on the same exported K and M, in the same run, with the
# frequency differences (bench/peer/eigsh_peer.py; its JSON line has the solve's wall and CPU
# time). Record the figures in docs/performance.md with `uptime` load; compare CPU times, not
# wall times (the machine is shared).
#
# usage: bench/peer/modes_vs_eigsh.sh N [OUT_DIR] [PYTHON]   (PYTHON needs numpy + scipy)
set -euo pipefail
N=${1:?elements per side}
OUT=${2:-target/modes_vs_eigsh/n$N}
PY=${3:-python3}
MEID=${MEID:-target/release/meid}
MODEL=examples/paper-soft-base.toml
mkdir -p "$OUT"
stamp() { echo "== $(date -u +%FT%TZ) load $(cut -d' ' -f1-3 /proc/loadavg): $*"; }
stamp "meid modes, N = $N"
/usr/bin/time -v "$MEID" modes "$MODEL" --count 20 -o "$OUT/run" -q \
  --set "structure.fem.machine.elements_per_side=$N" 2>&1 | grep -E "User time|System time|Elapsed|Maximum resident|rror"
stamp "export K, M"
"$MEID" modes "$MODEL" --count 20 -o "$OUT/x" -q --export-matrices \
  --set "structure.fem.machine.elements_per_side=$N"
stamp "SciPy eigsh (30 min limit)"
timeout 1800 /usr/bin/time -v "$PY" bench/peer/eigsh_peer.py "$OUT/x/K.mtx" "$OUT/x/M.mtx" 20 \
  --meid "$OUT/x/modes.json" 2>&1 | grep -E "^\{|User time|System time|Elapsed|Maximum resident|rror" || echo "eigsh: failed or over 30 min"
stamp "done"
