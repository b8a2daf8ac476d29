#!/usr/bin/env bash
# The tests: set up (lavapipe, test models, a local PostgreSQL for the dashboard's storage tests),
# check formatting and lints, run every test.
set -euo pipefail
cd "$(dirname "$0")/.."
ci/setup.sh
# Prints `export TESSERA_TEST_POSTGRES_URL=...` for the server it starts (idempotent).
eval "$(bash dashboard/ci/setup-postgres.sh)"
bash dashboard/ci/setup-chromium.sh  # headless Chromium + chromedriver for dashboard/tests/browser.rs (idempotent)
cargo fmt --all -- --check
cargo clippy --workspace --all-targets -- -D warnings
cargo test --workspace
# The quality and stress suites on lavapipe (issue 8), with their gates: a failed gate or a
# stability finding the suites gate on fails the run. JUnit and results stay under target/.
out=target/ci-suites
rm -rf "$out"
# The workspace's feature set, as `cargo test --workspace` built it: `-p tessera` alone would
# unify other features and rebuild most dependencies.
cargo build --workspace --bins
target/debug/tessera run scenarios/quality scenarios/stress --out "$out" --junit "$out/junit.xml" --quiet
