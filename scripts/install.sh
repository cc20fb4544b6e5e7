#!/usr/bin/env bash
# Install evomotion (editable) and, when possible, the OSMesa library for offscreen videos.
# Usage: scripts/install.sh          -> runtime dependencies
#        scripts/install.sh test     -> plus the test tools (pytest, hypothesis, ruff, pycma,
#                                       NiceGUI, Playwright and Debian's chromium)
set -euo pipefail
cd "$(dirname "$0")/.."
extras=""
[ "${1:-}" = "test" ] && extras="[test]"
python3 -m pip install --quiet --disable-pip-version-check --root-user-action=ignore -e ".${extras}"
# The studio's browser tests drive Debian's Chromium with Playwright (never Playwright's own
# browser download).
if [ "${1:-}" = "test" ] && ! command -v chromium >/dev/null; then
  if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null; then
    (apt-get update -qq && apt-get install -y -qq chromium) >/dev/null 2>&1 \
      || echo "note: chromium could not be installed; the studio's browser tests are skipped" >&2
  else
    echo "note: install Debian's chromium for the studio's browser tests" >&2
  fi
fi
# Offscreen rendering on the CPU needs Debian's libosmesa6 (videos are skipped without it).
if ! ldconfig -p 2>/dev/null | grep -q libOSMesa; then
  if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null; then
    (apt-get update -qq && apt-get install -y -qq libosmesa6) >/dev/null 2>&1 \
      || echo "note: libosmesa6 could not be installed; videos will be skipped" >&2
  else
    echo "note: install libosmesa6 (or provide EGL) for videos; they are skipped otherwise" >&2
  fi
fi
