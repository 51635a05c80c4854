#!/usr/bin/env bash
# A throw-away PostgreSQL server for the records tests (README.md, "The two commands"; .ci/run).
#
#   scripts/postgres.sh start DIR [PORT]   initialise DIR (when new) and start a server on
#                                          127.0.0.1:PORT (default: a free port); prints its URL
#                                          and writes it to DIR/url
#   scripts/postgres.sh stop DIR           stop the server of DIR (nothing to do when stopped)
#
# The server binaries are looked for on PATH, then in /usr/lib/postgresql/*/bin; when there are
# none, Debian's `postgresql` package is installed with apt-get (through sudo when not root).
# Run as root, the server runs as the unprivileged system user imucalib-pg (created if missing),
# since PostgreSQL refuses to run as root. Authentication is `trust` on 127.0.0.1 and on the
# socket in DIR only; the server is for tests, never for records that matter.
set -euo pipefail

PG_SYSTEM_USER=imucalib-pg

die() {
    printf 'postgres.sh: %s\n' "$*" >&2
    exit 1
}

usage() {
    printf 'usage: %s start DIR [PORT] | stop DIR\n' "$0" >&2
    exit 2
}

# The folder holding initdb, pg_ctl and postgres, or nothing.
find_bindir() {
    local candidate
    if command -v initdb >/dev/null 2>&1 && command -v pg_ctl >/dev/null 2>&1 \
            && command -v postgres >/dev/null 2>&1; then
        dirname "$(command -v pg_ctl)"
        return 0
    fi
    # Newest version first.
    for candidate in $(find /usr/lib/postgresql -mindepth 2 -maxdepth 2 -name bin -type d \
                           2>/dev/null | sort -r -V); do
        if [ -x "$candidate/initdb" ] && [ -x "$candidate/pg_ctl" ] \
                && [ -x "$candidate/postgres" ]; then
            printf '%s\n' "$candidate"
            return 0
        fi
    done
    return 1
}

install_postgresql() {
    local -a prefix=()
    if [ "$(id -u)" -ne 0 ]; then
        command -v sudo >/dev/null 2>&1 \
            || die "no PostgreSQL server binaries found and not root, and sudo is missing:" \
                   "install Debian's postgresql package"
        prefix=(sudo -n)
    fi
    command -v apt-get >/dev/null 2>&1 \
        || die "no PostgreSQL server binaries found and apt-get is missing:" \
               "install PostgreSQL's server (initdb, pg_ctl, postgres) and put it on PATH"
    printf 'postgres.sh: installing Debian'"'"'s postgresql package\n' >&2
    if ! { "${prefix[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update >&2 \
               && "${prefix[@]}" env DEBIAN_FRONTEND=noninteractive \
                      apt-get install -y --no-install-recommends postgresql >&2; }; then
        die "apt-get could not install the postgresql package"
    fi
}

# Run a command as the server's user (root: imucalib-pg; anyone else: themselves).
as_pg() {
    if [ "$(id -u)" -eq 0 ]; then
        if command -v runuser >/dev/null 2>&1; then
            runuser -u "$PG_SYSTEM_USER" -- "$@"
        else
            su -s /bin/bash -c "$(printf '%q ' "$@")" "$PG_SYSTEM_USER"
        fi
    else
        "$@"
    fi
}

server_user() {
    if [ "$(id -u)" -eq 0 ]; then
        printf '%s\n' "$PG_SYSTEM_USER"
    else
        id -un
    fi
}

ensure_system_user() {
    [ "$(id -u)" -eq 0 ] || return 0
    id -u "$PG_SYSTEM_USER" >/dev/null 2>&1 && return 0
    if command -v useradd >/dev/null 2>&1; then
        useradd --system --no-create-home --home-dir /nonexistent \
            --shell /usr/sbin/nologin "$PG_SYSTEM_USER"
    elif command -v adduser >/dev/null 2>&1; then
        adduser --system --no-create-home --disabled-login --group "$PG_SYSTEM_USER"
    else
        die "running as root and cannot create the user $PG_SYSTEM_USER (no useradd or adduser)"
    fi
}

free_port() {
    if command -v python3 >/dev/null 2>&1; then
        python3 -c 'import socket
s = socket.socket()
s.bind(("127.0.0.1", 0))
print(s.getsockname()[1])'
    else
        # 20000-59999; start() retries when it is taken.
        printf '%s\n' $((20000 + $(od -An -N2 -tu2 /dev/urandom) % 40000))
    fi
}

is_running() {
    local bindir=$1 data=$2
    [ -f "$data/postmaster.pid" ] && as_pg "$bindir/pg_ctl" -D "$data" status >/dev/null 2>&1
}

start() {
    local dir=$1 port=${2:-} bindir data user url tries
    bindir=$(find_bindir) || { install_postgresql; bindir=$(find_bindir) \
        || die "the postgresql package is installed but initdb/pg_ctl/postgres are not found"; }
    ensure_system_user
    mkdir -p "$dir"
    dir=$(cd "$dir" && pwd -P)
    data=$dir/data
    user=$(server_user)
    if [ "$(id -u)" -eq 0 ]; then
        chown -R "$PG_SYSTEM_USER" "$dir"
        chmod 700 "$dir"
        as_pg test -w "$dir" \
            || die "$PG_SYSTEM_USER cannot reach $dir: choose a folder whose parents it can enter"
    fi

    if is_running "$bindir" "$data"; then
        [ -f "$dir/url" ] || die "a server runs in $dir but $dir/url is missing"
        cat "$dir/url"
        return 0
    fi

    if [ ! -f "$data/PG_VERSION" ]; then
        as_pg "$bindir/initdb" -D "$data" -U "$user" --auth=trust --encoding=UTF8 \
            --no-locale >"$dir/initdb.log" 2>&1 \
            || { cat "$dir/initdb.log" >&2; die "initdb failed in $data"; }
        # Trust on the socket in DIR and on 127.0.0.1 only: no other host may connect.
        # (Rewriting the file keeps its owner, the server's user.)
        printf '%s\n' "local all all trust" "host all all 127.0.0.1/32 trust" \
            >"$data/pg_hba.conf"
    fi

    for tries in 1 2 3 4 5; do
        [ -n "$port" ] || port=$(free_port)
        if as_pg "$bindir/pg_ctl" -D "$data" -l "$dir/server.log" -w -t 60 \
                -o "-c listen_addresses=127.0.0.1 -p $port -k '$dir'" start >/dev/null; then
            break
        fi
        if [ -n "${2:-}" ] || [ "$tries" -eq 5 ]; then
            tail -n 20 "$dir/server.log" >&2 || true
            die "the server did not start on 127.0.0.1:$port (log: $dir/server.log)"
        fi
        port=  # a free port taken meanwhile: try another
    done

    # pg_ctl -w waited for the socket; wait for TCP connections too (60 s at most).
    for tries in $(seq 1 120); do
        if command -v pg_isready >/dev/null 2>&1 || [ -x "$bindir/pg_isready" ]; then
            PATH=$bindir:$PATH pg_isready -q -h 127.0.0.1 -p "$port" -U "$user" -d postgres \
                && break
        else
            as_pg "$bindir/pg_ctl" -D "$data" status >/dev/null 2>&1 && break
        fi
        [ "$tries" -lt 120 ] || die "the server on 127.0.0.1:$port accepts no connections"
        sleep 0.5
    done

    url="postgresql+psycopg://$user@127.0.0.1:$port/postgres"
    printf '%s\n' "$url" >"$dir/url"
    printf '%s\n' "$url"
}

stop() {
    local dir=$1 bindir data
    data=$dir/data
    [ -f "$data/postmaster.pid" ] || return 0
    bindir=$(find_bindir) || die "no PostgreSQL binaries to stop the server in $dir"
    if is_running "$bindir" "$data"; then
        as_pg "$bindir/pg_ctl" -D "$data" -m fast -w -t 60 stop >/dev/null
    fi
}

[ $# -ge 2 ] || usage
case $1 in
    start) [ $# -le 3 ] || usage; start "$2" "${3:-}" ;;
    stop) [ $# -eq 2 ] || usage; stop "$2" ;;
    *) usage ;;
esac
