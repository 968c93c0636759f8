//! Examining one bus: who answers, at which baud rate, what their registers
//! hold, and how slow the adapter is.

use std::time::Duration;

use servobus_config::{BusConfig, JointConfig, Robot, RobotCalibration};
use servobus_driver::{
    Bus, BusError, BusSettings, Clock, FtdiLatency, SerialTransport, Transport, PATIENCE,
    PATIENT_TRIES,
};
use servobus_protocol::registers::{self, addr, Series};
use servobus_protocol::MAX_ID;

use super::bus_checks;
use super::checks::{read_len, ServoState};
use super::{
    Action, Advice, Change, Finding, Fix, NewId, SetupStep as Step, Severity, SilentServo,
};

/// The longest return delay a servo can have (register 7 at 255, 2 us
/// units): the doctor waits this long so that it hears servos still at
/// their factory delay.
pub(crate) const MAX_RETURN_DELAY: Duration = Duration::from_micros(510);

/// Where the fixes are run: the port as the user names it, and the bus's
/// baud rate.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BusPort {
    /// The port; `None` for the built-in simulator.
    pub port: Option<String>,
    /// The bus's baud rate.
    pub baud: u32,
}

impl BusPort {
    /// The write of `value` into `register` of servo `id`.
    pub fn write_command(&self, id: u8, register: &str, value: i32) -> Fix {
        Fix::Write {
            port: self.port.clone(),
            baud: self.baud,
            id,
            register: register.to_owned(),
            value,
        }
    }

    fn set_id_command(&self, id: u8, new_id: NewId) -> Fix {
        Fix::SetId {
            port: self.port.clone(),
            baud: self.baud,
            id,
            new_id,
        }
    }

    /// Every fix of the doctor for the robot `robot` (as a program names
    /// it) on this port, storing homing offsets in EEPROM when
    /// `write_servos`.
    pub fn fix_all_command(&self, robot: &str, write_servos: bool) -> Fix {
        Fix::DoctorFix {
            robot: robot.to_owned(),
            port: self.port.clone(),
            write_servos,
        }
    }
}

/// Every fix of the doctor for `robot` on `target` (see
/// [`BusPort::fix_all_command`]); a built-in robot named by its name.
pub fn fix_all_command(target: &BusPort, robot: &Robot, write_servos: bool) -> Fix {
    target.fix_all_command(
        &servobus_config::builtin::argument(&robot.path),
        write_servos,
    )
}

/// What kind of port the bus is on, for the latency checks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PortKind {
    /// The built-in simulator in virtual time: no adapter at all.
    Simulator,
    /// A pseudo-terminal (`servobus sim`): its round trip is the host's
    /// scheduling, not an adapter's.
    Pty,
    /// A serial adapter, with its FTDI latency timer when it has one.
    Serial(Option<FtdiLatency>),
}

impl PortKind {
    /// The kind of the port `transport` is open on.
    pub fn of<C: Clock>(transport: &SerialTransport<C>) -> PortKind {
        if transport.is_pty() {
            PortKind::Pty
        } else {
            PortKind::Serial(transport.ftdi_latency().cloned())
        }
    }
}

/// What one examination found.
#[derive(Debug, Clone, PartialEq)]
pub struct Examined {
    /// Every finding, errors first.
    pub findings: Vec<Finding>,
    /// The servos read, in ID order.
    pub servos: Vec<ServoState>,
    /// The servos the robot file names for this bus.
    pub expected: usize,
}

/// The robot, bus and target every check of one bus shares.
pub(crate) struct Ctx<'a> {
    pub robot: &'a Robot,
    pub bus: &'a BusConfig,
    pub target: &'a BusPort,
    /// Real servos (or `servobus sim`'s), not the built-in simulator.
    pub real: bool,
}

impl<'a> Ctx<'a> {
    /// The joint the robot file gives ID `id` on this bus, if any.
    fn joint_of(&self, id: u8) -> Option<&'a JointConfig> {
        self.bus.joints.iter().find(|j| j.id == id)
    }

    /// Real servos without a calibration: their joint angles mean nothing
    /// yet (each horn sits at its own angle).
    pub(crate) fn uncalibrated(&self) -> bool {
        self.real && !matches!(self.robot.calibration, RobotCalibration::Applied { .. })
    }
}

/// Examines the bus `cfg` of `robot` through `bus`: pings every ID at the
/// bus's rate, looks for the missing servos at the other rates, reads every
/// servo that answers and runs the checks, then measures the adapter. The
/// bus's settings are left as they were. Nothing is written.
///
/// # Errors
/// Only when the transport fails ([`BusError::Transport`]); servos that do
/// not answer are findings, not errors.
pub fn examine<T: Transport>(
    bus: &mut Bus<T>,
    robot: &Robot,
    cfg: &BusConfig,
    target: &BusPort,
    kind: &PortKind,
) -> Result<Examined, BusError> {
    let saved = *bus.settings();
    let ctx = Ctx {
        robot,
        bus: cfg,
        target,
        real: *kind != PortKind::Simulator,
    };
    let result = examine_inner(bus, &ctx, kind);
    bus.set_settings(saved);
    result
}

/// [`examine`]'s work, which may leave the bus's settings changed.
fn examine_inner<T: Transport>(
    bus: &mut Bus<T>,
    ctx: &Ctx<'_>,
    kind: &PortKind,
) -> Result<Examined, BusError> {
    let cfg = ctx.bus;
    let mut findings = Vec::new();
    let base = bus.settings().with_return_delay(MAX_RETURN_DELAY);
    // The robot's own servos are waited for patiently (a loaded host or a
    // slow adapter must not make a present servo look absent or garbled):
    // longer deadlines and two more tries.
    let patient = base
        .with_latency(base.link.latency + PATIENCE)
        .with_retries(PATIENT_TRIES - 1);
    let answering = scan(bus, ctx, base, patient)?;
    bus.set_settings(patient);
    let (servos, collided) = read_servos(bus, ctx, &answering, &mut findings)?;

    let extras: Vec<u8> = answering
        .iter()
        .copied()
        .filter(|&id| ctx.joint_of(id).is_none())
        .collect();
    let mut missing: Vec<u8> = cfg
        .joints
        .iter()
        .map(|j| j.id)
        .filter(|id| !answering.contains(id))
        .collect();
    if !missing.is_empty() {
        find_at_other_bauds(bus, ctx, base, &mut missing, &mut findings)?;
        bus.set_settings(base);
    }
    collision_findings(ctx, &collided, &mut missing, &mut findings);
    for &id in &missing {
        findings.push(absent(ctx, id, extras.first().copied()));
    }
    for &id in &extras {
        findings.push(unexpected(ctx, id));
    }

    for s in &servos {
        findings.extend(ctx.servo_findings(s, ctx.joint_of(s.id)));
    }
    if ctx.robot.buses.first().is_some_and(|b| b.name == cfg.name) {
        super::calibration::robot_findings(ctx, &mut findings);
    }
    bus_checks::firmware(ctx, &servos, &mut findings);
    bus_checks::supply_drop(ctx, &servos, &mut findings);
    bus_checks::latency(bus, ctx, kind, &servos, &mut findings)?;
    // In the order a new robot needs them; the worst first within a step.
    findings.sort_by(|a, b| (a.step, b.severity, a.id).cmp(&(b.step, a.severity, b.id)));
    Ok(Examined {
        findings,
        servos,
        expected: cfg.joints.len(),
    })
}

/// Who answers at the bus's rate: the robot's servos asked `patient`ly,
/// absent IDs once at `base` (that keeps the scan short).
fn scan<T: Transport>(
    bus: &mut Bus<T>,
    ctx: &Ctx<'_>,
    base: BusSettings,
    patient: BusSettings,
) -> Result<Vec<u8>, BusError> {
    let mut answering = Vec::new();
    for id in 0..=MAX_ID {
        bus.set_settings(if ctx.joint_of(id).is_some() {
            patient
        } else {
            base.with_retries(0)
        });
        if answers(bus, id)? {
            answering.push(id);
        }
    }
    Ok(answering)
}

/// Reads each `answering` servo whole: the servos read, and the IDs whose
/// replies stay garbled (two servos on one ID). A servo that answers PING
/// but not READ is a finding.
fn read_servos<T: Transport>(
    bus: &mut Bus<T>,
    ctx: &Ctx<'_>,
    answering: &[u8],
    findings: &mut Vec<Finding>,
) -> Result<(Vec<ServoState>, Vec<u8>), BusError> {
    let mut servos = Vec::new();
    let mut collided = Vec::new();
    for &id in answering {
        match read_state(bus, id) {
            Ok(state) => servos.push(state),
            Err(BusError::Corrupt { .. } | BusError::WrongLength { .. }) => collided.push(id),
            Err(e) if e.is_retryable() => findings.push(ping_only(ctx, id)),
            Err(e) => return Err(e),
        }
    }
    Ok((servos, collided))
}

/// Servo `id` answers PING but not READ: an SCS servo at status return
/// level 0.
fn ping_only(ctx: &Ctx<'_>, id: u8) -> Finding {
    let mut f = finding(
        ctx,
        Severity::Error,
        Step::Connect,
        Some(id),
        Some("status_level"),
    );
    f.problem = format!("servo {id} answers PING but not READ: its status return level is 0 (SCS)");
    let reg = registers::SCS.get("status_level");
    f.advice = Advice::Run(ctx.target.write_command(id, "status_level", 2));
    f.action = reg.map(|register| Action::Write {
        id,
        register,
        value: 2,
        silent: true,
        series: Series::Scs,
    });
    f
}

/// The findings of the `collided` IDs, blaming the `missing` servos that
/// most likely have them; those blamed are taken out of `missing`.
fn collision_findings(
    ctx: &Ctx<'_>,
    collided: &[u8],
    missing: &mut Vec<u8>,
    findings: &mut Vec<Finding>,
) {
    // Two servos on one ID while an expected servo is silent: the silent
    // one most likely has that ID. With several silent, any of them may be
    // the one (the colliding replies do not say whose they are): each
    // collision names them all, and none is blamed alone.
    if !collided.is_empty() && missing.len() > 1 {
        let silent: Vec<(u8, &JointConfig)> = missing
            .iter()
            .filter_map(|&m| Some((m, ctx.joint_of(m)?)))
            .collect();
        missing.clear();
        let absent_too = silent.len().saturating_sub(collided.len());
        for &id in collided {
            findings.push(collision_among(ctx, id, &silent, absent_too));
        }
    } else {
        for &id in collided {
            let silent = missing.first().copied();
            missing.retain(|&m| Some(m) != silent);
            findings.push(collision(
                ctx,
                id,
                silent.and_then(|s| Some((s, ctx.joint_of(s)?))),
            ));
        }
    }
}

/// The robot's servo `id` answers at no baud rate; `extra`, a servo the
/// robot file does not name, may be it under another ID.
fn absent(ctx: &Ctx<'_>, id: u8, extra: Option<u8>) -> Finding {
    let joint = ctx.joint_of(id).map_or("?", |j| j.name.as_str());
    let mut f = finding(ctx, Severity::Error, Step::Connect, Some(id), None);
    f.problem = format!("servo {id} (joint `{joint}`) does not answer at any baud rate");
    f.advice = match extra {
        Some(extra) => Advice::GiveItsId {
            servo: extra,
            joint: joint.to_owned(),
            fix: ctx.target.set_id_command(extra, NewId::Id(id)),
        },
        None => Advice::CheckCable(Fix::ScanAllBauds {
            port: ctx.target.port.clone(),
        }),
    };
    f
}

/// Servo `id` answers, but the robot file has no joint with its ID.
fn unexpected(ctx: &Ctx<'_>, id: u8) -> Finding {
    let mut f = finding(ctx, Severity::Warning, Step::Connect, Some(id), Some("id"));
    f.problem = format!("servo {id} answers but the robot file has no joint with ID {id}");
    f.advice = Advice::IdOfItsJoint {
        fix: ctx.target.set_id_command(id, NewId::OfItsJoint),
        edit: ctx.edit_robot_file(Change::AddJoint { id }),
    };
    f
}

/// Whether anything answers as `id`: a READ of the model number first,
/// because a PING's reply with status 0x01 (the voltage flag) is byte for
/// byte the PING itself and is skipped as an echo; then, on an SCS bus, a
/// PING, which an SCS servo at status level 0 answers alone. An STS/SMS
/// servo answers READ at every status level, so on its bus one silent READ
/// settles it: an absent ID costs one deadline, not two (the whole scan
/// takes half as long). Garbled replies count: two servos may share the ID.
fn answers<T: Transport>(bus: &mut Bus<T>, id: u8) -> Result<bool, BusError> {
    let mut number = [0u8; 2];
    let read = bus.read(id, addr::MODEL_NUMBER, &mut number);
    let ping_only_possible = bus.settings().series == Series::Scs;
    let result = match read {
        Err(e) if e.is_timeout() && ping_only_possible => bus.ping(id).map(|_| ()),
        other => other.map(|_| ()),
    };
    match result {
        Ok(()) | Err(BusError::Corrupt { .. } | BusError::WrongLength { .. }) => Ok(true),
        Err(e) if e.is_retryable() => Ok(false),
        Err(e) => Err(e),
    }
}

pub(crate) fn finding(
    ctx: &Ctx<'_>,
    severity: Severity,
    step: Step,
    id: Option<u8>,
    reg: Option<&'static str>,
) -> Finding {
    Finding {
        severity,
        step,
        bus: ctx.bus.name.clone(),
        id,
        register: reg,
        measured: None,
        problem: String::new(),
        advice: Advice::None,
        action: None,
        setting: None,
    }
}

/// Two or more servos answer as `id`; `silent` is the robot's servo that
/// does not answer (its ID and joint), which most likely is one of them.
fn collision(ctx: &Ctx<'_>, id: u8, silent: Option<(u8, &JointConfig)>) -> Finding {
    let mut f = finding(ctx, Severity::Error, Step::Connect, Some(id), Some("id"));
    let set_id = |to: NewId| ctx.target.set_id_command(id, to);
    match silent {
        Some((want, joint)) => {
            f.problem = format!(
                "two servos answer as ID {id} and servo {want} (joint `{}`) is silent: servo \
                 {want} probably has ID {id}",
                joint.name
            );
            f.advice = Advice::UnplugOthers {
                joint: joint.name.clone(),
                fix: set_id(NewId::Id(want)),
            };
        }
        None => {
            f.problem = format!(
                "two or more servos answer as ID {id}: their replies collide and none can be read"
            );
            f.advice = Advice::OneAtATime(set_id(NewId::Free));
        }
    }
    f
}

/// Two servos answer as `id` while the robot's servos `silent` (their IDs
/// and joints) do not answer: one of those most likely has `id`, and
/// `absent_too` of them are missing for another reason (more are silent
/// than IDs collide).
fn collision_among(
    ctx: &Ctx<'_>,
    id: u8,
    silent: &[(u8, &JointConfig)],
    absent_too: usize,
) -> Finding {
    let mut f = finding(ctx, Severity::Error, Step::Connect, Some(id), Some("id"));
    let named: Vec<String> = silent
        .iter()
        .map(|(want, joint)| format!("{want} (joint `{}`)", joint.name))
        .collect();
    let named = match named.split_last() {
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} and {last}", rest.join(", ")),
        None => String::new(),
    };
    let rest = match absent_too {
        0 => String::new(),
        1 => ", and one does not answer at any baud rate".to_owned(),
        n => format!(", and {n} do not answer at any baud rate"),
    };
    f.problem = format!(
        "two servos answer as ID {id} and servos {named} are silent: one of them probably has \
         ID {id}{rest}"
    );
    f.advice = Advice::UnplugOthersOneOf(
        silent
            .iter()
            .map(|(want, joint)| SilentServo {
                id: *want,
                joint: joint.name.clone(),
                fix: ctx.target.set_id_command(id, NewId::Id(*want)),
            })
            .collect(),
    );
    f
}

/// Reads servo `id`'s table from address 0, in the layout of the series its
/// model number names (tried in both byte orders).
pub(crate) fn read_state<T: Transport>(bus: &mut Bus<T>, id: u8) -> Result<ServoState, BusError> {
    let mut bytes = vec![0u8; read_len(Series::Sts)];
    let flags = bus.read(id, addr::FIRMWARE_MAJOR, &mut bytes)?;
    let number = |n: u16| registers::model_by_number(n).map(|m| m.series);
    let series = number(u16::from_le_bytes([bytes[3], bytes[4]]))
        .or_else(|| number(u16::from_be_bytes([bytes[3], bytes[4]])))
        .unwrap_or(bus.settings().series);
    bytes.truncate(read_len(series));
    Ok(ServoState::new(id, series, flags, bytes))
}

/// Looks for the `missing` servos at every other baud rate of the servo
/// table; those found are taken out of `missing`. The transport is back at
/// the bus's rate afterwards.
fn find_at_other_bauds<T: Transport>(
    bus: &mut Bus<T>,
    ctx: &Ctx<'_>,
    base: BusSettings,
    missing: &mut Vec<u8>,
    findings: &mut Vec<Finding>,
) -> Result<(), BusError> {
    let home = ctx.bus.baud;
    let Some(index) = registers::baud_index(home) else {
        return Ok(());
    };
    let rates = crate::scan::table_bauds()
        .into_iter()
        .filter(|&b| b != home);
    for baud in rates {
        bus.set_baud(baud)?;
        bus.set_settings(base.with_retries(1));
        let mut found = Vec::new();
        for &id in missing.iter() {
            if answers(bus, id)? {
                found.push(id);
            }
        }
        for id in found {
            missing.retain(|&m| m != id);
            let mut f = finding(
                ctx,
                Severity::Error,
                Step::Connect,
                Some(id),
                Some("baud_rate"),
            );
            f.problem = format!(
                "servo {id} answers only at {baud} baud; the bus runs at {home}, which is \
                 baud_rate {index} (the register holds an index into the baud table: \
                 {index} = {home} baud)"
            );
            f.advice = Advice::Run(Fix::SetBaud {
                port: ctx.target.port.clone(),
                baud,
                id,
                index,
            });
            f.action = Some(Action::Baud { id, baud, index });
            findings.push(f);
        }
    }
    bus.set_baud(home)
}
