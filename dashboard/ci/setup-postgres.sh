#!/usr/bin/env bash
# Installs PostgreSQL (Debian's package), starts a server on localhost without systemd, creates the
# database and user the dashboard's storage tests use, and prints the URL to export as
# TESSERA_TEST_POSTGRES_URL. Idempotent: re-running it reuses the cluster, user and database.
#
#   eval "$(dashboard/ci/setup-postgres.sh)"   # exports TESSERA_TEST_POSTGRES_URL
#
# Settings (environment): PGPORT (5432), TESSERA_PG_USER (tessera), TESSERA_PG_PASSWORD (tessera),
# TESSERA_PG_DB (tessera_test). Progress goes to stderr; stdout has only the export line.
set -euo pipefail

PORT="${PGPORT:-5432}"
USER_NAME="${TESSERA_PG_USER:-tessera}"
PASSWORD="${TESSERA_PG_PASSWORD:-tessera}"
DB="${TESSERA_PG_DB:-tessera_test}"

log() { echo "setup-postgres: $*" >&2; }

if ! ls /usr/lib/postgresql/*/bin/pg_ctl >/dev/null 2>&1; then
    log "installing postgresql"
    SUDO=""
    [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq >&2
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq postgresql >&2
fi

VERSION="$(ls /usr/lib/postgresql | sort -V | tail -1)"
BIN="/usr/lib/postgresql/$VERSION/bin"
log "PostgreSQL $VERSION"

as_postgres() {
    if [ "$(id -un)" = postgres ]; then "$@"; else su postgres -s /bin/sh -c "$(printf '%q ' "$@")"; fi
}

if command -v pg_ctlcluster >/dev/null 2>&1 && [ -d "/etc/postgresql/$VERSION/main" ]; then
    # Debian's cluster layout: pg_ctlcluster starts it without systemd.
    if ! pg_lsclusters -h 2>/dev/null | awk -v v="$VERSION" '$1==v && $2=="main" && $4=="online"' | grep -q .; then
        log "starting cluster $VERSION/main"
        pg_ctlcluster "$VERSION" main start >&2
    fi
    PORT="$(pg_lsclusters -h | awk -v v="$VERSION" '$1==v && $2=="main" {print $3}')"
else
    DATA="${TESSERA_PG_DATA:-/var/lib/postgresql/tessera-data}"
    mkdir -p "$DATA" && chown postgres: "$DATA"
    if [ ! -f "$DATA/PG_VERSION" ]; then
        log "initdb $DATA"
        as_postgres "$BIN/initdb" -D "$DATA" -A scram-sha-256 --pwfile=<(echo postgres) >&2 ||
            as_postgres "$BIN/initdb" -D "$DATA" >&2
    fi
    if ! as_postgres "$BIN/pg_ctl" -D "$DATA" status >/dev/null 2>&1; then
        log "starting server on port $PORT"
        as_postgres "$BIN/pg_ctl" -D "$DATA" -l "$DATA/server.log" -o "-p $PORT -k /tmp" -w start >&2
    fi
fi

for _ in $(seq 1 30); do
    as_postgres psql -p "$PORT" -tAc "SELECT 1" >/dev/null 2>&1 && break
    sleep 1
done

if ! as_postgres psql -p "$PORT" -tAc "SELECT 1 FROM pg_roles WHERE rolname = '$USER_NAME'" | grep -q 1; then
    log "creating user $USER_NAME"
    as_postgres psql -p "$PORT" -q -c "CREATE ROLE $USER_NAME LOGIN PASSWORD '$PASSWORD'" >&2
fi
if ! as_postgres psql -p "$PORT" -tAc "SELECT 1 FROM pg_database WHERE datname = '$DB'" | grep -q 1; then
    log "creating database $DB"
    as_postgres psql -p "$PORT" -q -c "CREATE DATABASE $DB OWNER $USER_NAME" >&2
fi

URL="postgres://$USER_NAME:$PASSWORD@localhost:$PORT/$DB"
log "ready: $URL"
echo "export TESSERA_TEST_POSTGRES_URL=$URL"
