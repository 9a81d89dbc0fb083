#!/bin/sh
# Runs COMMAND with the kernel's transparent-huge-page mode set to MODE (always, madvise or never; needs root), for
# A/B timings of one binary: e.g. as variants of tools/compare_builds.py (docs/PERFORMANCE.md, huge pages).
# The mode stays set after the command; Debian's default is madvise.
# Usage: tools/with_thp.sh MODE COMMAND [ARG ...]
set -eu
case "${1:-}" in
  always|madvise|never) ;;
  *) echo "with_thp.sh: MODE must be always, madvise or never, got '${1:-}'" >&2; exit 2 ;;
esac
[ $# -ge 2 ] || { echo "with_thp.sh: no COMMAND after MODE" >&2; exit 2; }
echo "$1" > /sys/kernel/mm/transparent_hugepage/enabled
shift
exec "$@"
