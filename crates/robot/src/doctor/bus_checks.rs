//! Checks across the servos of one bus: firmware versions, the supply
//! along the chain, and the adapter's latency.

use std::collections::BTreeMap;
use std::time::Duration;

use servobus_driver::{Bus, BusError, Transport};

use super::checks::ServoState;
use super::probe::{finding, Ctx, PortKind};
use super::{Advice, Change, Finding, Fix, SetupStep as Step, Severity};

/// How far the measured latency may exceed the robot file's before it is
/// worth a warning (scheduling noise of the host).
const LATENCY_SLACK: Duration = Duration::from_micros(300);
/// PINGs the adapter's latency is measured with.
const LATENCY_SAMPLES: u32 = 8;
/// The longest latency waited for while measuring the adapter (an FTDI
/// latency timer goes up to 255 ms).
const LATENCY_CEILING: Duration = Duration::from_millis(300);
/// Servos whose firmware differs from the most common version on the bus.
pub(crate) fn firmware(ctx: &Ctx<'_>, servos: &[ServoState], out: &mut Vec<Finding>) {
    let mut count: BTreeMap<(u8, u8), usize> = BTreeMap::new();
    for s in servos {
        *count.entry(s.firmware()).or_default() += 1;
    }
    let Some((&usual, _)) = count.iter().max_by_key(|(v, n)| (**n, **v)) else {
        return;
    };
    for s in servos.iter().filter(|s| s.firmware() != usual) {
        let (major, minor) = s.firmware();
        let mut f = finding(
            ctx,
            Severity::Warning,
            Step::Check,
            Some(s.id),
            Some("firmware_major"),
        );
        f.problem = format!(
            "firmware {major}.{minor} differs from {}.{} on the other servos: older firmware \
             answers some instructions differently (\"incorrect status packet\")",
            usual.0, usual.1
        );
        f.advice = Advice::UpdateFirmware {
            id: s.id,
            version: usual,
        };
        out.push(f);
    }
}

/// How much lower one servo's supply may read than another's on the same
/// bus before the wiring is suspect, in 0.1 V (the voltage register's
/// resolution is 0.1 V; healthy daisy chains read within a few tenths).
const SUPPLY_DROP_DV: i32 = 6;

/// A supply that reads markedly lower at some servos than at others: the
/// wires drop voltage, and drop more under load.
pub(crate) fn supply_drop(ctx: &Ctx<'_>, servos: &[ServoState], out: &mut Vec<Finding>) {
    let readings: Vec<(u8, i32)> = servos
        .iter()
        .filter_map(|s| Some((s.id, s.value("present_voltage")?)))
        .collect();
    let Some(&(top_id, top)) = readings.iter().max_by_key(|r| r.1) else {
        return;
    };
    for &(id, v) in readings.iter().filter(|r| top - r.1 >= SUPPLY_DROP_DV) {
        let mut f = finding(
            ctx,
            Severity::Warning,
            Step::Check,
            Some(id),
            Some("present_voltage"),
        );
        f.problem = format!(
            "supply reads {:.1} V here but {:.1} V at servo {top_id}: the wiring drops {:.1} V \
             before any load, more while moving",
            f64::from(v) / 10.0,
            f64::from(top) / 10.0,
            f64::from(top - v) / 10.0
        );
        f.measured = Some(v);
        f.advice = Advice::Wiring;
        out.push(f);
    }
}

/// The FTDI latency timer and the measured round trip against the robot
/// file's `latency_us`.
pub(crate) fn latency<T: Transport>(
    bus: &mut Bus<T>,
    ctx: &Ctx<'_>,
    kind: &PortKind,
    servos: &[ServoState],
    out: &mut Vec<Finding>,
) -> Result<(), BusError> {
    if let PortKind::Serial(Some(ftdi)) = kind {
        if ftdi.is_too_high() {
            let mut f = finding(ctx, Severity::Warning, Step::Check, None, None);
            f.problem = format!(
                "the FTDI adapter's latency timer is {} ms: every reply waits that long",
                ftdi.latency.as_millis()
            );
            f.measured = i32::try_from(ftdi.latency.as_millis()).ok();
            f.advice = Advice::Run(Fix::FtdiLatency {
                sysfs: ftdi.sysfs_path.clone(),
            });
            out.push(f);
        }
    }
    if *kind == PortKind::Simulator {
        return Ok(());
    }
    let Some(first) = servos.first() else {
        return Ok(());
    };
    // The measurement subtracts the return delay the settings name: use the
    // servo's own.
    let delay = first.value("return_delay").unwrap_or(0).max(0) as u64 * 2;
    let s = bus
        .settings()
        .with_return_delay(Duration::from_micros(delay));
    bus.set_settings(s);
    let m = match bus.measure_latency(first.id, LATENCY_SAMPLES, LATENCY_CEILING) {
        Ok(m) => m,
        Err(e) if e.is_retryable() => return Ok(()),
        Err(e) => return Err(e),
    };
    let configured = ctx.bus.latency;
    let us = |d: Duration| d.as_micros();
    let mut f = finding(ctx, Severity::Info, Step::Check, Some(first.id), None);
    let assumed = if ctx.bus.latency_auto {
        // `auto` is no figure: the run measures the link and follows it.
        "the robot file's `latency_us: auto` measures it when a run starts and follows it".into()
    } else {
        format!("the robot file assumes {} us", us(configured))
    };
    f.problem = format!(
        "round trip beyond the wire: {}..{} us (mean {} us); {assumed}",
        us(m.min),
        us(m.max),
        us(m.mean),
    );
    if *kind == PortKind::Pty {
        f.problem
            .push_str(" (a pseudo-terminal: the host's scheduling, not an adapter)");
    } else if !ctx.bus.latency_auto && m.mean > configured + LATENCY_SLACK {
        f.severity = Severity::Warning;
        // Rounded up to 100 us.
        let want = m.max.as_micros().div_ceil(100) * 100;
        f.advice = Advice::EditRobotFile(ctx.edit_robot_file(Change::SetLatency {
            bus: ctx.bus.name.clone(),
            us: want,
        }));
    }
    out.push(f);
    Ok(())
}
