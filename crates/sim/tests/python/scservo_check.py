#!/usr/bin/env python3
"""Talks to a simulated servo bus with Feetech's own Python SDK, unchanged.

Usage: scservo_check.py PORT [ID ...]   (IDs default to 1..6, STS3215 at 1 Mbps)

Pings every servo and checks its model number, reads present positions one
by one, sync-writes new goal positions with torque on, reads them back with
SYNC READ and checks that the joints moved there. Exits 0 and prints one
`OK` line when everything matched, 1 with the reason otherwise.

Requires `pip install feetech-servo-sdk` (module `scservo_sdk`, the one
LeRobot uses).
"""

import sys
import time

import scservo_sdk as scs

STS3215 = 777
PRESENT_POSITION = 56
GOAL_POSITION = 42
TORQUE_ENABLE = 40
LOCK = 55


def fail(msg):
    print(f"FAIL {msg}")
    sys.exit(1)


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        sys.exit(2)
    port_name = sys.argv[1]
    ids = [int(a) for a in sys.argv[2:]] or [1, 2, 3, 4, 5, 6]

    port = scs.PortHandler(port_name)
    if not port.openPort():
        fail(f"cannot open {port_name}")
    if not port.setBaudRate(1_000_000):
        fail("cannot set 1 Mbps")
    ph = scs.PacketHandler(0)  # 0: STS/SMS byte order (little-endian)

    for i in ids:
        model, result, error = ph.ping(port, i)
        if result != scs.COMM_SUCCESS:
            fail(f"ping {i}: {ph.getTxRxResult(result)}")
        if error != 0:
            fail(f"ping {i}: error byte {error}")
        if model != STS3215:
            fail(f"ping {i}: model {model}, expected {STS3215}")

    start = {}
    for i in ids:
        pos, result, error = ph.read2ByteTxRx(port, i, PRESENT_POSITION)
        if result != scs.COMM_SUCCESS or error != 0:
            fail(f"read {i}: {ph.getTxRxResult(result)} error {error}")
        start[i] = pos

    for i in ids:
        result, error = ph.write1ByteTxRx(port, i, TORQUE_ENABLE, 1)
        if result != scs.COMM_SUCCESS or error != 0:
            fail(f"torque enable {i}: {ph.getTxRxResult(result)} error {error}")

    goals = {i: (start[i] + 100 * (k + 1)) % 4000 for k, i in enumerate(ids)}
    writer = scs.GroupSyncWrite(port, ph, GOAL_POSITION, 2)
    for i in ids:
        writer.addParam(i, [scs.SCS_LOBYTE(goals[i]), scs.SCS_HIBYTE(goals[i])])
    result = writer.txPacket()
    if result != scs.COMM_SUCCESS:
        fail(f"sync write: {ph.getTxRxResult(result)}")

    time.sleep(0.5)  # every move is at most 600 ticks: well under 0.5 s at full speed

    reader = scs.GroupSyncRead(port, ph, PRESENT_POSITION, 2)
    for i in ids:
        reader.addParam(i)
    result = reader.txRxPacket()
    if result != scs.COMM_SUCCESS:
        fail(f"sync read: {ph.getTxRxResult(result)}")
    for i in ids:
        pos = reader.getData(i, PRESENT_POSITION, 2)
        if abs(pos - goals[i]) > 2:
            fail(f"servo {i} at {pos}, goal {goals[i]}")

    for i in ids:
        ph.write1ByteTxRx(port, i, TORQUE_ENABLE, 0)
    port.closePort()
    print(f"OK {len(ids)} servos: ping, read, sync write, sync read")


if __name__ == "__main__":
    main()
