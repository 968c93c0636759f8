//! Checking every bus of a robot: on the ports the robot file and the
//! program give, or on the built-in simulator when no bus has a port, with
//! the fixes applied when asked and each bus checked again after them.

use servobus_config::{BusConfig, Robot};
use servobus_driver::{Bus, Transport};

use super::{apply, examine, BusPort, Examined, Finding, FixOutcome, Fixing, PortKind};
use crate::ports::{bus_ports, open_bus, Allowance};
use crate::Error;

/// What [`check`] does beside examining.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CheckOptions {
    /// Apply the fixes that are writes, then examine again.
    pub fix: bool,
    /// With `fix`: store homing offsets in EEPROM instead of setting them
    /// for the session, and store what the robot file asks of the servos'
    /// EEPROM (operating modes, `servo:` settings).
    pub write_servos: bool,
}

/// What was found on one bus.
#[derive(Debug)]
pub struct BusCheck {
    /// The bus's name in the robot file.
    pub name: String,
    /// Its port (none: the built-in simulator) and baud rate.
    pub at: BusPort,
    /// The first examination.
    pub first: Examined,
    /// The fixes applied, with [`CheckOptions::fix`].
    pub fixes: Vec<FixOutcome>,
    /// The examination after the fixes, when any was applied.
    pub after: Option<Examined>,
}

impl BusCheck {
    /// The findings that stand: after the fixes when there were any.
    pub fn standing(&self) -> &[Finding] {
        &self.after.as_ref().unwrap_or(&self.first).findings
    }
}

/// What was found on a robot.
#[derive(Debug)]
pub struct Checkup {
    /// Each bus checked, in the robot file's order.
    pub buses: Vec<BusCheck>,
    /// The buses not checked: they have no port while others have one.
    pub unchecked: Vec<String>,
}

impl Checkup {
    /// The findings that stand on every bus.
    pub fn standing(&self) -> Vec<Finding> {
        self.buses
            .iter()
            .flat_map(|b| b.standing().iter().cloned())
            .collect()
    }
}

/// Checks every bus of `robot`: on the port `ports[i]` gives bus `i`, the
/// robot file's `port:` past them, or on the built-in simulator (in
/// virtual time) when no bus has a port. A bus without a port while others
/// have one is left unchecked. The calibration is examined, not enforced:
/// servos that do not match it are findings.
///
/// # Errors
/// [`Error::Open`] when a port cannot be opened, [`Error::Simulator`]
/// when the robot cannot be simulated, [`Error::Unfinished`] when a port
/// fails mid-check.
pub fn check<S: AsRef<str>>(
    robot: &Robot,
    ports: &[S],
    options: &CheckOptions,
) -> Result<Checkup, Error> {
    let ports = bus_ports(robot, ports);
    let mut checkup = Checkup {
        buses: Vec::new(),
        unchecked: Vec::new(),
    };
    if ports.iter().all(Option::is_none) {
        let buses = crate::sim::virtual_buses(robot).map_err(Error::Simulator)?;
        for (index, (mut bus, cfg)) in buses.into_iter().zip(&robot.buses).enumerate() {
            let target = BusPort {
                port: None,
                baud: cfg.baud,
            };
            let kind = PortKind::Simulator;
            let checked = check_bus(&mut bus, (robot, index, cfg), target, &kind, options)?;
            checkup.buses.push(checked);
        }
        return Ok(checkup);
    }
    for (index, (cfg, port)) in robot.buses.iter().zip(ports).enumerate() {
        let Some(port) = port else {
            checkup.unchecked.push(cfg.name.clone());
            continue;
        };
        // A slow adapter is one of the findings.
        let mut bus = open_bus(cfg, &port, Allowance::Assumed).map_err(Error::Open)?;
        let kind = PortKind::of(bus.transport());
        let target = BusPort {
            port: Some(port),
            baud: cfg.baud,
        };
        let checked = check_bus(&mut bus, (robot, index, cfg), target, &kind, options)?;
        checkup.buses.push(checked);
    }
    Ok(checkup)
}

/// Examines bus `index` of `robot` (its `cfg`) through `bus` (on a port of
/// `kind`, whose fixes run at `target`) and, with [`CheckOptions::fix`],
/// applies the fixes and examines it again.
fn check_bus<T: Transport>(
    bus: &mut Bus<T>,
    (robot, index, cfg): (&Robot, usize, &BusConfig),
    target: BusPort,
    kind: &PortKind,
    options: &CheckOptions,
) -> Result<BusCheck, Error> {
    let unfinished = |source| Error::Unfinished {
        bus: cfg.name.clone(),
        source,
    };
    let first = examine(bus, robot, cfg, &target, kind).map_err(unfinished)?;
    let mut fixes = Vec::new();
    let mut after = None;
    // A fix only `--write-servos` applies is left alone without it: then
    // nothing changed, and nothing is examined again.
    let applies = |f: &Finding| f.fixable() && (options.write_servos || !f.needs_write_servos());
    if options.fix && first.findings.iter().any(applies) {
        let how = Fixing {
            robot,
            bus: index,
            write_servos: options.write_servos,
        };
        fixes = apply(bus, &first.findings, &how).map_err(unfinished)?;
        // Stopped by a signal: said at once, not examined again.
        if servobus_driver::stop_signal().is_none() {
            after = Some(examine(bus, robot, cfg, &target, kind).map_err(unfinished)?);
        }
    }
    Ok(BusCheck {
        name: cfg.name.clone(),
        at: target,
        first,
        fixes,
        after,
    })
}
