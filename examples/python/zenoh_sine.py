"""Drive a serving robot from any machine with Python and eclipse-zenoh.

    servobus serve --robot so101                 # on the robot's machine
    pip install eclipse-zenoh==1.10.1
    python examples/python/zenoh_sine.py tcp/127.0.0.1:7447 so101

It prints the robot's state as it comes and sends a sine of targets to the
elbow for ten seconds at 30 Hz, then `shutdown` (which ends the node, as
Ctrl-C does), and prints the report.
"""

import json
import math
import sys
import time

import zenoh

endpoint = sys.argv[1] if len(sys.argv) > 1 else "tcp/127.0.0.1:7447"
robot = sys.argv[2] if len(sys.argv) > 2 else "so101"
base = f"servobus/{robot}"

conf = zenoh.Config()
conf.insert_json5("mode", '"peer"')
conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
conf.insert_json5("scouting/multicast/enabled", "false")
with zenoh.open(conf) as session:
    latest = {}

    def on_state(sample):
        state = json.loads(bytes(sample.payload.to_bytes()))
        latest.update(zip(state["joints"], state["measured"]))

    session.declare_subscriber(f"{base}/state", on_state)
    start = time.monotonic()
    while time.monotonic() - start < 10.0:
        t = time.monotonic() - start
        target = {"elbow_flex": 30.0 * math.sin(2 * math.pi * 0.25 * t)}
        session.put(f"{base}/target", json.dumps({"joints": target, "sent_ns": time.time_ns()}))
        print(f"\rtarget {target['elbow_flex']:+6.1f}  measured {latest.get('elbow_flex') or 0:+6.1f}", end="")
        time.sleep(1 / 30)
    session.put(f"{base}/command", "shutdown")
    time.sleep(1.0)
    for reply in session.get(f"{base}/report", timeout=5.0):
        if reply.ok is not None:
            print("\n" + json.dumps(json.loads(bytes(reply.ok.payload.to_bytes())), indent=2))
