#!/usr/bin/env python3
"""6-servo SYNC READ of present positions from Python, three ways, on one
simulated bus: servobus (``servobus.Bus.sync_read``), Feetech's SDK
(``scservo_sdk.GroupSyncRead``) and rustypot
(``Sts3215PyController.sync_read_present_position``).

Usage: python sync_read.py [--port PTY] [--rounds 5] [--reads 200]

Without --port the SO-101's servos are served by ``servobus.Sim`` (the pty
server of ``servobus sim``) from a thread of this process; with --port, by
a ``servobus sim --robot so101 --link PTY`` you started. The clients take
turns, round by round, each opening the port, doing ``--reads`` reads and
closing it, so that load on the machine falls on all of them alike. A read
is lost when any servo's value is missing from it (an exception, an error
code, or a servo reported missing). For a note, not a timed test.

Needs, beside servobus: ``pip install feetech-servo-sdk==1.0.0 pyserial
rustypot==1.13.1``; a client whose package is missing is left out.
"""

from __future__ import annotations

import argparse
import statistics
import time

IDS = [1, 2, 3, 4, 5, 6]
BAUD = 1_000_000
PRESENT_POSITION = 56  # STS address, 2 bytes


def servobus_client(port):
    import servobus

    bus = servobus.Bus(port, BAUD)

    def read():
        return not bus.sync_read("present_position", IDS).missing

    return read, bus.close


def scservo_client(port):
    import scservo_sdk as scs

    handler = scs.PortHandler(port)
    if not handler.openPort() or not handler.setBaudRate(BAUD):
        raise RuntimeError(f"scservo_sdk cannot open {port}")
    group = scs.GroupSyncRead(handler, scs.PacketHandler(0), PRESENT_POSITION, 2)
    for i in IDS:
        group.addParam(i)

    def read():
        if group.txRxPacket() != scs.COMM_SUCCESS:
            return False
        return all(group.isAvailable(i, PRESENT_POSITION, 2) for i in IDS)

    return read, handler.closePort


def rustypot_client(port):
    from rustypot import Sts3215PyController

    controller = Sts3215PyController(serial_port=port, baudrate=BAUD, timeout=0.1)

    def read():
        try:
            return len(controller.sync_read_present_position(IDS)) == len(IDS)
        except Exception:
            return False

    def close():
        nonlocal controller
        controller = None

    return read, close


CLIENTS = {
    "servobus": servobus_client,
    "scservo_sdk": scservo_client,
    "rustypot": rustypot_client,
}


def one_round(make, port, reads):
    """Reads per second and lost reads of one client in one round."""
    read, close = make(port)
    try:
        read()  # the first read after opening is not timed
        lost = 0
        start = time.perf_counter()
        for _ in range(reads):
            if not read():
                lost += 1
        elapsed = time.perf_counter() - start
    finally:
        close()
    return reads / elapsed, lost


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", help="a `servobus sim` pty (default: servobus.Sim in-process)")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--reads", type=int, default=200)
    args = parser.parse_args()

    clients = {}
    for name, make in CLIENTS.items():
        try:
            __import__(name)
            clients[name] = make
        except ImportError:
            print(f"{name}: not installed, left out")

    sim = None
    port = args.port
    if port is None:
        import servobus

        sim = servobus.Sim("so101")
        port = sim.port
    try:
        rates = {name: [] for name in clients}
        lost = {name: 0 for name in clients}
        for _ in range(args.rounds):
            for name, make in clients.items():
                rate, missing = one_round(make, port, args.reads)
                rates[name].append(rate)
                lost[name] += missing
    finally:
        if sim is not None:
            sim.close()

    total = args.rounds * args.reads
    print(f"6-servo SYNC READ of present_position on {port}, {args.rounds} rounds of {args.reads} reads")
    print(f"{'client':<12} {'reads/s median':>15} {'min':>8} {'max':>8} {'lost':>10}")
    for name in clients:
        r = rates[name]
        print(f"{name:<12} {statistics.median(r):>15.0f} {min(r):>8.0f} {max(r):>8.0f} {lost[name]:>5}/{total}")
    if "servobus" in clients:
        ours = statistics.median(rates["servobus"])
        for name in clients:
            if name != "servobus":
                print(f"servobus / {name}: {ours / statistics.median(rates[name]):.2f}x")


if __name__ == "__main__":
    main()
