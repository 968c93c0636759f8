//! `servobus sim`: serve a robot file's simulated servos on a pseudo-terminal.

use std::io::Write;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::{bail, Context};
use servobus_runtime::config::{load_robot, Robot};
use servobus_sim::{Faults, PtyServer, SimServo};

const FAULTS_HELP: &str = "\
Fault injection: comma-separated items, applied to every reply independently.
  drop=P        a reply is not sent, with probability P (0..1)
  corrupt=P     one byte of a reply is corrupted, with probability P
  delay=P       a reply starts late, with probability P ...
  delay_us=N    ... by N microseconds (default 2000)
  seed=N        seed of the random source (default 0): same seed, same faults
  echo          echo every request back (same as --echo)
  vanish=ID     servo ID is disconnected (repeatable)
  block=ID      servo ID's shaft is blocked: overload after the protection time (repeatable)
  overheat=ID   servo ID starts at its temperature limit (repeatable)
  supply=V      every servo's supply at V volts; supply=ID:V for one servo
  firmware=ID:MAJOR.MINOR   servo ID reports another firmware version
  baud=ID:RATE  servo ID listens at another baud rate (e.g. 3:115200)
  duplicate=FROM:TO         servo FROM answers as ID TO (two servos share TO)
Example: --faults drop=0.01,corrupt=0.01,seed=7";

/// Arguments of `servobus sim`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The robot file whose servos to serve.
    #[arg(long)]
    pub robot: std::path::PathBuf,
    /// Make this path a symbolic link to the pty (removed on exit).
    #[arg(long)]
    pub link: Option<std::path::PathBuf>,
    /// Do not pace bytes at the wire rate (replies come at once).
    #[arg(long)]
    pub no_pacing: bool,
    /// Fault injection, e.g. `drop=0.01,corrupt=0.01,seed=7` (see --help).
    #[arg(long, long_help = FAULTS_HELP)]
    pub faults: Option<String>,
    /// Echo every request back, as a half-duplex adapter without direction control does.
    #[arg(long)]
    pub echo: bool,
    /// Serve only the bus with this name (default: every bus of the robot
    /// on one pty, at the first bus's baud rate; IDs must then be distinct).
    #[arg(long)]
    pub bus: Option<String>,
}

/// Runs `servobus sim`.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let robot = load_robot(&args.robot)?;
    let mut faults = match &args.faults {
        Some(spec) => spec
            .parse::<Faults>()
            .with_context(|| format!("--faults {spec}"))?,
        None => Faults::none(),
    };
    faults.echo |= args.echo;
    let (baud, servos) = servos_of(&robot, args.bus.as_deref())?;
    let count = servos.len();
    let mut server = PtyServer::open(baud, servos)?;
    if let Some(link) = &args.link {
        server.link_to(link)?;
    }
    server.set_pacing(!args.no_pacing);
    server.set_faults(faults);

    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst))
        .context("cannot install the SIGINT/SIGTERM handler")?;

    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "serving {count} servos on {}",
        server.client_path().display()
    )?;
    out.flush()?;
    drop(out);

    let served = server.serve(&stop);
    // Dropping the server removes the link, also after an I/O error.
    drop(server);
    served?;
    Ok(ExitCode::SUCCESS)
}

/// The servos to serve and the baud rate to serve them at: each joint's
/// servo with its ID, model, the bus's return delay, and its shaft at the
/// joint's rest position.
fn servos_of(robot: &Robot, only: Option<&str>) -> anyhow::Result<(u32, Vec<SimServo>)> {
    let buses: Vec<_> = match only {
        Some(name) => {
            let Some(bus) = robot.buses.iter().find(|b| b.name == name) else {
                let names: Vec<&str> = robot.buses.iter().map(|b| b.name.as_str()).collect();
                bail!(
                    "{}: no bus named `{name}` (buses: {})",
                    robot.path.display(),
                    names.join(", ")
                );
            };
            vec![bus]
        }
        None => robot.buses.iter().collect(),
    };
    let Some(first) = buses.first() else {
        bail!("{}: the robot has no bus", robot.path.display());
    };
    let baud = first.baud;
    let mut seen = std::collections::HashMap::new();
    let mut servos = Vec::new();
    for bus in buses {
        for joint in &bus.joints {
            if let Some(other) = seen.insert(joint.id, (&bus.name, &joint.name)) {
                bail!(
                    "{}: ID {} is used by `{}` on bus `{}` and by `{}` on bus `{}`; \
                     serve one bus at a time with --bus",
                    robot.path.display(),
                    joint.id,
                    other.1,
                    other.0,
                    joint.name,
                    bus.name
                );
            }
        }
        // Every servo listens at the first bus's rate: that is the pty's.
        let mut served = bus.clone();
        served.baud = baud;
        servos.extend(servobus_runtime::sim::bus_servos(robot, &served)?);
    }
    Ok((baud, servos))
}
