//! Subcommands of the `servobus` binary, one module each.
//!
//! Adding a subcommand: a module with `Args` and `run`, a variant in
//! [`Command`] and a line in [`run`]. A robot or motion argument takes
//! `value_parser = flags::robot_arg` (or `motion_arg`) of
//! [`crate::shared::flags`] to accept built-in names as well as files; a
//! number takes one of the range-checked parsers of
//! [`crate::shared::args`] (`rate_arg`, `run_seconds_arg`, ...).

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod bench;
mod budget;
mod bus;
mod calibrate;
mod decode;
mod docs;
mod doctor;
mod fk;
mod follow;
mod init;
mod list;
mod monitor;
mod plan;
mod play;
#[cfg(feature = "zenoh")]
mod serve;
#[cfg(not(feature = "zenoh"))]
mod serve_hint;
mod sim;
mod stream;
mod teach;

const EXIT_STATUS: &str = "\
Exit status:
  0  ok
  1  a problem was found (a servo missing or failing, a fault, a bad frame)
  2  usage or input error (command line, robot or motion file, port)";

const AFTER_HELP: &str = "\
A ROBOT or MOTION argument is a file path or the name of a built-in robot or
motion (`servobus list`); when a file of that name exists, the file wins.";

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
    /// Calibrate a physical robot: torque off, pose held, joints swept; writes the calibration file.
    Calibrate(calibrate::Args),
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
    /// List the register names read and write take, with addresses and units.
    Registers(bus::RegistersArgs),
    /// Decode frames written in hex.
    Decode(decode::Args),
    /// List the built-in robots and motions.
    List(list::Args),
    /// Write a starter robot file and motion to edit.
    Init(init::Args),
    /// Print a shell completion script (bash, zsh, fish, ...).
    Completions(docs::CompletionsArgs),
    /// Print the manual page (roff): `servobus man | man -l -`.
    Man(docs::ManArgs),
    /// Pose the robot by hand (torque off) and write a motion file.
    Teach(teach::Args),
    /// Check a bus against the robot file and the usual set-up mistakes.
    Doctor(doctor::Args),
    /// Watch every servo live: position, load, voltage, temperature, flags.
    Monitor(monitor::Args),
    /// Follow joint targets given as JSON lines on stdin, smoothly (jerk limited).
    Stream(stream::Args),
    /// A leader arm moved by hand drives a follower arm (both simulated without ports).
    Follow(follow::Args),
    /// Print where a pose puts every joint frame and named frame (mm, roll/pitch/yaw).
    Fk(fk::FkArgs),
    /// Find the joint angles that put a named frame at a point, or say why there are none.
    Ik(fk::IkArgs),
    /// Run the robot live as a Zenoh node: state out, targets and commands in (--features zenoh).
    #[cfg(feature = "zenoh")]
    Serve(serve::Args),
    /// Not in this build: says how to build `serve` (--features zenoh).
    #[cfg(not(feature = "zenoh"))]
    #[command(hide = true)]
    Serve(serve_hint::Args),
}

/// The command line's definition, with the exit codes and the note on
/// built-in names added to every command's `--help` (the man page and the
/// completions are generated from it too).
pub fn command() -> clap::Command {
    use clap::CommandFactory;
    let with_exit = |help: Option<String>| match help {
        Some(h) => format!("{h}\n\n{EXIT_STATUS}"),
        None => EXIT_STATUS.to_owned(),
    };
    let top = Cli::command();
    let top_help = with_exit(Some(AFTER_HELP.to_owned()));
    top.after_help(top_help).mut_subcommands(|sub| {
        let own = sub.get_after_help().map(|h| h.to_string());
        // A command that states its own exit status (doctor) keeps it alone.
        if own
            .as_deref()
            .is_some_and(|h| h.starts_with("Exit status ("))
        {
            return sub;
        }
        let help = with_exit(own);
        sub.after_help(help)
    })
}

/// Parses the process's arguments (exits 2 on a usage error, 0 for `--help`).
pub fn parse() -> Cli {
    use clap::FromArgMatches;
    let matches = command().get_matches();
    Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit())
}

/// Runs the parsed command line and returns the process exit code.
pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        // A group's play is announced to the robots serving the group, not
        // played here.
        #[cfg(feature = "zenoh")]
        Command::Play(args) if args.zenoh_group.is_some() => {
            let group = args.zenoh_group.as_deref().unwrap_or_default();
            serve::announce(&args.motion, group, args.start_in, &args.connect)
        }
        Command::Play(args) => play::run(args),
        Command::Plan(args) => plan::run(args),
        Command::Budget(args) => budget::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Calibrate(args) => calibrate::run(args),
        Command::Sim(args) => sim::run(args),
        Command::Scan(args) => bus::scan(args),
        Command::Ping(args) => bus::ping(args),
        Command::Read(args) => bus::read(args),
        Command::Write(args) => bus::write(args),
        Command::SetId(args) => bus::set_id(args),
        Command::Registers(args) => bus::registers(args),
        Command::Decode(args) => decode::run(args),
        Command::List(args) => list::run(args),
        Command::Init(args) => init::run(args),
        Command::Completions(args) => docs::completions(args, command()),
        Command::Man(args) => docs::man(args, command()),
        Command::Teach(args) => teach::run(args),
        Command::Doctor(args) => doctor::run(args),
        Command::Monitor(args) => monitor::run(args),
        Command::Stream(args) => stream::run(args),
        Command::Follow(args) => follow::run(args),
        Command::Fk(args) => fk::fk(args),
        Command::Ik(args) => fk::ik(args),
        #[cfg(feature = "zenoh")]
        Command::Serve(args) => serve::run(args),
        #[cfg(not(feature = "zenoh"))]
        Command::Serve(args) => serve_hint::run(args),
    }
}
