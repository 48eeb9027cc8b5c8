#!/usr/bin/env bash
# Spark-DSG anchor for `ygg-bench ladder`.
#
#   bench/spark_dsg/run.sh --dsg FILE.json --workload WORKLOAD.json --out ROWS.json [--quick]
#
# Creates once (and then reuses) a virtual environment at ${YGG_VENV:-target/spark-dsg-venv}
# (relative paths are taken from the repository root) with spark-dsg==1.1.3, numpy and
# scipy, then runs anchor.py in it. Progress goes to stderr.
# Exit codes: 0 ok; 2 the environment could not be set up (no python3/venv, pip or
# network failure: report the anchor as unavailable); 3 the anchor failed (bad input,
# or its paths disagree); anything else: anchor.py crashed.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
venv="${YGG_VENV:-target/spark-dsg-venv}"
case "$venv" in /*) ;; *) venv="$root/$venv" ;; esac
python="${YGG_PYTHON:-python3}"
reqs=(spark-dsg==1.1.3 numpy scipy)
stamp="$venv/.ygg-anchor-ready"

say() { echo "[spark-dsg anchor] $*" >&2; }
unavailable() { say "UNAVAILABLE: $*"; exit 2; }

setup() {
    command -v "$python" >/dev/null 2>&1 || unavailable "no '$python' on PATH (set YGG_PYTHON)"
    if [ ! -x "$venv/bin/python" ]; then
        say "creating virtual environment $venv (once) with $("$python" --version 2>&1)"
        mkdir -p "$(dirname "$venv")"
        "$python" -m venv "$venv" >&2 \
            || unavailable "'$python -m venv' failed (on Debian: apt-get install python3-venv)"
    fi
    say "pip install ${reqs[*]} into $venv (needs PyPI) ..."
    if ! "$venv/bin/python" -m pip install --disable-pip-version-check --no-input -q \
            --timeout 30 --retries 2 "${reqs[@]}" >&2; then
        unavailable "pip install ${reqs[*]} failed (network or no wheel for $("$venv/bin/python" --version 2>&1))"
    fi
    "$venv/bin/python" -c 'import spark_dsg, numpy, scipy.spatial' >&2 \
        || unavailable "spark_dsg/numpy/scipy installed but do not import"
    echo "${reqs[*]}" > "$stamp"
    say "environment ready"
}

ready() { [ -x "$venv/bin/python" ] && [ -f "$stamp" ] && [ "$(cat "$stamp")" = "${reqs[*]}" ]; }

if ! ready; then
    # serialise concurrent first runs when flock is available
    if command -v flock >/dev/null 2>&1; then
        mkdir -p "$(dirname "$venv")"
        exec 9>"$venv.lock"
        flock 9
        ready || setup
        flock -u 9
    else
        setup
    fi
fi

exec "$venv/bin/python" "$here/anchor.py" "$@"
