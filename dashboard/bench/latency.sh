#!/usr/bin/env bash
# p95 latency of every page and API call of a running dashboard, with wrk over loopback.
# Usage: dashboard/bench/latency.sh http://127.0.0.1:8080 URLS_FILE [seconds] [connections]
# URLS_FILE has one path per line (`# comments` allowed). Requests ask for gzip, as browsers do.
# Prints a Markdown table: path, p50, p95, p99, max (ms), requests, errors.
set -euo pipefail
base=$1 urls=$2 secs=${3:-5} conns=${4:-4}
here=$(cd "$(dirname "$0")" && pwd)
command -v wrk >/dev/null || { echo "wrk is not installed (apt-get install -y wrk)" >&2; exit 2; }
echo "| path | p50 ms | p95 ms | p99 ms | max ms | requests | errors |"
echo "|---|---:|---:|---:|---:|---:|---:|"
grep -v '^\s*\(#\|$\)' "$urls" | while read -r path; do
  line=$(wrk -t2 -c"$conns" -d"${secs}s" -H 'Accept-Encoding: gzip' -s "$here/p95.lua" "$base$path" | tail -1)
  eval "$(echo "$line" | tr ' ' '\n' | sed 's/^/local_/')" 2>/dev/null || true
  echo "| \`$path\` | ${local_p50:-?} | ${local_p95:-?} | ${local_p99:-?} | ${local_max:-?} | ${local_requests:-?} | ${local_errors:-?} |"
done
