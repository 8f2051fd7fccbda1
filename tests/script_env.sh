# script_env.sh - sourced (with BUILD set) by the test and benchmark scripts that run the release
# programs: cd to the repository's root and set REL (BUILD's release programs), PY (the PyPI
# venv's Python, or $PY), PYTHONPATH (BUILD's lcm-gen Python types) and TMP (a fresh folder,
# removed at exit unless KEEP is set; a script that needs more at exit sets its own trap after).
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT" || exit 1
REL=$BUILD/release
PY=${PY:-.venv/bin/python}
export PYTHONPATH=$BUILD/lcmgen/python
TMP=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$TMP"' EXIT
