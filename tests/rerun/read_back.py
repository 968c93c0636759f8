"""Reads a servobus recording back with Rerun's own Python SDK (rerun-sdk),
an independent reader of the .rrd file, and checks what it holds.

    read_back.py arm RUN.rrd SERVOBUS ROBOT URDF JOINTS
        the robot's entities, one per joint nested as its chain; at three
        times, the transforms composed along each chain against
        `SERVOBUS fk --robot ROBOT --json` at the angles logged then
        (measured for the robot, commanded for the ghost), within 0.1 mm;
        every link of URDF with a mesh has an Asset3D holding that file;
        every joint of JOINTS (comma-separated) has its series.
    read_back.py truth SIM.rrd SERVOBUS ROBOT URDF JOINTS
        the simulator's truth: as `arm`, the robot posed by the measured
        angles, and nothing commanded (no ghost).
    read_back.py walk PLAN.rrd SERVOBUS ROBOT X_MM Y_MM TURN_DEG
        a plan: nothing measured; the tree against fk at three times; the
        body's world pose at the end within 10 mm and 1 deg of X, Y, TURN.
    read_back.py refusal RUN.rrd TEXT
        an ERROR event whose text holds TEXT.

Prints one line per check (PASS or FAIL) and exits 1 on a failure.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import numpy as np
from rerun.experimental import RrdReader

FK_TOLERANCE_MM = 0.1
FAILURES: list[str] = []


def check(ok: bool, what: str) -> None:
    print(("PASS " if ok else "FAIL ") + what, flush=True)
    if not ok:
        FAILURES.append(what)


def columns(table) -> dict[str, dict[str, str]]:
    """Each column's entity path and component, from its field metadata
    (`table`: an Arrow table or schema)."""
    out = {}
    for field in getattr(table, "schema", table):
        meta = {k.decode(): v.decode() for k, v in (field.metadata or {}).items()}
        if meta.get("rerun:kind") == "data":
            out[field.name] = meta
    return out


def entity_columns(table, component: str) -> dict[str, str]:
    """Entity path -> column name, for the columns of `component`."""
    return {
        meta["rerun:entity_path"]: name
        for name, meta in columns(table).items()
        if meta.get("rerun:component") == component
    }


def quaternion_matrix(x: float, y: float, z: float, w: float) -> np.ndarray:
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def transform_at(row: dict, translations: dict, rotations: dict, entity: str) -> np.ndarray:
    """The 4x4 transform (mm) logged for `entity` in `row`; identity if none."""
    m = np.eye(4)
    t = translations.get(entity)
    q = rotations.get(entity)
    if q is not None and row.get(q):
        m[:3, :3] = quaternion_matrix(*row[q][0])
    if t is not None and row.get(t):
        m[:3, 3] = np.array(row[t][0]) * 1000.0
    return m


def composed(row: dict, translations: dict, rotations: dict, entity: str, root: str) -> np.ndarray:
    """The transforms from `root`'s children down to `entity`, composed (the
    pose in the root's frame, mm)."""
    parts = entity.strip("/").split("/")
    m = np.eye(4)
    for depth in range(2, len(parts) + 1):
        m = m @ transform_at(row, translations, rotations, "/" + "/".join(parts[:depth]))
    return m


def fk(servobus: str, robot: str, pose: dict[str, float]) -> dict:
    out = subprocess.run(
        [servobus, "fk", "--robot", robot, "--pose", json.dumps(pose), "--json"],
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout)["frames"]


def load(path: str):
    return RrdReader(path).stream().collect()


def joint_entities(table, root: str, joints: list[str]) -> dict[str, str]:
    """Each joint's entity under `root`: the Transform3D entity whose last
    part is the joint's name."""
    found = {}
    for entity in entity_columns(table, "Transform3D:translation"):
        parts = entity.strip("/").split("/")
        if parts[0] == root and parts[-1] in joints:
            found[parts[-1]] = entity
    return found


def schema_of(store, index):
    """The columns of a query on `store` (nothing read)."""
    return store.reader(index=index).schema()


def check_tree_against_fk(store, servobus, robot, joints, root, series, label) -> None:
    """At three times, the tree under `root` composed against fk at the
    angles of `series` (`measured` or `commanded`) logged then."""
    entities = joint_entities(schema_of(store, "time"), root, joints)
    # Only the transforms and angles: the meshes' bytes stay out of the rows.
    wanted = [f"/{root}"] + list(entities.values()) + [f"/joints/{j}/{series}" for j in joints]
    table = store.reader(index="time", contents=wanted, fill_latest_at=True).to_arrow_table()
    check(
        sorted(entities) == sorted(joints),
        f"{label}: one {root}/... entity per joint ({len(entities)} of {len(joints)})",
    )
    for name, entity in entities.items():
        parts = entity.strip("/").split("/")
        chain_ok = all(p in joints for p in parts[1:])
        if not chain_ok:
            check(False, f"{label}: {entity} is a chain of joints")
    translations = entity_columns(table, "Transform3D:translation")
    rotations = entity_columns(table, "Transform3D:quaternion")
    scalars = entity_columns(table, "Scalars:scalars")
    angle_columns = {j: scalars.get(f"/joints/{j}/{series}") for j in joints}
    rows = [
        r
        for r in table.to_pylist()
        if all(c is not None and r.get(c) for c in angle_columns.values())
        and all(r.get(translations[e]) for e in entities.values())
    ]
    check(len(rows) >= 3, f"{label}: {len(rows)} samples with every joint's {series} angle")
    if len(rows) < 3:
        return
    for at in (len(rows) // 4, len(rows) // 2, 3 * len(rows) // 4):
        row = rows[at]
        pose = {j: row[angle_columns[j]][0] for j in joints}
        frames = fk(servobus, robot, pose)
        worst = 0.0
        for name, entity in entities.items():
            m = composed(row, translations, rotations, entity, root)
            worst = max(worst, float(np.linalg.norm(m[:3, 3] - np.array(frames[name]["xyz"]))))
        check(
            worst <= FK_TOLERANCE_MM,
            f"{label} at {row['time']}: composed transforms vs fk of the {series} angles, "
            f"worst {worst:.5f} mm",
        )


def check_meshes(store, urdf: str) -> None:
    """Every URDF link with a mesh visual has Asset3Ds, one per mesh, each
    holding its file's bytes."""
    table = store.reader(index=None).to_arrow_table()
    blobs = entity_columns(table, "Asset3D:blob")
    row = table.to_pylist()[0] if table.num_rows else {}
    root = ElementTree.parse(urdf).getroot()
    links = 0
    for link in root.iter("link"):
        meshes = [
            m.get("filename")
            for v in link.iter("visual")
            for m in v.iter("mesh")
        ]
        if not meshes:
            continue
        links += 1
        name = link.get("name")
        held = sorted(e for e in blobs if e.strip("/").split("/")[-2].rstrip("_") == name)
        ok = len(held) == len(meshes)
        for entity, mesh in zip(held, meshes):
            size = (Path(urdf).parent / mesh).stat().st_size
            blob = row.get(blobs[entity]) or [[]]
            ok = ok and len(blob[0]) == size
        check(ok, f"link {name}: {len(held)} Asset3D of its {len(meshes)} meshes, bytes as the files")
    check(links > 0, f"{links} links with meshes in the URDF")


def check_series(store, joints: list[str], wanted: list[str], absent: list[str]) -> None:
    table = store.reader(index="time", contents="/joints/**").to_arrow_table()
    scalars = entity_columns(table, "Scalars:scalars")
    for joint in joints:
        for what in wanted:
            column = scalars.get(f"/joints/{joint}/{what}")
            count = 0 if column is None else sum(1 for v in table.column(column).to_pylist() if v)
            check(count >= 100, f"/joints/{joint}/{what}: {count} values")
        for what in absent:
            check(f"/joints/{joint}/{what}" not in scalars, f"/joints/{joint}/{what}: none")


def main_arm(path, servobus, robot, urdf, joints) -> None:
    joints = joints.split(",")
    store = load(path)
    check_tree_against_fk(store, servobus, robot, joints, "robot", "measured", "robot")
    check_tree_against_fk(store, servobus, robot, joints, "ghost", "commanded", "ghost")
    check_meshes(store, urdf)
    check_series(store, joints, ["commanded", "measured", "error"], [])
    points = entity_columns(schema_of(store, "time"), "Points3D:positions")
    check("/paths/tool" in points, "the tool's path in the world: /paths/tool")


def main_truth(path, servobus, robot, urdf, joints) -> None:
    joints = joints.split(",")
    store = load(path)
    check_tree_against_fk(store, servobus, robot, joints, "robot", "measured", "truth")
    check_meshes(store, urdf)
    check_series(store, joints, ["measured"], ["commanded", "error"])


def main_walk(path, servobus, robot, x_mm, y_mm, turn_deg) -> None:
    store = load(path)
    scalars = entity_columns(schema_of(store, "time"), "Scalars:scalars")
    joints = sorted({e.split("/")[2] for e in scalars if e.startswith("/joints/")})
    check(len(joints) == 18, f"{len(joints)} joints with series")
    check_series(store, joints, ["commanded", "margin"], ["measured"])
    check_tree_against_fk(store, servobus, robot, joints, "robot", "commanded", "plan")
    points = entity_columns(schema_of(store, "time"), "Points3D:positions")
    feet = [e for e in points if e.startswith("/paths/foot_")]
    check(len(feet) == 6, f"{len(feet)} feet's paths in the world")
    table = store.reader(index="time", contents="/robot").to_arrow_table()
    translation = entity_columns(table, "Transform3D:translation").get("/robot")
    rotation = entity_columns(table, "Transform3D:quaternion").get("/robot")
    rows = [r for r in table.to_pylist() if translation and r.get(translation)]
    check(len(rows) > 100, f"{len(rows)} poses of the body in the world")
    if not rows:
        return
    last = rows[-1]
    t = np.array(last[translation][0]) * 1000.0
    x, y, z, w = last[rotation][0]
    yaw = math.degrees(math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))
    check(
        abs(t[0] - x_mm) <= 10 and abs(t[1] - y_mm) <= 10 and abs(yaw - turn_deg) <= 1.0,
        f"the body ends at x {t[0]:.1f} mm, y {t[1]:.1f} mm, turned {yaw:.2f} deg "
        f"(wanted {x_mm}, {y_mm}, {turn_deg})",
    )
    statics = entity_columns(store.reader(index=None).to_arrow_table(), "Points3D:positions")
    check("/robot/workspace" in statics, "the workspace under /robot")
    ghosts = [
        meta["rerun:entity_path"]
        for index in ("time", None)
        for meta in columns(schema_of(store, index)).values()
        if meta["rerun:entity_path"].startswith("/ghost")
    ]
    check(not ghosts, f"no ghost in a plan, where nothing is measured: {ghosts[:3]}")


def main_refusal(path, text) -> None:
    store = load(path)
    table = store.reader(index="time", contents="/events").to_arrow_table()
    texts = entity_columns(table, "TextLog:text")
    levels = entity_columns(table, "TextLog:level")
    rows = table.to_pylist()
    found = [
        r[texts["/events"]][0]
        for r in rows
        if "/events" in texts and r.get(texts["/events"]) and r[levels["/events"]][0] == "ERROR"
    ]
    check(any(text in f for f in found), f"an ERROR event holding `{text}`: {found}")


def main() -> int:
    mode, args = sys.argv[1], sys.argv[2:]
    if mode == "arm":
        main_arm(*args)
    elif mode == "truth":
        main_truth(*args)
    elif mode == "walk":
        path, servobus, robot, x, y, turn = args
        main_walk(path, servobus, robot, float(x), float(y), float(turn))
    elif mode == "refusal":
        main_refusal(*args)
    else:
        print(f"FAIL unknown mode {mode}")
        return 1
    print(json.dumps({"failures": FAILURES}))
    return 1 if FAILURES else 0


if __name__ == "__main__":
    sys.exit(main())
