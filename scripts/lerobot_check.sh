#!/usr/bin/env bash
# Runs Hugging Face LeRobot's FeetechMotorsBus, unchanged, against the simulated
# SO-101 arm: crates/sim/tests/python/lerobot_check.py says what it checks.
#
# Usage: scripts/lerobot_check.sh [--scan]
# Env:   LEROBOT_VENV (default /tmp/lerobot-venv), PYTHON (a Python >= 3.12).
# Creates the virtualenv on first use (LeRobot without torch, and only the
# packages its motors code imports), builds servobus if needed, serves the arm
# on a pseudo-terminal, runs the check and stops the simulator on exit.
set -euo pipefail

cd "$(dirname "$0")/.."
venv=${LEROBOT_VENV:-/tmp/lerobot-venv}

if [ ! -e "$venv/.lerobot-check-ready" ]; then
    py=${PYTHON:-}
    if [ -z "$py" ]; then
        # pyenv's shims refuse a version that is not selected: try its builds directly too.
        for c in python3.12 python3.13 python3 "${PYENV_ROOT:-$HOME/.pyenv}"/versions/3.1[2-9]*/bin/python3; do
            if "$c" -c 'import sys; sys.exit(sys.version_info < (3, 12))' 2>/dev/null; then
                py=$c
                break
            fi
        done
    fi
    [ -n "$py" ] || { echo "FAIL LeRobot 0.5+ needs Python >= 3.12 (set PYTHON)"; exit 1; }
    "$py" -m venv "$venv"
    "$venv/bin/pip" install -q --no-deps lerobot==0.6.1
    # pip warns that lerobot's torch, torchvision, ... are missing: on purpose, logged aside.
    "$venv/bin/pip" install -q 'tqdm>=4.66,<5' 'feetech-servo-sdk>=1.0.0,<2' 'pyserial>=3.5,<4' \
        'deepdiff>=7.0.1,<9' 'huggingface-hub>=1.6,<2' 'numpy>=2.0,<2.3' 'draccus>=0.11.6,<0.12' \
        >"$venv/pip.log" 2>&1 || { cat "$venv/pip.log"; exit 1; }
    touch "$venv/.lerobot-check-ready"
fi

[ -x target/release/servobus ] || cargo build --release

dir=$(mktemp -d)
link=$dir/arm
sim_pid=
cleanup() {
    if [ -n "$sim_pid" ]; then
        kill -INT "$sim_pid" 2>/dev/null || true
        wait "$sim_pid" 2>/dev/null || true
    fi
    rm -rf "$dir"
}
trap cleanup EXIT

./target/release/servobus sim --robot configs/robots/so101.yaml --link "$link" >"$dir/sim.log" 2>&1 &
sim_pid=$!
for _ in $(seq 50); do
    [ -e "$link" ] && break
    kill -0 "$sim_pid" 2>/dev/null || { cat "$dir/sim.log"; echo "FAIL simulator exited"; exit 1; }
    sleep 0.1
done
[ -e "$link" ] || { echo "FAIL simulator did not create $link"; exit 1; }

"$venv/bin/python" crates/sim/tests/python/lerobot_check.py "$link" "$@"
