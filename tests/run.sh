#!/usr/bin/env bash
# The README's test command: installs everything the tests need, then runs them.
#
#   bash tests/run.sh [--editable] [pytest arguments ...]
#
# 1. Debian packages: CalculiX (ccx, the independent cross-check), Chromium (browser tests) and the
#    GL/X libraries gmsh's wheel loads.  Missing ones are installed with apt-get when run as root;
#    otherwise the apt-get command is printed and the script fails.  A failed install fails the
#    script: a test that needs a missing program fails, it never skips (tests/conftest.py).
# 2. Python: the active virtual environment, else $RIGFEM_VENV (default .venv/ here, created when
#    missing); rigfem is installed into it with its test extras: a regular install, or an
#    editable one with --editable.
# 3. pytest with the remaining arguments.  "No tests collected" (pytest's exit 5) is a failure.
set -euo pipefail
cd "$(dirname "$0")/.."
editable=()
if [ "${1-}" = "--editable" ]; then editable=(-e); shift; fi

debs=(calculix-ccx chromium python3-venv libglu1-mesa libgl1 libxrender1 libxcursor1 libxft2 libxinerama1)
missing=()
for d in "${debs[@]}"; do
  dpkg-query -W -f='${Status}' "$d" 2>/dev/null | grep -q "ok installed" || missing+=("$d")
done
if [ ${#missing[@]} -gt 0 ]; then
  if [ "$(id -u)" -ne 0 ]; then
    echo "tests/run.sh: the tests need these Debian packages; install them, then run this again:" >&2
    echo "  sudo apt-get update && sudo apt-get install -y ${missing[*]}" >&2
    exit 1
  fi
  echo "tests/run.sh: apt-get install ${missing[*]}"
  if ! { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null; }
  then
    echo "tests/run.sh: apt-get could not install ${missing[*]}: the tests cannot all run" >&2
    exit 1
  fi
fi

venv=${VIRTUAL_ENV:-${RIGFEM_VENV:-.venv}}
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
# shellcheck disable=SC1091
. "$venv/bin/activate"
python -m pip install -q "${editable[@]}" ".[test]"

status=0
pytest "$@" || status=$?
if [ "$status" -eq 5 ]; then
  echo "tests/run.sh: pytest collected no tests (arguments: $*): nothing was checked" >&2
  exit 1
fi
exit "$status"
