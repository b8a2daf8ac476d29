#!/usr/bin/env bash
# A/B acceptance on one GPU: a dashboard, one `tessera runner`, and two A/Bs of a perf scenario:
#   1. C0 against itself (expect "no change" on gpu_ms.median, its interval holding 0);
#   2. C0 against C1, which raises the scenario's shading_cost 64 -> 65 (one more sin/cos round
#      per fragment of the scene pass: up to 1/64 = 1.6% more of that pass's work; expect
#      "changed").
# The runner's build cache is seeded with this checkout's binary (C0 and C1 differ only in a
# scenario file, so they share that build).
#
# Usage: dashboard/bench/ab-h200.sh  (env: WORK, LABEL=h200, SCENARIO, VARIANT=native, ATTEMPTS=10)
# Needs: a built workspace (cargo build --bins), a clean checkout outside scenarios/ and docs.
set -euo pipefail

ROOT=$(git rev-parse --show-toplevel)
WORK=${WORK:-$(mktemp -d /tmp/tessera-ab.XXXXXX)}
LABEL=${LABEL:-h200}
SCENARIO=${SCENARIO:-scenarios/perf/shading-bound-1080p.toml}
VARIANT=${VARIANT:-native}
ATTEMPTS=${ATTEMPTS:-10}
BIN="${CARGO_TARGET_DIR:-$ROOT/target}/debug"
DB="$WORK/store.sqlite"
PIDS=()
cleanup() { for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null || true; done; }
trap cleanup EXIT
echo "work folder: $WORK"

git clone -q --no-local "$ROOT" "$WORK/repo"
cd "$WORK/repo"
git config user.email ab@tessera.invalid
git config user.name "ab acceptance"
C0=$(git rev-parse HEAD)
sed -i 's/^shading_cost = 64$/shading_cost = 65/' "$SCENARIO"
git diff --quiet && { echo "error: $SCENARIO has no 'shading_cost = 64' line" >&2; exit 2; }
git commit -qam "ab: one more shading round per fragment"
C1=$(git rev-parse HEAD)
cd "$WORK"

KEY=$(python3 - "$WORK/repo" "$C0" <<'PY'
import hashlib, subprocess, sys
out = subprocess.check_output(["git", "-C", sys.argv[1], "ls-tree", sys.argv[2]]).decode().strip()
h = hashlib.sha256()
for line in out.splitlines():
    name = line.split("\t")[1]
    if name in ("scenarios", "dashboard", "ci", ".github") or name.endswith(".md"):
        continue
    h.update(line.encode() + b"\n")
print(h.hexdigest()[:24])
PY
)
mkdir -p "$WORK/target/tessera-bins/$KEY"
cp "$BIN/tessera" "$WORK/target/tessera-bins/$KEY/tessera"

"$BIN/tessera-dashboard" token add ab-runner --scope runner --db "$DB" > "$WORK/token" 2>/dev/null
export TESSERA_DASHBOARD_TOKEN=$(cat "$WORK/token")
"$BIN/tessera-dashboard" serve --db "$DB" --listen 127.0.0.1:0 2> "$WORK/serve.log" &
PIDS+=($!)
for _ in $(seq 1 100); do grep -q "serving" "$WORK/serve.log" && break; sleep 0.1; done
URL=$(sed -n 's/.* on \(http:\/\/[0-9.:]*\).*/\1/p' "$WORK/serve.log" | head -1)
"$BIN/tessera" runner --dashboard "$URL" --labels "$LABEL" --repository "$WORK/repo" \
  --work "$WORK/runner" --target-dir "$WORK/target" --name ab-1 --poll-secs 2 2> "$WORK/runner.log" &
PIDS+=($!)
for _ in $(seq 1 600); do grep -q registered "$WORK/runner.log" && break; sleep 0.5; done
head -1 "$WORK/runner.log"

ab() {
  "$BIN/tessera-dashboard" ab --db "$DB" --repository "$WORK/repo" --labels "$LABEL" \
    --scenario "$SCENARIO" --variant "$VARIANT" --attempts "$ATTEMPTS" --wait --a "$1" --b "$2"
}
echo "== A/B 1: $C0 against itself"
ab "$C0" "$C0"
echo "== A/B 2: $C0 against $C1 (shading_cost 64 -> 65)"
ab "$C0" "$C1"
