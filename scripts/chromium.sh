#!/usr/bin/env bash
# Debian's chromium for the web page's browser tests (tests/web/test_browser.py; .ci/run).
#
#   scripts/chromium.sh     print the path of a chromium binary, installing Debian's
#                           `chromium` package with apt-get (through sudo when not root) when
#                           there is none; exit 1 with one line when it cannot
#
# `playwright install` downloads its own browsers from the network, which CI cannot reach;
# the tests launch this binary instead (Playwright's `executable_path`). A binary named by
# $IMUCALIB_TEST_CHROMIUM is used as it is.
set -euo pipefail

die() {
    printf 'chromium.sh: %s\n' "$*" >&2
    exit 1
}

find_chromium() {
    local candidate
    for candidate in "${IMUCALIB_TEST_CHROMIUM:-}" /usr/bin/chromium /usr/bin/chromium-browser; do
        if [ -n "$candidate" ] && [ -x "$candidate" ]; then
            printf '%s\n' "$candidate"
            return 0
        fi
    done
    return 1
}

if find_chromium; then
    exit 0
fi

prefix=()
if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null 2>&1 \
        || die "no chromium found and not root, and sudo is missing: install Debian's chromium package"
    prefix=(sudo -n)
fi
command -v apt-get >/dev/null 2>&1 \
    || die "no chromium found and apt-get is missing: install chromium and set IMUCALIB_TEST_CHROMIUM"
printf 'chromium.sh: installing Debian'"'"'s chromium package\n' >&2
if ! { "${prefix[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -qq >&2 \
           && "${prefix[@]}" env DEBIAN_FRONTEND=noninteractive \
                  apt-get install -y -qq --no-install-recommends chromium >&2; }; then
    die "apt-get could not install the chromium package"
fi
find_chromium || die "the chromium package was installed but no chromium binary was found"
