//! `servobus._native.Robot.doctor`: the robot's buses checked by the
//! library's doctor, as JSON text of plain data (the Python package makes
//! typed findings of it).

use servobus_robot::doctor::{exit_status, Applied, BusCheck, CheckOptions, Checkup, Finding};

use crate::errors::{Class, Failure, Outcome};

/// One finding: its fields, the advice as data, whether the doctor can
/// apply its fix, and the setting it is about (a joint's mode or `servo:`
/// setting; null otherwise), as `servobus doctor --json` gives it.
fn finding(f: &Finding) -> Outcome<serde_json::Value> {
    let mut v = serde_json::to_value(f).map_err(json_failure)?;
    if let Some(map) = v.as_object_mut() {
        map.insert(
            "advice".into(),
            serde_json::to_value(&f.advice).map_err(json_failure)?,
        );
        map.insert("fixable".into(), f.fixable().into());
        map.insert(
            "setting".into(),
            serde_json::to_value(&f.setting).map_err(json_failure)?,
        );
    }
    Ok(v)
}

/// What a fix did, as data.
fn applied(a: &Applied) -> Outcome<serde_json::Value> {
    Ok(match a {
        Applied::Advice(advice) => {
            serde_json::json!({ "advice": serde_json::to_value(advice).map_err(json_failure)? })
        }
        Applied::OffsetStored(v) => serde_json::json!({ "offset_stored": v }),
        Applied::OffsetForSession(v) => serde_json::json!({ "offset_for_session": v }),
        other => serde_json::json!({ "other": format!("{other:?}") }),
    })
}

fn bus(b: &BusCheck) -> Outcome<serde_json::Value> {
    let findings = b
        .standing()
        .iter()
        .map(finding)
        .collect::<Outcome<Vec<_>>>()?;
    let fixes = b
        .fixes
        .iter()
        .map(|f| {
            Ok(serde_json::json!({
                "id": f.id,
                "applied": applied(&f.applied)?,
                "error": f.result.as_ref().err().map(ToString::to_string),
            }))
        })
        .collect::<Outcome<Vec<_>>>()?;
    Ok(serde_json::json!({
        "name": b.name,
        "port": b.at.port,
        "baud": b.at.baud,
        "servos": b.after.as_ref().unwrap_or(&b.first).servos.len(),
        "expected": b.first.expected,
        "findings": findings,
        "fixes": fixes,
    }))
}

/// The checkup as JSON text: `status` (0 nothing wrong, 1 warnings, 2
/// errors), `buses` (each with its standing findings and the fixes
/// applied) and `unchecked` (buses with no port while others have one).
pub(crate) fn checkup_json(checkup: &Checkup) -> Outcome<String> {
    let buses = checkup.buses.iter().map(bus).collect::<Outcome<Vec<_>>>()?;
    Ok(serde_json::json!({
        "status": exit_status(&checkup.standing()),
        "buses": buses,
        "unchecked": checkup.unchecked,
    })
    .to_string())
}

/// Checks `robot`'s buses on `port` (the first bus; the robot file's
/// ports past it) or on the built-in simulator, fixing what can be fixed
/// with `fix` (homing offsets in EEPROM only with `write_servos`).
pub(crate) fn doctor(
    robot: &servobus_robot::Robot,
    port: Option<&str>,
    fix: bool,
    write_servos: bool,
) -> Outcome<String> {
    let ports: Vec<&str> = port.into_iter().collect();
    let options = CheckOptions { fix, write_servos };
    let checkup = robot.doctor(&ports, &options)?;
    checkup_json(&checkup)
}

fn json_failure(e: serde_json::Error) -> Failure {
    Failure::new(Class::Error, format!("the doctor's findings as JSON: {e}"))
}
