#!/usr/bin/env bash
# Run after the tests: proves they left nothing behind in the source tree
# and that no test names an absolute path outside its temporary folders
# (a fresh CI machine lacks whatever such a path points at).
set -euo pipefail
cd "$(dirname "$0")/.."
left=$(git status --porcelain --untracked-files=all)
if [ -n "$left" ]; then
  echo "ci/check-clean.sh: the tests left files in the source tree:" >&2
  echo "$left" | head -20 >&2
  exit 1
fi
abs=$(grep -rnE '"/(nonexist[^"]*|tmp/[^"]*|root/[^"]*|home/[^"]*|var/[^"]*)"' \
      --include='*.rs' engine/tests inference/tests codec/tests engine/src inference/src codec/src 2>/dev/null || true)
if [ -n "$abs" ]; then
  echo "ci/check-clean.sh: tests name absolute paths outside their temp folders:" >&2
  echo "$abs" >&2
  exit 1
fi
