#!/usr/bin/env bash
# Drives `servobus monitor` in a real terminal (tmux) against the simulated
# SO-101 arm with servo 3 overheating and servo 5 disconnected, and reads
# the screen back with `tmux capture-pane`:
#   - servo 3's row shows the OVERHEAT flag, servo 5's row shows MISSING;
#   - the other servos' reply counts go up from one screen to the next;
#   - the keys are on screen; Space sends torque off and says so;
#   - `q` leaves the terminal as it was: main screen back, cursor visible,
#     the same stty settings, the shell prompt usable.
#
# Usage: scripts/monitor_tmux.sh [SERVOBUS_BINARY]
# (default: target/debug/servobus, built with `cargo build`).
# Exit 0: every check passed; 1: a check failed; 77: tmux is not installed.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
bin=${1:-$root/target/debug/servobus}
robot=$root/configs/robots/so101.yaml

if ! command -v tmux >/dev/null 2>&1; then
    echo "SKIP: tmux is not installed (apt-get install -y tmux)"
    exit 77
fi
[ -x "$bin" ] || { echo "FAIL: no servobus binary at $bin (cargo build first)"; exit 1; }

dir=$(mktemp -d)
session="servobus-monitor-$$"
sim_pid=""
cleanup() {
    tmux kill-session -t "$session" 2>/dev/null || true
    if [ -n "$sim_pid" ]; then kill "$sim_pid" 2>/dev/null || true; wait "$sim_pid" 2>/dev/null || true; fi
    rm -rf "$dir"
}
trap cleanup EXIT

fail() {
    echo "FAIL: $*"
    echo "---- screen ----"
    tmux capture-pane -p -t "$session" 2>/dev/null || true
    exit 1
}

# The simulator, with the faults under test.
"$bin" sim --robot "$robot" --link "$dir/bus" --faults overheat=3,vanish=5 >"$dir/sim.out" 2>&1 &
sim_pid=$!
for _ in $(seq 1 300); do
    grep -q "^serving" "$dir/sim.out" 2>/dev/null && break
    sleep 0.1
done
grep -q "^serving 6 servos" "$dir/sim.out" || { cat "$dir/sim.out"; echo "FAIL: sim did not start"; exit 1; }

# A plain shell in a 160x30 terminal; note its settings before the monitor.
# Waits until the screen shows $1 (a grep pattern), up to 30 s.
wait_for() {
    for _ in $(seq 1 300); do
        tmux capture-pane -p -t "$session" | grep -q -- "$1" && return 0
        sleep 0.1
    done
    return 1
}
tmux new-session -d -s "$session" -x 160 -y 30 "env PS1='prompt> ' bash --norc --noprofile"
wait_for "^prompt>" || fail "the shell did not start"
tmux send-keys -t "$session" "stty -g > $dir/stty.before; echo before-monitor" Enter
wait_for "^before-monitor$" || fail "the shell did not run the first command"
tmux send-keys -t "$session" "$bin monitor --robot $robot --port $dir/bus" Enter

# The field $2 of servo $1's row on the screen $3.
field() {
    echo "$3" | awk -v id="$1" -v f="$2" '$1 == id && $3 ~ /^STS/ { print $f; exit }'
}

wait_for "wrist_roll.*MISSING" || fail "servo 5 is not shown as missing"
# Servo 5 has been silent for a while now (five refreshes at least); its
# row must stay marked.
sleep 0.5
screen1=$(tmux capture-pane -p -t "$session")
echo "$screen1" | grep -q "^5 .*wrist_roll.*MISSING (no reply)" || fail "servo 5 is not shown as missing"
echo "PASS: servo 5 shows as missing"
echo "$screen1" | grep -q "^3 .*elbow_flex.*OVERHEAT" || fail "servo 3 does not show the overheat flag"
echo "PASS: servo 3 shows the overheat flag"
echo "$screen1" | grep -q "keys: q quit   Space torque OFF" || fail "the keys are not shown"
echo "PASS: the keys are on screen"
echo "$screen1" | grep -Eq "read rate [0-9.]+ Hz   bus utilisation [0-9.]+ %" || fail "no bus summary"
echo "$screen1" | grep -q "figures: read from the bus by the monitor" || fail "the summary does not say where its figures come from"
echo "$screen1" | grep -q "reply p99 us" || fail "the reply column has no unit"
echo "PASS: the bus summary is on screen"

# Five refreshes at least (the monitor refreshes at 10 Hz or more).
sleep 0.5
screen2=$(tmux capture-pane -p -t "$session")
for id in 1 2 3 4 6; do
    # replies: field 14 of a row whose status is one word (ok, OVERHEAT).
    a=$(field $id 14 "$screen1"); b=$(field $id 14 "$screen2")
    [[ "$a" =~ ^[0-9]+$ && "$b" =~ ^[0-9]+$ ]] || fail "servo $id: no reply count ($a, $b)"
    [ "$b" -gt "$a" ] || fail "servo $id does not update ($a then $b replies)"
done
echo "PASS: servos 1 2 3 4 6 update (replies counted up between two screens)"

tmux send-keys -t "$session" " "
wait_for "torque OFF sent to every servo" || fail "Space did not say torque off was sent"
echo "PASS: Space sends torque off to every servo and says so"

tmux send-keys -t "$session" q
wait_for "^prompt> *$" || fail "q did not return to the shell"
sleep 0.3
[ "$(tmux display -p -t "$session" '#{alternate_on}')" = 0 ] || fail "still on the alternate screen"
[ "$(tmux display -p -t "$session" '#{cursor_flag}')" = 1 ] || fail "the cursor is hidden"
after=$(tmux capture-pane -p -t "$session")
echo "$after" | grep -q "^before-monitor$" || fail "the screen before the monitor is gone"
if echo "$after" | grep -q "wrist_roll"; then fail "the monitor's table is left on screen"; fi
tmux send-keys -t "$session" "stty -g > $dir/stty.after; echo typed-after" Enter
wait_for "^typed-after$" || fail "the shell does not echo typed commands after q"
cmp -s "$dir/stty.before" "$dir/stty.after" || fail "terminal settings changed: $(cat "$dir/stty.before") -> $(cat "$dir/stty.after")"
echo "PASS: q leaves the terminal as it was (main screen, cursor, stty settings, shell)"

# A panic restores the terminal too (the panic hook).
tmux send-keys -t "$session" "clear; RUST_BACKTRACE=0 SERVOBUS_MONITOR_TEST_PANIC=5 $bin monitor --robot $robot --port $dir/bus; echo panic-exit=\$?" Enter
wait_for "^panic-exit=" || fail "the monitor did not end after its test panic"
[ "$(tmux display -p -t "$session" '#{alternate_on}')" = 0 ] || fail "a panic left the alternate screen on"
[ "$(tmux display -p -t "$session" '#{cursor_flag}')" = 1 ] || fail "a panic left the cursor hidden"
tmux capture-pane -p -t "$session" | grep -q "asked for a panic after 5 refreshes" || fail "the panic message is not on the restored screen"
tmux send-keys -t "$session" "stty -g > $dir/stty.panic; echo typed-after-panic" Enter
wait_for "^typed-after-panic$" || fail "the shell does not echo after a panic"
cmp -s "$dir/stty.before" "$dir/stty.panic" || fail "a panic changed the terminal settings"
echo "PASS: a panic restores the terminal (main screen, cursor, stty settings) and shows its message"

# play --monitor: the same view of a running motion, from its telemetry.
tmux send-keys -t "$session" "clear; $bin play $root/configs/motions/arm-wave.yaml --monitor; echo play-exit=\$?" Enter
wait_for "so101 (play)" || fail "play --monitor shows no view"
wait_for "figures: the running motion's telemetry" || fail "play --monitor does not say its figures come from telemetry"
sleep 0.5
p1=$(tmux capture-pane -p -t "$session")
sleep 0.5
p2=$(tmux capture-pane -p -t "$session")
a=""; b=""
for id in 1 2 3 4 5 6; do a="$a $(field $id 4 "$p1")"; b="$b $(field $id 4 "$p2")"; done
[ -n "${a// /}" ] && [ "$a" != "$b" ] || fail "play --monitor: no joint moves ($a then $b)"
echo "PASS: play --monitor shows the running motion (positions$a ->$b deg)"
tmux send-keys -t "$session" q
wait_for "^play-exit=0" || fail "play --monitor did not end with q"
[ "$(tmux display -p -t "$session" '#{alternate_on}')" = 0 ] || fail "play --monitor left the alternate screen on"
tmux capture-pane -p -t "$session" | grep -q "^stopped:" || fail "play's report does not say it stopped"
echo "PASS: q stops the motion, the report follows on the restored terminal"
echo "all monitor checks passed"
