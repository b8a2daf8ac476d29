#!/usr/bin/env bash
# Installs headless Chromium and chromedriver (Debian's `chromium` and `chromium-driver`) for the
# dashboard's browser tests (dashboard/tests/browser.rs). Idempotent: does nothing when both are
# already installed. Progress goes to stderr.
#
#   bash dashboard/ci/setup-chromium.sh
#
# The test finds them at /usr/bin/chromium and /usr/bin/chromedriver, on PATH, or where
# TESSERA_CHROMIUM and TESSERA_CHROMEDRIVER point.
set -euo pipefail

log() { echo "setup-chromium: $*" >&2; }

have() { [ -x "/usr/bin/$1" ] || command -v "$1" >/dev/null 2>&1; }

if have chromium && have chromedriver; then
    log "already installed: $(chromedriver --version 2>/dev/null | head -1)"
    exit 0
fi

log "installing chromium and chromium-driver"
SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"
$SUDO apt-get update -qq >&2
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends chromium chromium-driver >&2
log "installed: $(chromedriver --version 2>/dev/null | head -1)"
