//! `servobus read`, `write` and `set-id`: one servo's registers, by name,
//! with values in their units and a warning where a write has no visible
//! effect.

use std::process::ExitCode;

use anyhow::{bail, Context};
use servobus_driver::BusError;
use servobus_protocol::registers::{addr, Access, Register, Series};

use super::{check_id, open_servo, ReadArgs, SerialBus, SetIdArgs, WriteArgs};
use crate::cmd::exit::input;

/// The register named `name` (or at the address `name`) of `series`.
fn register(series: Series, name: &str) -> anyhow::Result<&'static Register> {
    let map = series.map();
    let by_address = name.parse::<u8>().ok().and_then(|a| map.at(a));
    match by_address.or_else(|| map.get(name)) {
        Some(r) => Ok(r),
        None => Err(input(format!(
            "no register called {name:?} on {} servos (e.g. present_position, goal_position, id)",
            series.name().to_uppercase()
        ))),
    }
}

/// Runs `servobus read`.
pub fn read(args: ReadArgs) -> anyhow::Result<ExitCode> {
    let (mut bus, _) = open_servo(&args.servo)?;
    let series = bus.settings().series;
    let reg = register(series, &args.register)?;
    let (value, flags) = bus.read_register(args.servo.id, reg)?;
    if args.json {
        let out = serde_json::json!({
            "id": args.servo.id,
            "register": reg.name,
            "address": reg.address,
            "size": reg.size,
            "value": value,
            "unit": reg.unit,
            "status": flags.bits(),
        });
        println!("{out}");
    } else {
        println!("{} = {}", reg.name, human_value(value, reg.unit));
    }
    if !flags.is_ok() {
        eprintln!("warning: servo {} reports {flags}", args.servo.id);
    }
    Ok(ExitCode::SUCCESS)
}

/// Refuses `new_id` when a servo already answers to it.
fn refuse_taken(bus: &mut SerialBus, new_id: u8) -> anyhow::Result<()> {
    match bus.ping(new_id) {
        Err(BusError::Timeout { .. }) => Ok(()),
        Ok(_) | Err(BusError::Corrupt { .. }) | Err(BusError::WrongLength { .. }) => {
            bail!("ID {new_id} is already taken by a servo on this bus")
        }
        Err(e) => Err(e).context(format!("checking whether ID {new_id} is free")),
    }
}

/// Runs `servobus write`.
pub fn write(args: WriteArgs) -> anyhow::Result<ExitCode> {
    let (mut bus, _) = open_servo(&args.servo)?;
    let series = bus.settings().series;
    let reg = register(series, &args.register)?;
    let (lo, hi) = reg.range();
    let value = i32::try_from(args.value)
        .ok()
        .filter(|v| (lo..=hi).contains(v))
        .ok_or_else(|| {
            input(format!(
                "{} takes {lo}..={hi}, not {}",
                reg.name, args.value
            ))
        })?;
    match reg.access {
        Access::ReadOnly => return Err(input(format!("{} is read-only", reg.name))),
        Access::Ram => {
            bus.write_register(args.servo.id, reg, value)?;
            println!("{} = {value} (RAM: lost at power-off)", reg.name);
            warn_if_torque_off(&mut bus, args.servo.id, reg, &args.servo.port.port);
        }
        Access::Eeprom => {
            if reg.address == addr::ID {
                let new_id = u8::try_from(value).unwrap_or(u8::MAX);
                check_id(new_id)?;
                if new_id != args.servo.id {
                    refuse_taken(&mut bus, new_id)?;
                }
            }
            println!(
                "{} is an EEPROM register: the new value will persist across power cycles",
                reg.name
            );
            let mut buf = [0u8; 4];
            let bytes = &mut buf[..usize::from(reg.size)];
            reg.encode(value, series.byte_order(), bytes)
                .with_context(|| format!("{} cannot hold {value}", reg.name))?;
            let w = bus.write_eeprom(args.servo.id, reg.address, bytes)?;
            println!(
                "{} = {value} on servo {} (unlocked, written, verified, locked)",
                reg.name, w.id
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// A register value in its unit: a unit with a scale (`0.1 V`) is applied
/// (`120` reads `12.0 V (raw 120)`); a plain unit is appended.
fn human_value(value: i32, unit: &str) -> String {
    let scaled = unit
        .split_once(' ')
        .and_then(|(factor, rest)| Some((factor.parse::<f64>().ok()?, rest)));
    match scaled {
        Some((factor, rest)) => {
            // As many decimals as the scale has (0.1 -> 1, 100 -> 0).
            let decimals = (-factor.log10()).ceil().max(0.0) as usize;
            let v = f64::from(value) * factor;
            format!("{v:.decimals$} {rest} (raw {value})")
        }
        None if unit.is_empty() => value.to_string(),
        None => format!("{value} {unit}"),
    }
}

/// After a write to a goal register: warns when the servo's torque is off,
/// since it then holds no position and the goal has no visible effect.
fn warn_if_torque_off(bus: &mut SerialBus, id: u8, reg: &Register, port: &str) {
    let goals = [addr::GOAL_POSITION, addr::GOAL_SPEED, addr::GOAL_TIME];
    if !goals.contains(&reg.address) {
        return;
    }
    let Some(torque) = bus.settings().series.map().at(addr::TORQUE_ENABLE) else {
        return;
    };
    if let Ok((0, _)) = bus.read_register(id, torque) {
        eprintln!(
            "warning: torque is off on servo {id}, so it will not move to this goal; \
             turn it on with: servobus write --port {port} --id {id} torque_enable 1"
        );
    }
}

/// Runs `servobus set-id`.
pub fn set_id(args: SetIdArgs) -> anyhow::Result<ExitCode> {
    check_id(args.new_id)?;
    let (mut bus, _) = open_servo(&args.servo)?;
    if args.new_id == args.servo.id {
        println!("servo {} already has ID {}", args.servo.id, args.new_id);
        return Ok(ExitCode::SUCCESS);
    }
    refuse_taken(&mut bus, args.new_id)?;
    let w = bus.write_eeprom(args.servo.id, addr::ID, &[args.new_id])?;
    bus.ping(w.id)
        .with_context(|| format!("servo does not answer at its new ID {}", w.id))?;
    println!("servo {} is now ID {} (persisted)", args.servo.id, w.id);
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    #[test]
    fn scaled_units_read_as_people_write_them() {
        assert_eq!(super::human_value(120, "0.1 V"), "12.0 V (raw 120)");
        assert_eq!(
            super::human_value(50, "100 steps/s^2"),
            "5000 steps/s^2 (raw 50)"
        );
        assert_eq!(super::human_value(-30, "steps"), "-30 steps");
        assert_eq!(super::human_value(7, ""), "7");
    }
}
