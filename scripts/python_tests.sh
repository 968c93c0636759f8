#!/usr/bin/env bash
# Builds servobus's Python package (python/) with pip and the pinned
# maturin, installs it into a kept virtualenv and runs its pytest suite
# (python/tests); then, with SERVOBUS_LEROBOT_PYTHON set (LeRobot's venv of
# scripts/python_clients.sh), installs the same wheel and
# python/lerobot_robot_servobus (and the pinned pytest) there and runs
# their pytest suite against the simulator. fmt and clippy of the extension crate come first.
#
# Usage: bash scripts/python_tests.sh [PYTEST_ARGS...]
# Env:   SERVOBUS_VENVS (default ~/.cache/servobus/venvs): the venv is
#        $SERVOBUS_VENVS/python-servobus, kept between runs;
#        CARGO_TARGET_DIR (default ./target): the extension is built there,
#        beside the workspace's crates, so they are not built twice.
#
# Idempotent: a ready virtualenv is kept (its tools are pinned); the
# package is rebuilt (incrementally) and reinstalled on every run.
set -euo pipefail
cd "$(dirname "$0")/.."

root=${SERVOBUS_VENVS:-$HOME/.cache/servobus/venvs}
venv=$root/python-servobus
say() { printf '%s\n' "$*" >&2; }

# The build and test tools, pinned: maturin as in python/pyproject.toml.
tools=('maturin==1.16.0' 'pytest==8.3.4' 'numpy==2.2.6')

# What this run creates and runs, before any of it.
if [ -e "$venv/.ready" ]; then
    say "python_tests.sh: uses the kept virtualenv $venv (SERVOBUS_VENVS sets where)"
else
    say "python_tests.sh: creates the virtualenv $venv (SERVOBUS_VENVS sets where; kept for later runs)"
    say "  and installs ${tools[*]} into it with pip"
fi
say "  then runs: cargo fmt --check, clippy and cargo test --lib in python/;"
say "  pip wheel + pip install ./python into that virtualenv (extension built in ${CARGO_TARGET_DIR:-$PWD/target});"
say "  pytest python/tests;"
if [ -n "${SERVOBUS_LEROBOT_PYTHON:-}" ]; then
    say "  and installs the wheel, python/lerobot_robot_servobus and pytest==8.3.4 into LeRobot's"
    say "  virtualenv ($SERVOBUS_LEROBOT_PYTHON), then runs pytest python/lerobot_robot_servobus/tests"
else
    say "  the LeRobot check is left out: SERVOBUS_LEROBOT_PYTHON is not set"
fi

if [ ! -e "$venv/.ready" ]; then
    py=${SERVOBUS_PYTHON:-python3}
    if ! "$py" -c 'import sys; sys.exit(sys.version_info < (3, 10))' 2>/dev/null; then
        say "FAIL the Python package needs Python >= 3.10 (set SERVOBUS_PYTHON)"
        exit 1
    fi
    say "setting up $venv"
    rm -rf "$venv"
    mkdir -p "$root"
    "$py" -m venv "$venv"
    if ! "$venv/bin/pip" install -q --disable-pip-version-check "${tools[@]}" >"$venv/pip.log" 2>&1; then
        cat "$venv/pip.log" >&2
        say "FAIL pip could not install ${tools[*]}"
        exit 1
    fi
    touch "$venv/.ready"
fi

export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$PWD/target}
# The extension is outside the workspace: the workspace's fmt and clippy do
# not see it.
say "cargo fmt --check, cargo clippy -D warnings and cargo test --lib in python/"
(cd python && cargo fmt -- --check && cargo clippy --quiet --all-targets -- -D warnings && cargo test --quiet --lib)
# maturin's build hook runs the `maturin` command of the venv.
export PATH="$venv/bin:$PATH"
# The pinned maturin of the venv builds the package once, as a wheel (no
# isolated build environment to download every run) ...
wheels=$(mktemp -d)
trap 'rm -rf "$wheels"' EXIT
say "pip install ./python (target directory $CARGO_TARGET_DIR)"
if ! "$venv/bin/pip" wheel -q --disable-pip-version-check --no-build-isolation --no-deps \
    -w "$wheels" ./python >"$venv/install.log" 2>&1 ||
    ! "$venv/bin/pip" install -q --disable-pip-version-check --force-reinstall --no-deps \
        "$wheels"/servobus-*.whl >>"$venv/install.log" 2>&1; then
    cat "$venv/install.log" >&2
    say "FAIL the Python package did not build"
    exit 1
fi

# ... and the pytest suite runs from the tests' directory, so that
# `import servobus` is the installed package, not the source tree.
(cd python/tests && "$venv/bin/python" -m pytest -q -p no:cacheprovider "$@" .)

# LeRobot's SO-101 follower code path with the so101_servobus robot type, in
# the pinned LeRobot venv of scripts/python_clients.sh (its Python is given
# by SERVOBUS_LEROBOT_PYTHON, which `eval "$(scripts/python_clients.sh)"`
# sets): the same wheel and the pure-Python lerobot_robot_servobus into it.
lerobot=${SERVOBUS_LEROBOT_PYTHON:-}
if [ -z "$lerobot" ]; then
    if [ "${CI:-}" = true ]; then
        say "FAIL SERVOBUS_LEROBOT_PYTHON is not set: run eval \"\$(bash scripts/python_clients.sh)\" first"
        exit 1
    fi
    say "SKIPPED the LeRobot check: SERVOBUS_LEROBOT_PYTHON is not set (eval \"\$(bash scripts/python_clients.sh)\")"
    exit 0
fi
say "lerobot_robot_servobus against the simulator with $lerobot"
if ! "$lerobot" -m pip install -q --disable-pip-version-check --force-reinstall --no-deps \
    "$wheels"/servobus-*.whl ./python/lerobot_robot_servobus >"$venv/lerobot-install.log" 2>&1 ||
    ! "$lerobot" -m pip install -q --disable-pip-version-check 'pytest==8.3.4' \
        >>"$venv/lerobot-install.log" 2>&1; then
    cat "$venv/lerobot-install.log" >&2
    say "FAIL servobus, lerobot_robot_servobus or pytest did not install into LeRobot's venv"
    exit 1
fi
(cd python/lerobot_robot_servobus/tests && "$lerobot" -m pytest -q -p no:cacheprovider .)
