#!/bin/sh
# The Blender loader test (ctest label `blender`): runs Blender headless on
# check_loader.py. Exits 77 (ctest SKIP_RETURN_CODE) when Blender is absent.
# Usage: run_blender_test.sh TOOLS_DIR CHECK_SCRIPT WORK_DIR
set -eu
if ! command -v blender >/dev/null 2>&1; then
  echo "SKIP: blender is not installed (Debian: apt-get install blender); the loader test needs it"
  exit 77
fi
rm -rf "$3"
mkdir -p "$3"
exec blender -b --factory-startup --python-exit-code 1 --python "$2" -- "$1" "$3"
