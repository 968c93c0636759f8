#!/usr/bin/env python3
"""Control cycles per second on one pty, servobus against rustypot, taking
turns: ``servobus bench --port PTY`` (every cycle a SYNC WRITE of the six
goals and a SYNC READ of the feedback) and a rustypot loop doing the same
(``sync_write_goal_position`` of the positions it read, then
``sync_read_present_position``), as fast as each goes.

Usage: python cycle_rate.py --port /tmp/arm [--rounds 3] [--seconds 5]
                            [--servobus target/release/servobus]

Start the servos first: ``servobus sim --robot so101 --link /tmp/arm``.
Each round runs servobus, then rustypot, on the same pty, so that load on
the machine falls on both alike. Prints one line per run and the medians.
A rustypot cycle is lost when its read raises or returns fewer positions;
servobus's own count of timeouts is quoted from its JSON. For a note, not a
timed test. Needs ``pip install rustypot==1.13.1``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import time

IDS = [1, 2, 3, 4, 5, 6]
BAUD = 1_000_000


def servobus_run(binary: str, port: str, seconds: float) -> tuple[float, int, int]:
    """(cycles per second, timeouts, cycles) of one bench run."""
    out = subprocess.run(
        [binary, "bench", "--port", port, "--seconds", str(seconds), "--json"],
        capture_output=True,
        text=True,
        check=False,
        timeout=seconds + 60,
    )
    if not out.stdout.strip():
        raise RuntimeError(f"servobus bench printed nothing: {out.stderr}")
    report = json.loads(out.stdout)
    bus = report["buses"][0]
    return float(bus["achieved_rate_hz"]), int(bus["timeouts"]), int(bus["cycles"])


def rustypot_run(port: str, seconds: float) -> tuple[float, int, int]:
    """(cycles per second, lost cycles, cycles) of one rustypot loop."""
    from rustypot import Sts3215PyController

    controller = Sts3215PyController(serial_port=port, baudrate=BAUD, timeout=0.1)
    goals = list(controller.sync_read_present_position(IDS))
    cycles = lost = 0
    start = time.perf_counter()
    end = start + seconds
    while time.perf_counter() < end:
        controller.sync_write_goal_position(IDS, goals)
        try:
            read = controller.sync_read_present_position(IDS)
            if len(read) == len(IDS):
                goals = list(read)
            else:
                lost += 1
        except Exception:  # a missing reply is an exception in rustypot
            lost += 1
        cycles += 1
    took = time.perf_counter() - start
    return cycles / took, lost, cycles


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--port", required=True)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--seconds", type=float, default=5.0)
    p.add_argument("--servobus", default="target/release/servobus")
    a = p.parse_args()
    rates: dict[str, list[float]] = {"servobus": [], "rustypot": []}
    for r in range(a.rounds):
        hz, timeouts, reads = servobus_run(a.servobus, a.port, a.seconds)
        rates["servobus"].append(hz)
        print(f"round {r + 1}  servobus  {hz:7.1f} Hz  timeouts {timeouts} in {reads} cycles")
        hz, lost, cycles = rustypot_run(a.port, a.seconds)
        rates["rustypot"].append(hz)
        print(f"round {r + 1}  rustypot  {hz:7.1f} Hz  lost {lost}/{cycles} cycles")
    for name, rs in rates.items():
        print(f"median {name:9} {statistics.median(rs):7.1f} Hz")


if __name__ == "__main__":
    main()
