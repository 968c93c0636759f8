#!/usr/bin/env bash
# Prepares the outside servo software that servobus's simulator is checked
# against, each in its own virtualenv, and prints the environment lines that
# point the tests at them:
#
#   SERVOBUS_FEETECH_PYTHON=...   a Python with Feetech's SDK (scservo_sdk)
#   SERVOBUS_LEROBOT_PYTHON=...   a Python with LeRobot's FeetechMotorsBus
#   SERVOBUS_ZENOH_PYTHON=...     a Python with eclipse-zenoh and rosbags
#   SERVOBUS_RERUN_PYTHON=...     a Python with Rerun's SDK (rerun-sdk)
#
# Usage: eval "$(scripts/python_clients.sh)"
# Env:   SERVOBUS_VENVS (default ~/.cache/servobus/venvs).
#
# Idempotent: a virtualenv that is ready is kept. Progress and pip's output
# go to stderr; a client that cannot be installed is an error (exit 1), so a
# gate that calls this never goes on without the checks.
set -euo pipefail

root=${SERVOBUS_VENVS:-$HOME/.cache/servobus/venvs}
mkdir -p "$root"

say() { printf '%s\n' "$*" >&2; }

# The first Python at or above $1 (as "3.12"), trying pyenv's builds directly
# too: its shims refuse a version that is not selected.
python_at_least() {
    local want=$1 c
    for c in python3 python3.12 python3.13 "${PYENV_ROOT:-$HOME/.pyenv}"/versions/3.1[0-9]*/bin/python3; do
        if "$c" -c "import sys; sys.exit(sys.version_info < tuple(map(int, '$want'.split('.'))))" 2>/dev/null; then
            printf '%s\n' "$c"
            return 0
        fi
    done
    return 1
}

# make_venv NAME MIN_PYTHON PIP_ARGS... : a ready virtualenv's python.
make_venv() {
    local name=$1 want=$2 dir py
    shift 2
    dir=$root/$name
    if [ ! -e "$dir/.ready" ]; then
        py=$(python_at_least "$want") || { say "FAIL $name needs Python >= $want"; return 1; }
        say "setting up $name in $dir (Python $("$py" -c 'import platform; print(platform.python_version())'))"
        rm -rf "$dir"
        "$py" -m venv "$dir"
        if ! "$dir/bin/pip" install -q --disable-pip-version-check "$@" >"$dir/pip.log" 2>&1; then
            cat "$dir/pip.log" >&2
            say "FAIL pip could not install $name"
            return 1
        fi
        touch "$dir/.ready"
    fi
    printf '%s\n' "$dir/bin/python"
}

# Feetech's SDK, pinned: the module LeRobot drives the servos with.
feetech=$(make_venv feetech-sdk 3.8 'feetech-servo-sdk==1.0.0' 'pyserial>=3.5,<4')

# LeRobot without PyTorch: the package itself without its dependencies, then
# only what its motors code imports. 0.6.1 is the newest release, and needs
# Python 3.12; lerobot_check.py stands in for torch, which the motors code
# imports but never calls.
lerobot=$(make_venv lerobot-0.6.1 3.12 --no-deps 'lerobot==0.6.1')
if [ ! -e "$root/lerobot-0.6.1/.deps-ready" ]; then
    if ! "$lerobot" -m pip install -q --disable-pip-version-check \
        'tqdm>=4.66,<5' 'feetech-servo-sdk>=1.0.0,<2' 'pyserial>=3.5,<4' \
        'deepdiff>=7.0.1,<9' 'huggingface-hub>=1.6,<2' 'numpy>=2.0,<2.3' \
        'draccus>=0.11.6,<0.12' >"$root/lerobot-0.6.1/deps.log" 2>&1; then
        cat "$root/lerobot-0.6.1/deps.log" >&2
        say "FAIL pip could not install LeRobot's motor dependencies"
        exit 1
    fi
    touch "$root/lerobot-0.6.1/.deps-ready"
fi

# A Zenoh peer and ROS 2's CDR decoder, pinned: the clients of `servobus
# serve` in tests/serve_cli.rs.
zenoh_py=$(make_venv zenoh-1.10.1 3.9 'eclipse-zenoh==1.10.1' 'rosbags==0.10.11')

# Rerun's Python SDK, pinned to the release of the Rust `rerun` crate that
# servobus records with (crates/robot/Cargo.toml): the independent reader
# of the recordings in tests/rerun_cli.rs.
rerun_py=$(make_venv rerun-sdk-0.36.3 3.10 'rerun-sdk[datafusion]==0.36.3')

"$feetech" -c 'import scservo_sdk' || { say "FAIL scservo_sdk does not import"; exit 1; }
"$lerobot" -c "import scservo_sdk, deepdiff, draccus" ||
    { say "FAIL lerobot does not import"; exit 1; }
"$zenoh_py" -c "import zenoh, rosbags" || { say "FAIL eclipse-zenoh does not import"; exit 1; }
"$rerun_py" -c "import rerun, rerun.experimental, datafusion" || { say "FAIL rerun-sdk does not import"; exit 1; }

printf 'export SERVOBUS_FEETECH_PYTHON=%q\n' "$feetech"
printf 'export SERVOBUS_LEROBOT_PYTHON=%q\n' "$lerobot"
printf 'export SERVOBUS_ZENOH_PYTHON=%q\n' "$zenoh_py"
printf 'export SERVOBUS_RERUN_PYTHON=%q\n' "$rerun_py"
