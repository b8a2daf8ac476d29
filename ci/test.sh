#!/usr/bin/env bash
# The tests: set up (lavapipe, test models, PostgreSQL), check formatting and lints, run every test.
set -euo pipefail
cd "$(dirname "$0")/.."
ci/setup.sh
if [ -f dashboard/ci/postgres-url ]; then
  TESSERA_TEST_POSTGRES_URL="$(cat dashboard/ci/postgres-url)"
  export TESSERA_TEST_POSTGRES_URL
fi
cargo fmt --all -- --check
cargo clippy --workspace --all-targets -- -D warnings
cargo test --workspace
