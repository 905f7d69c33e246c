#!/bin/sh
# Creates (or reuses) the project's virtual environment and installs gearjax into it.
#
#     sh tools/setup_env.sh VENV EXTRAS [PYTHON]
#
# The interpreter is PYTHON when given, else the newest Python >= 3.12 found: python3.14,
# python3.13, python3.12 and python3 on PATH, then pyenv's installed versions
# ($PYENV_ROOT/versions, default ~/.pyenv/versions); else python3. A current JAX (>= 0.11.1)
# needs Python >= 3.12; an older interpreter gets jax 0.10.2 with its workarounds, and one
# line says what that costs. A venv made from another interpreter version is made anew.
# Prints the interpreter and the JAX it installed.
set -eu
VENV=$1
EXTRAS=$2
PYTHON=${3:-}

# the interpreter's version as "3 13 0", or nothing if it does not run
version_of() {
    "$1" -c 'import sys; print(*sys.version_info[:3])' 2>/dev/null || true
}

# prints the candidate with the highest version >= 3.12, or nothing
newest_current() {
    best="" best_key=0
    for cand in "$@"; do
        v=$(version_of "$cand")
        [ -n "$v" ] || continue
        set -- $v
        key=$(( $1 * 10000 + $2 * 100 + $3 ))
        if [ "$key" -ge 31200 ] && [ "$key" -gt "$best_key" ]; then
            best=$("$cand" -c 'import sys; print(sys.executable)') best_key=$key
        fi
    done
    printf '%s' "$best"
}

if [ -z "$PYTHON" ]; then
    pyenv_root=${PYENV_ROOT:-$HOME/.pyenv}
    PYTHON=$(newest_current python3.14 python3.13 python3.12 python3 "$pyenv_root"/versions/3.*/bin/python3)
    [ -n "$PYTHON" ] || PYTHON=python3
fi

wanted=$(version_of "$PYTHON")
if [ -z "$wanted" ]; then
    echo "gearjax set-up: error: the interpreter '$PYTHON' does not run" >&2
    exit 2
fi
if [ -x "$VENV/bin/python" ] && [ "$(version_of "$VENV/bin/python")" != "$wanted" ]; then
    echo "gearjax set-up: $VENV was made with another Python; making it anew with $PYTHON"
    rm -rf "$VENV"
fi
if [ ! -x "$VENV/bin/python" ]; then
    "$PYTHON" -m venv "$VENV"
    "$VENV/bin/python" -m pip install --quiet --upgrade pip
fi
"$VENV/bin/python" -m pip install --quiet -e ".[$EXTRAS]"
"$VENV/bin/python" - <<'EOF'
import sys
import jax, jaxlib
import os
print(f"gearjax set-up: Python {sys.version.split()[0]} ({os.path.realpath(sys.executable)}), jax {jax.__version__}, "
      f"jaxlib {jaxlib.__version__}")
if sys.version_info < (3, 12):
    print(f"gearjax set-up: note: Python {sys.version_info[0]}.{sys.version_info[1]} gets jax {jax.__version__}, whose "
          "programs run 1.5-3x slower and whose gradient programs cannot be cached; with Python >= 3.12 "
          "(e.g. 'pyenv install 3.13', then 'make clean demo') pip installs a current JAX")
EOF
