#!/usr/bin/env bash
# Create the SEPARATE virtualenv that holds the reference implementation
# (PyPI package `fabrics` 0.10.0, tud-amr/fabrics) used by our benchmark.
#
# `fabrics` pins numpy<2 (and old forwardkinematics / pytest versions), so it can
# never be a dependency of dynfab itself; it lives in <repo>/.venv-reference,
# which is gitignored.  Everything is installed from PyPI with pip.
#
# Idempotent: re-running it reuses an existing, working environment.
# Exits non-zero with a message if the installation fails.
#
# Environment:
#   PYTHON   interpreter used to create the venv (default: python3)
#   DYNFAB_REFERENCE_VENV  venv location (default: <repo>/.venv-reference)
set -euo pipefail

REPO_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${DYNFAB_REFERENCE_VENV:-$REPO_ROOT/.venv-reference}"
PYTHON="${PYTHON:-python3}"
FABRICS_VERSION="0.10.0"

fail() {
    echo "setup_reference.sh: ERROR: $*" >&2
    exit 1
}

check_installed() {
    "$VENV/bin/python" - "$FABRICS_VERSION" <<'EOF' >/dev/null 2>&1
import sys
from importlib.metadata import version
assert version("fabrics") == sys.argv[1]
import numpy, casadi, forwardkinematics  # noqa: F401
from fabrics.planner.parameterized_planner import ParameterizedFabricPlanner  # noqa: F401
from forwardkinematics.urdfFks.generic_urdf_fk import GenericURDFFk  # noqa: F401
EOF
}

command -v "$PYTHON" >/dev/null 2>&1 || fail "no interpreter '$PYTHON' found (set PYTHON=...)"

if [ -x "$VENV/bin/python" ] && check_installed; then
    echo "reference environment already set up: $VENV (fabrics==$FABRICS_VERSION)"
    exit 0
fi

if [ ! -x "$VENV/bin/python" ]; then
    echo "creating virtualenv $VENV"
    "$PYTHON" -m venv "$VENV" || fail "could not create virtualenv at $VENV ('$PYTHON -m venv' failed)"
fi

echo "installing fabrics==$FABRICS_VERSION into $VENV (from PyPI)"
"$VENV/bin/python" -m pip install --disable-pip-version-check --quiet --upgrade pip \
    || fail "could not upgrade pip inside $VENV"
"$VENV/bin/python" -m pip install --disable-pip-version-check "fabrics==$FABRICS_VERSION" \
    || fail "pip could not install fabrics==$FABRICS_VERSION into $VENV (see pip output above)"

if ! check_installed; then
    # Show the real import error for diagnosis.
    "$VENV/bin/python" -c "
from fabrics.planner.parameterized_planner import ParameterizedFabricPlanner
from forwardkinematics.urdfFks.generic_urdf_fk import GenericURDFFk
" || true
    fail "fabrics==$FABRICS_VERSION was installed but does not import in $VENV"
fi

echo "reference environment ready: $VENV"
"$VENV/bin/python" -m pip list --disable-pip-version-check 2>/dev/null \
    | grep -Ei '^(fabrics|forwardkinematics|casadi|numpy|mpscenes|geomdl) ' || true
