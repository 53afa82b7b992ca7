#!/usr/bin/env bash
# Installs mufusion with everything it needs into the current Python environment.
#
# Order matters: comma-deps-acados ships a slim CasADi (no IPOPT) into site-packages/casadi/,
# which would shadow the full CasADi wheel. Installing the full CasADi *after* it, without
# dependencies, restores IPOPT (used by the reference backend and the do-mpc benchmark) while
# acados' code generation keeps working with it.
set -euo pipefail
cd "$(dirname "$0")"
PY=${PYTHON:-python3}
"$PY" -m pip install --upgrade pip >/dev/null
# The CommonRoad import's commonroad-io pins protobuf==3.20.2, which Ray >= 2.49 refuses: the
# bound lets pip settle at once instead of backtracking through Ray's wheels for minutes
# (docs/decisions/0059).
"$PY" -m pip install -e ".[dev,bench,scale,commonroad]" "ray<2.49"
"$PY" -m pip install --no-deps --force-reinstall "casadi==3.8.2"
"$PY" -c "import casadi, mufusion; print('mufusion', mufusion.__version__, '| casadi', casadi.__version__)"
