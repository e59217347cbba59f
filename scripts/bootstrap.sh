#!/bin/sh
# Set up everything clothsim needs on a Debian machine that has only Python:
#   system packages (SuiteSparse for CHOLMOD, OpenBLAS, venv; optionally g++ and Eigen for
#   the C++ example port) via apt when root and missing,
#   a virtual environment .venv at the repository root, the package with its extras.
# Idempotent and quiet when nothing is missing. Usage: sh scripts/bootstrap.sh
set -eu
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-python3}
VENV=.venv

missing=""
[ -e /usr/include/suitesparse/cholmod.h ] || missing="$missing libsuitesparse-dev"
ls /usr/lib/*/libopenblas*.so* >/dev/null 2>&1 || ls /usr/lib/*/openblas-pthread >/dev/null 2>&1 || missing="$missing libopenblas0-pthread"
"$PYTHON" -c "import ensurepip, venv" >/dev/null 2>&1 || missing="$missing python3-venv"
command -v cc >/dev/null 2>&1 || missing="$missing gcc"
# optional, for the compiled example port (examples/ports/cpp); its tests skip without them
optional=""
command -v g++ >/dev/null 2>&1 || optional="$optional g++"
[ -e /usr/include/eigen3/Eigen/Sparse ] || optional="$optional libeigen3-dev"
if [ -n "$missing" ]; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
        echo "bootstrap: installing system packages:$missing"
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $missing >/dev/null
    else
        echo "bootstrap: warning: missing system packages:$missing (not root or no apt-get);" \
             "clothsim will fall back to scipy's SuperLU" >&2
    fi
fi
if [ -n "$optional" ]; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
        echo "bootstrap: installing optional system packages:$optional"
        [ -n "$missing" ] || apt-get update -qq || true
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $optional >/dev/null ||
            echo "bootstrap: warning: could not install$optional; the C++ port's tests will skip" >&2
    else
        echo "bootstrap: note: optional packages missing:$optional (the C++ port's tests skip)" >&2
    fi
fi

[ -x "$VENV/bin/python" ] || "$PYTHON" -m venv "$VENV"
stamp="$VENV/.clothsim-installed"
if [ ! -e "$stamp" ] || [ pyproject.toml -nt "$stamp" ]; then
    "$VENV/bin/python" -m pip install -q --upgrade pip
    "$VENV/bin/python" -m pip install -q -e ".[test,docs,cluster]"
    # CHOLMOD is optional: without SuiteSparse the build fails and clothsim uses SuperLU.
    if ! "$VENV/bin/python" -m pip install -q -e ".[cholmod]"; then
        echo "bootstrap: warning: scikit-sparse did not build; the SuperLU fallback will be used" >&2
    fi
    touch "$stamp"
fi
