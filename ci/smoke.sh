#!/usr/bin/env bash
# The main job: set up, build, and run the smoke suite on the best adapter found (lavapipe when
# there is no GPU). Extra arguments go to `tessera run` (e.g. --adapter nvidia, --junit out.xml).
set -euo pipefail
cd "$(dirname "$0")/.."
ci/setup.sh
cargo build --release -p tessera
exec target/release/tessera run scenarios/smoke "$@"
