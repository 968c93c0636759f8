//! Subcommands of the `servobus` binary, one module each.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod bench;
mod budget;
mod bus;
mod decode;
mod doctor;
mod monitor;
mod plan;
mod play;
mod sim;

/// Smooth, on-time motion for Feetech serial-bus servos.
#[derive(Debug, Parser)]
#[command(name = "servobus", version, about, propagate_version = true)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Play a motion file on the simulated robot, or on real servos with --port.
    Play(play::Args),
    /// Plan a motion and print its timing, peaks and ranges without moving.
    Plan(plan::Args),
    /// Print the bus budget of a robot: bytes and time per cycle, maximum rate.
    Budget(budget::Args),
    /// Measure the achieved bus update rate of a robot's buses.
    Bench(bench::Args),
    /// Serve a robot file's simulated servos on a pseudo-terminal.
    Sim(sim::Args),
    /// Find every servo on a port.
    Scan(bus::ScanArgs),
    /// Ping one servo.
    Ping(bus::PingArgs),
    /// Read a register of one servo.
    Read(bus::ReadArgs),
    /// Write a register of one servo (EEPROM registers persist: said before doing it).
    Write(bus::WriteArgs),
    /// Change a servo's ID (refuses an ID already present).
    SetId(bus::SetIdArgs),
    /// Decode frames written in hex.
    Decode(decode::Args),
    /// Check a bus against the robot file and the usual set-up mistakes.
    Doctor(doctor::Args),
    /// Watch every servo live: position, load, voltage, temperature, flags.
    Monitor(monitor::Args),
}

/// Runs the parsed command line and returns the process exit code.
pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Play(args) => play::run(args),
        Command::Plan(args) => plan::run(args),
        Command::Budget(args) => budget::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Sim(args) => sim::run(args),
        Command::Scan(args) => bus::scan(args),
        Command::Ping(args) => bus::ping(args),
        Command::Read(args) => bus::read(args),
        Command::Write(args) => bus::write(args),
        Command::SetId(args) => bus::set_id(args),
        Command::Decode(args) => decode::run(args),
        Command::Doctor(args) => doctor::run(args),
        Command::Monitor(args) => monitor::run(args),
    }
}
