#!/usr/bin/env python3
"""Reference durations for servobus-trajectory's rest-to-rest profiles.

Draws reproducible random multi-joint rest-to-rest cases (with and without a
jerk limit), computes the time-optimal synchronised duration of each with
Ruckig (`pip install ruckig`), and writes them to
testdata/trajectory/ruckig.csv, one row per joint:

    case,joint,start,target,max_velocity,max_acceleration,max_jerk,ruckig_duration

`max_jerk` is empty for a joint without a jerk limit (Ruckig's infinite
jerk, a trapezoidal profile). `ruckig_duration` is the case's duration,
repeated on every joint row. The Rust test crates/trajectory/tests/ruckig.rs
plans each case and checks its duration against this column.

Usage: python3 scripts/ruckig_compare.py [--cases N] [--seed S] [--out PATH]
"""

import argparse
import csv
import math
import os
import random

from ruckig import InputParameter, Result, Ruckig, Trajectory


def case(rng):
    dofs = rng.randint(1, 6)
    jerk_limited = rng.random() < 0.75
    joints = []
    for _ in range(dofs):
        start = rng.uniform(-3.0, 3.0)
        # Some joints do not move, some barely move, most move far.
        kind = rng.random()
        if kind < 0.1:
            target = start
        elif kind < 0.3:
            target = start + rng.uniform(-0.05, 0.05)
        else:
            target = rng.uniform(-3.0, 3.0)
        vmax = rng.uniform(0.5, 6.0)
        amax = rng.uniform(1.0, 40.0)
        jmax = rng.uniform(10.0, 800.0) if jerk_limited else None
        joints.append((start, target, vmax, amax, jmax))
    return joints


def duration(joints):
    dofs = len(joints)
    otg = Ruckig(dofs)
    inp = InputParameter(dofs)
    inp.current_position = [j[0] for j in joints]
    inp.current_velocity = [0.0] * dofs
    inp.current_acceleration = [0.0] * dofs
    inp.target_position = [j[1] for j in joints]
    inp.target_velocity = [0.0] * dofs
    inp.target_acceleration = [0.0] * dofs
    inp.max_velocity = [j[2] for j in joints]
    inp.max_acceleration = [j[3] for j in joints]
    inp.max_jerk = [j[4] if j[4] is not None else math.inf for j in joints]
    traj = Trajectory(dofs)
    result = otg.calculate(inp, traj)
    if result not in (Result.Working, Result.Finished):
        raise RuntimeError(f"ruckig failed: {result}")
    return traj.duration


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    default_out = os.path.join(here, "..", "testdata", "trajectory", "ruckig.csv")
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=300)
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--out", default=default_out)
    args = ap.parse_args()
    rng = random.Random(args.seed)
    with open(args.out, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["case", "joint", "start", "target", "max_velocity",
                    "max_acceleration", "max_jerk", "ruckig_duration"])
        for c in range(args.cases):
            joints = case(rng)
            t = duration(joints)
            for j, (start, target, vmax, amax, jmax) in enumerate(joints):
                w.writerow([c, j, repr(start), repr(target), repr(vmax), repr(amax),
                            "" if jmax is None else repr(jmax), repr(t)])
    print(f"wrote {args.cases} cases to {os.path.normpath(args.out)}")


if __name__ == "__main__":
    main()
