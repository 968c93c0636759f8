//! Read and write the positions of Feetech servos with `servobus-driver`
//! alone: typed registers, one result per servo, the sign handled.
//!
//! ```sh
//! # Six simulated STS3215 in virtual time: no hardware, no pty.
//! cargo run -p servobus-driver --example positions -- --sim --nudge 100
//! # A real bus (or `servobus sim --link /tmp/arm` on a pseudo-terminal).
//! cargo run -p servobus-driver --example positions -- --port /dev/ttyACM0
//! ```
//!
//! Options: `--baud B` (default 1000000), `--ids 1,2,3` (default 1 to 6),
//! `--nudge STEPS` (default 0). Every servo that answers gets its own
//! position back as its goal, plus the nudge. With a nudge the torque is
//! switched on and the servos move: make sure the arm is free to. Without
//! one nothing moves and the torque is left as it is.

use std::process::ExitCode;
use std::time::Duration;

use servobus_driver::registers::{self, sts};
use servobus_driver::{Bus, BusError, BusSettings, Clock, ManualClock, Series, Servos, Transport};
use servobus_sim::{SimBus, SimServo};

/// What the command line asked for.
struct Args {
    port: Option<String>,
    baud: u32,
    ids: Vec<u8>,
    nudge: i16,
}

fn parse(mut words: impl Iterator<Item = String>) -> Result<Args, String> {
    let mut args = Args {
        port: None,
        baud: 1_000_000,
        ids: (1..=6).collect(),
        nudge: 0,
    };
    let mut sim = false;
    while let Some(word) = words.next() {
        let mut value = || words.next().ok_or(format!("{word} needs a value"));
        match word.as_str() {
            "--sim" => sim = true,
            "--port" => args.port = Some(value()?),
            "--baud" => args.baud = value()?.parse().map_err(|e| format!("--baud: {e}"))?,
            "--nudge" => args.nudge = value()?.parse().map_err(|e| format!("--nudge: {e}"))?,
            "--ids" => {
                args.ids = value()?
                    .split(',')
                    .map(|id| id.trim().parse().map_err(|e| format!("--ids: {id}: {e}")))
                    .collect::<Result<_, _>>()?;
            }
            other => return Err(format!("unknown argument {other}")),
        }
    }
    match (sim, &args.port) {
        (true, Some(_)) => Err("give --port or --sim, not both".into()),
        (false, None) => Err("give --port PATH or --sim".into()),
        _ => Ok(args),
    }
}

fn main() -> ExitCode {
    let args = match parse(std::env::args().skip(1)) {
        Ok(args) => args,
        Err(e) => {
            eprintln!("error: {e}\nusage: positions (--port PATH | --sim) [--baud B] [--ids 1,2,3] [--nudge STEPS]");
            return ExitCode::FAILURE;
        }
    };
    let done = match &args.port {
        Some(port) => Servos::open(port, args.baud).and_then(|mut s| show(&mut s, &args)),
        None => show(&mut simulated(&args), &args),
    };
    match done {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// STS3215 servos with the IDs asked for, spread over their travel, on a
/// simulated bus in virtual time.
fn simulated(args: &Args) -> Servos<SimBus> {
    let clock = ManualClock::new();
    let servos = args.ids.iter().enumerate().map(|(i, &id)| {
        SimServo::sts3215(id)
            .with_return_delay(Duration::ZERO)
            .with_position(1024 + 400 * i as i32)
    });
    let sim = SimBus::new(clock.clone(), args.baud).with_servos(servos);
    Servos::new(Bus::new(sim, BusSettings::new(Series::Sts)))
}

/// Degrees per step of servo `id`, from the model it reports.
fn deg_per_step<T: Transport>(servos: &mut Servos<T>, id: u8) -> Option<f64> {
    let number = servos.read(id, sts::MODEL_NUMBER).ok()?;
    registers::model_by_number(number).map(|m| m.deg_per_tick())
}

/// Reads every position, writes the goals, and reads again.
fn show<T: Transport>(servos: &mut Servos<T>, args: &Args) -> Result<(), BusError> {
    let before = servos.sync_read(sts::PRESENT_POSITION, &args.ids)?;
    let mut goals = Vec::new();
    for (&id, position) in args.ids.iter().zip(&before) {
        match position {
            Ok(steps) => {
                let deg = deg_per_step(servos, id).unwrap_or(f64::NAN);
                println!(
                    "Servo {id} is at {steps} steps ({:.1} degrees).",
                    f64::from(*steps) * deg
                );
                goals.push((id, steps.saturating_add(args.nudge)));
            }
            Err(missing) => println!("Servo {id} did not answer: {}.", missing.reason),
        }
    }
    if goals.is_empty() {
        println!("No servo answered: nothing to write.");
        return Ok(());
    }
    if args.nudge != 0 {
        let on: Vec<(u8, u8)> = goals.iter().map(|&(id, _)| (id, 1)).collect();
        servos.sync_write(sts::TORQUE_ENABLE, &on)?;
    }
    servos.sync_write(sts::GOAL_POSITION, &goals)?;
    println!(
        "Wrote {} goal positions, {:+} steps from where the servos were.",
        goals.len(),
        args.nudge
    );
    let later = servos.clock().now() + Duration::from_secs(1);
    servos.clock().sleep_until(later);
    let ids: Vec<u8> = goals.iter().map(|&(id, _)| id).collect();
    let after = servos.sync_read(sts::PRESENT_POSITION, &ids)?;
    for (&(id, goal), position) in goals.iter().zip(&after) {
        match position {
            Ok(steps) => println!("One second later servo {id} is at {steps} steps (goal {goal})."),
            Err(missing) => println!(
                "One second later servo {id} did not answer: {}.",
                missing.reason
            ),
        }
    }
    Ok(())
}
