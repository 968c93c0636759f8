//! `servobus read`, `write` and `set-id`: one servo's registers, by name,
//! with values in their units and a warning where a write has no visible
//! effect; `servobus registers`: the names, for each series.

use std::process::ExitCode;

use anyhow::{bail, Context};
use servobus_protocol::registers::{self, addr, Access, Register, Series};
use servobus_robot::bus::BusError;

use super::args::{ReadArgs, RegistersArgs, SetIdArgs, WriteArgs};
use super::open::{check_id, open_servo};
use crate::shared::exit::input;
use crate::shared::out::{errln, outln};
use crate::shared::ports::SerialBus;

/// Catches SIGINT, SIGTERM and SIGHUP from the start of a command that
/// writes: one that comes during its EEPROM transaction is acted on once
/// the servo is locked and what was done is said; one that comes before
/// it means nothing is written ([`before_eeprom_write`]).
fn catch_signals() {
    if let Err(e) = servobus_robot::bus::catch_stop_signals() {
        crate::shared::out::errln!("warning: signals cannot be caught ({e})");
    }
}

/// Right before an EEPROM transaction: a stop signal caught so far ends
/// the command with nothing written.
fn before_eeprom_write() -> anyhow::Result<()> {
    match servobus_robot::bus::stop_signal() {
        Some(signal) => bail!("stopped by {signal} before writing: nothing was written"),
        None => Ok(()),
    }
}

/// After a write: the error to end with when a stop signal came during it
/// (the servo was finished first); `what` says what was done.
fn after_eeprom_write(what: &str) -> anyhow::Result<()> {
    match servobus_robot::bus::stop_signal() {
        Some(signal) => bail!("stopped by {signal}: {what}; nothing else was done"),
        None => Ok(()),
    }
}

/// The register named `name` (or at the address `name`) of `series`.
fn register(series: Series, name: &str) -> anyhow::Result<&'static Register> {
    let map = series.map();
    let by_address = name.parse::<u8>().ok().and_then(|a| map.at(a));
    match by_address.or_else(|| map.get(name)) {
        Some(r) => Ok(r),
        None => {
            let names: Vec<&str> = map.registers.iter().map(|r| r.name).collect();
            Err(input(format!(
                "no register called {name:?} on {} servos; the registers are: {} \
                 (addresses, sizes and units: servobus registers --series {})",
                series.name().to_uppercase(),
                names.join(", "),
                series.name()
            )))
        }
    }
}

/// Runs `servobus registers`: the control table of each series asked for.
pub fn list(args: RegistersArgs) -> anyhow::Result<ExitCode> {
    let all = [Series::Sts, Series::Scs];
    let chosen: Vec<Series> = match args.series.as_deref() {
        None => all.to_vec(),
        Some(name) => match all
            .into_iter()
            .find(|s| s.name().eq_ignore_ascii_case(name))
        {
            Some(s) => vec![s],
            None => return Err(input(format!("--series {name}: sts or scs"))),
        },
    };
    for (n, series) in chosen.into_iter().enumerate() {
        if n > 0 {
            outln!()?;
        }
        outln!(
            "{} servos (EEPROM: kept over power-off; RAM: lost; read-only: reported)",
            series.name().to_uppercase()
        )?;
        outln!(
            "{:>4} {:>4}  {:<9} {:<22} {:<16} WHAT",
            "ADDR",
            "SIZE",
            "ACCESS",
            "NAME",
            "UNIT"
        )?;
        for r in series.map().registers {
            let access = match r.access {
                Access::Eeprom => "EEPROM",
                Access::Ram => "RAM",
                Access::ReadOnly => "read-only",
            };
            outln!(
                "{:>4} {:>4}  {access:<9} {:<22} {:<16} {}",
                r.address,
                r.size,
                r.name,
                r.unit,
                r.description
            )?;
        }
    }
    Ok(ExitCode::SUCCESS)
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
        outln!("{}", crate::shared::json::line(&out)?)?;
    } else {
        outln!("{} = {}", reg.name, human_value(value, reg))?;
    }
    if !flags.is_ok() {
        errln!("warning: servo {} reports {flags}", args.servo.id);
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
    catch_signals();
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
            outln!(
                "{} = {} (RAM: lost at power-off)",
                reg.name,
                human_value(value, reg)
            )?;
            after_eeprom_write(&format!("{} = {value} was written (RAM)", reg.name))?;
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
            outln!(
                "{} is an EEPROM register: the new value will persist across power cycles",
                reg.name
            )?;
            if reg.address == addr::BAUD_RATE {
                return write_baud_rate(&mut bus, &args, value);
            }
            let mut buf = [0u8; 4];
            let bytes = &mut buf[..usize::from(reg.size)];
            reg.encode(value, series.byte_order(), bytes)
                .with_context(|| format!("{} cannot hold {value}", reg.name))?;
            before_eeprom_write()?;
            let w = bus.write_eeprom(args.servo.id, reg.address, bytes)?;
            // Said before a stop is acted on: the servo holds it now.
            let said = outln!(
                "{} = {} on servo {} (unlocked, written, verified, locked)",
                reg.name,
                human_value(value, reg),
                w.id
            );
            after_eeprom_write(&format!(
                "servo {} was written first ({} = {value}; unlocked, written, verified, locked)",
                w.id, reg.name
            ))?;
            said?;
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// Writes baud-rate index `value` to the servo: it then listens at the
/// new rate, so the write is verified and locked there.
fn write_baud_rate(bus: &mut SerialBus, args: &WriteArgs, value: i32) -> anyhow::Result<ExitCode> {
    let id = args.servo.id;
    let index = u8::try_from(value).unwrap_or(u8::MAX);
    let Some(rate) = registers::baud_rate(index) else {
        return Err(input(format!(
            "baud_rate {value} is not an index of the baud table"
        )));
    };
    before_eeprom_write()?;
    servobus_robot::doctor::change_baud(bus, id, args.servo.baud, index)
        .with_context(|| format!("servo {id}: moving it to {rate} baud"))?;
    let said = outln!(
        "baud_rate = {value} ({rate} baud) on servo {id} (unlocked, written, verified, locked): \
         it now answers at {rate} baud"
    );
    after_eeprom_write(&format!(
        "servo {id} was moved to {rate} baud first (unlocked, written, verified, locked)"
    ))?;
    said?;
    Ok(ExitCode::SUCCESS)
}

/// A register value as people read it: the baud-rate register's index with
/// its rate (`0 (1000000 baud)`), else the value in its unit.
fn human_value(value: i32, reg: &Register) -> String {
    if reg.address == addr::BAUD_RATE {
        let rate = u8::try_from(value).ok().and_then(registers::baud_rate);
        if let Some(rate) = rate {
            return format!("{value} ({rate} baud)");
        }
    }
    in_unit(value, reg.unit)
}

/// A value in its unit: a unit with a scale (`0.1 V`) is applied (`120`
/// reads `12.0 V (raw 120)`); a plain unit is appended.
fn in_unit(value: i32, unit: &str) -> String {
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
        errln!(
            "warning: torque is off on servo {id}, so it will not move to this goal; \
             turn it on with: servobus write --port {port} --id {id} torque_enable 1"
        );
    }
}

/// Runs `servobus set-id`.
pub fn set_id(args: SetIdArgs) -> anyhow::Result<ExitCode> {
    check_id(args.new_id)?;
    catch_signals();
    let (mut bus, _) = open_servo(&args.servo)?;
    if args.new_id == args.servo.id {
        outln!("servo {} already has ID {}", args.servo.id, args.new_id)?;
        return Ok(ExitCode::SUCCESS);
    }
    refuse_taken(&mut bus, args.new_id)?;
    before_eeprom_write()?;
    let w = bus.write_eeprom(args.servo.id, addr::ID, &[args.new_id])?;
    if servobus_robot::bus::stop_signal().is_none() {
        bus.ping(w.id)
            .with_context(|| format!("servo does not answer at its new ID {}", w.id))?;
    }
    let said = outln!("servo {} is now ID {} (persisted)", args.servo.id, w.id);
    after_eeprom_write(&format!("servo {} was given ID {}", args.servo.id, w.id))?;
    said?;
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    #[test]
    fn scaled_units_read_as_people_write_them() {
        assert_eq!(super::in_unit(120, "0.1 V"), "12.0 V (raw 120)");
        assert_eq!(
            super::in_unit(50, "100 steps/s^2"),
            "5000 steps/s^2 (raw 50)"
        );
        assert_eq!(super::in_unit(-30, "steps"), "-30 steps");
        assert_eq!(super::in_unit(7, ""), "7");
    }

    #[test]
    fn a_baud_rate_index_reads_with_its_rate() {
        use servobus_protocol::registers::Series;
        let reg = Series::Sts.map().get("baud_rate").expect("baud_rate");
        assert_eq!(super::human_value(0, reg), "0 (1000000 baud)");
        assert_eq!(super::human_value(4, reg), "4 (115200 baud)");
    }
}
