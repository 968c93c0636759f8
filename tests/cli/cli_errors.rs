//! Every error says what to do, once, with `file:line:column` where there is
//! one, and every command exits 0 (ok), 1 (a problem found) or 2 (usage or
//! input error).

use crate::common;

use std::process::{Command, Output};

use common::{
    arg, error, is_root, json, says, scratch, servobus, servobus_in, servobus_unprivileged, stderr,
    stdout, write_file as write, BIN,
};

const ROBOT: &str = "\
name: tiny
buses:
  - name: bus
    baud: 1000000
    joints:
      - {name: a, id: 1, model: sts3215, min: -90, max: 90, max_velocity: 180, max_acceleration: 900}
";

/// `plan` of a motion in a fresh directory with `robot.yaml` next to it.
fn plan_error(test: &str, motion: &str) -> String {
    let dir = scratch(test);
    write(&dir, "robot.yaml", ROBOT);
    write(&dir, "m.yaml", motion);
    error(&servobus_in(&dir, &["plan", "m.yaml"]), 2)
}

#[test]
fn yaml_mistakes_keep_their_position_and_get_a_plain_hint() {
    // (folder, motion, the place named, the hint)
    let cases = [
        (
            "tab",
            "robot: robot.yaml\nkeyframes:\n\t- pose: {a: 0}\n",
            "m.yaml:3:1: ",
            "line 3 is indented with a tab",
        ),
        (
            "brace",
            "robot: robot.yaml\nkeyframes:\n  - pose: {a: 10\n  - pose: {a: 20}\n",
            "m.yaml:3:15: ",
            "the `{` on line 3 is never closed",
        ),
        (
            "colon",
            "robot: robot.yaml\nrepeat:2\nkeyframes:\n  - pose: {a: 0}\n",
            "m.yaml:3:1: ",
            "line 2: put a space after the colon of `repeat:`",
        ),
    ];
    for (test, motion, place, hint) in cases {
        says(&plan_error(test, motion), &[place, hint]);
    }
}

#[test]
fn a_baud_rate_the_servos_cannot_use_is_refused_with_the_valid_ones() {
    let dir = scratch("baud");
    for baud in ["1234567", "2000000"] {
        let robot = write(&dir, "r.yaml", &ROBOT.replace("1000000", baud));
        let err = error(&servobus(&["budget", "--robot", arg(&robot)]), 2);
        says(
            &err,
            &[
                "r.yaml:4:11: buses[0].baud: ",
                &format!("{baud} baud is not a rate"),
                "1000000, 500000, 250000, 128000, 115200, 76800, 57600, 38400",
            ],
        );
    }
}

#[test]
fn a_missing_file_is_said_once_with_what_to_give_instead() {
    let err = error(&servobus(&["plan", "nothere.yaml"]), 2);
    says(
        &err,
        &["nothere.yaml: cannot read: no such file", "built-in"],
    );
    assert_eq!(err.matches("no such file").count(), 1, "{err}");
    assert!(!err.contains("os error"), "{err}");
}

#[test]
fn a_missing_robot_points_at_the_motions_robot_line() {
    let dir = scratch("robot-line");
    write(
        &dir,
        "m.yaml",
        "# wave\nrobot: ../nope.yaml\nkeyframes:\n  - pose: {a: 0}\n",
    );
    let err = error(&servobus_in(&dir, &["plan", "m.yaml"]), 2);
    says(
        &err,
        &[
            "m.yaml:2:8: robot: ",
            "nope.yaml: cannot read: no such file",
            "fix this `robot:`",
        ],
    );
}

#[test]
fn a_missing_port_lists_the_ports_present() {
    let err = error(
        &servobus(&["ping", "--port", "/dev/servobus-none", "--id", "1"]),
        2,
    );
    assert!(
        err.contains("cannot open /dev/servobus-none: no such port"),
        "{err}"
    );
    assert!(err.contains("ports present") || err.contains("no serial ports are present"));
    assert_eq!(err.matches("cannot open").count(), 1, "{err}");
}

#[test]
fn a_port_without_permission_names_the_group_and_the_command() {
    let dir = scratch("denied");
    let port = write(&dir, "port", "");
    // A port like a USB adapter's: owned by group `dialout`, rw for the group.
    let grouped = Command::new("chgrp").arg("dialout").arg(&port).status();
    let group = if grouped.is_ok_and(|s| s.success()) {
        "dialout"
    } else {
        ""
    };
    let mode = if group.is_empty() { "000" } else { "660" };
    assert!(Command::new("chmod")
        .arg(mode)
        .arg(&port)
        .status()
        .is_ok_and(|s| s.success()));
    let port = arg(&port);
    let ping = ["ping", "--port", port, "--id", "1"];
    let out = if is_root() {
        // Root may open anything: run as `nobody`, with no groups.
        servobus_unprivileged(&common::repo(""), &ping)
    } else {
        servobus(&ping)
    };
    let err = error(&out, 2);
    let denied = format!("cannot open {port}: permission denied");
    says(&err, &[&denied, "log out and back in"]);
    if !group.is_empty() {
        says(&err, &["sudo usermod -aG dialout $USER"]);
    }
    assert_eq!(err.matches("ermission denied").count(), 1, "{err}");
}

#[test]
fn exit_codes_and_names_are_documented_in_help() {
    let help = stdout(&servobus(&["--help"]));
    assert!(help.contains("Exit status:"), "{help}");
    for line in ["0  ok", "1  a problem was found", "2  usage or input error"] {
        assert!(help.contains(line), "{line}: {help}");
    }
    assert!(help.contains("the file wins"), "{help}");
    // clap's own usage errors use the same code.
    assert_eq!(servobus(&["play", "--no-such-flag"]).status.code(), Some(2));
}

#[test]
fn a_file_named_like_a_builtin_wins() {
    let dir = scratch("file-wins");
    write(&dir, "so101", &ROBOT.replace("name: tiny", "name: mine"));
    let out = servobus_in(&dir, &["budget", "--robot", "so101", "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let v = json(&out);
    assert_eq!(
        v["buses"][0]["servos"], 1,
        "the file's one servo, not the arm's six"
    );
    let v = json(&servobus_in(
        &dir,
        &["budget", "--robot", "hexapod", "--json"],
    ));
    assert_eq!(
        v["buses"][0]["servos"], 18,
        "a name with no such file is built in"
    );
}

#[test]
fn list_off_a_terminal_gives_whole_descriptions_and_each_motion_s_robot() {
    let out = servobus(&["list"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let list = stdout(&out);
    assert!(!list.contains("..."), "{list}");
    let line = |name: &str| {
        list.lines()
            .find(|l| l.starts_with(&format!("  {name} ")))
            .map(|l| l.split_whitespace().collect::<Vec<_>>().join(" "))
            .unwrap_or_default()
    };
    assert_eq!(
        line("hexapod-walk-turn"),
        "hexapod-walk-turn hexapod Walk forward 30 cm, turn 90 deg to the left on the spot, \
         then step 10 cm to the right, in a tripod gait"
    );
    assert!(
        line("arm-wave").starts_with("arm-wave so101 The SO-101 arm"),
        "{list}"
    );
    assert!(
        line("scs-mini-nod").starts_with("scs-mini-nod scs-mini "),
        "{list}"
    );
    assert!(
        line("hexapod-2bus").ends_with("(left and right), one adapter each"),
        "{list}"
    );
}

#[test]
fn list_shows_the_builtins_and_init_refuses_to_overwrite() {
    let list = stdout(&servobus(&["list"]));
    for name in [
        "so101",
        "hexapod",
        "hexapod-2bus",
        "scs-mini",
        "arm-wave",
        "hexapod-tripod",
    ] {
        assert!(list.contains(&format!("  {name} ")), "{name}: {list}");
    }
    let dir = scratch("init");
    let out = servobus_in(&dir, &["init", "--robot", "hexapod", "starter"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let robot = std::fs::read_to_string(dir.join("starter/robot.yaml")).expect("robot");
    assert!(
        robot.starts_with("# An 18-servo hexapod"),
        "comments kept: {robot}"
    );
    let motion = std::fs::read_to_string(dir.join("starter/motion.yaml")).expect("motion");
    assert!(
        motion.contains("robot: robot.yaml") && motion.contains("# "),
        "{motion}"
    );
    let plan = servobus_in(&dir, &["plan", "starter/motion.yaml", "--json"]);
    assert!(
        plan.status.success(),
        "the starter plans: {}",
        stderr(&plan)
    );

    let again = servobus_in(&dir, &["init", "starter"]);
    let err = error(&again, 2);
    assert!(
        err.contains("robot.yaml exists") && err.contains("--force"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("starter/robot.yaml")).expect("robot"),
        robot,
        "left as it was"
    );
    let forced = servobus_in(&dir, &["init", "--force", "starter"]);
    assert!(forced.status.success(), "{}", stderr(&forced));
    let robot = std::fs::read_to_string(dir.join("starter/robot.yaml")).expect("robot");
    assert!(
        robot.starts_with("# SO-101"),
        "replaced by the so101 starter"
    );
}

/// `SHELL -c SCRIPT` where `tool` is installed (it runs with `--version`);
/// `None` where it is not.
fn script_if_installed(tool: &str, shell: &str, script: &str) -> Option<Output> {
    Command::new(tool).arg("--version").output().ok()?;
    Some(
        Command::new(shell)
            .args(["-c", script])
            .output()
            .expect(shell),
    )
}

#[test]
fn completions_load_in_bash_and_the_man_page_renders() {
    for shell in ["bash", "zsh", "fish"] {
        let out = servobus(&["completions", shell]);
        assert!(out.status.success(), "{shell}");
        assert!(stdout(&out).contains("servobus"), "{shell}");
    }
    let script = format!("set -e; source <('{BIN}' completions bash); complete -p servobus");
    if let Some(out) = script_if_installed("bash", "bash", &script) {
        assert!(out.status.success(), "bash: {}", stderr(&out));
        assert!(stderr(&out).is_empty(), "bash: {}", stderr(&out));
        assert!(
            stdout(&out).contains("servobus"),
            "registered: {}",
            stdout(&out)
        );
    }
    let page = servobus(&["man"]);
    assert!(page.status.success());
    let roff = stdout(&page);
    assert!(
        roff.starts_with(".ie") || roff.contains(".TH servobus"),
        "{roff}"
    );
    assert!(roff.contains("SERVOBUS PLAY") && roff.contains("SERVOBUS COMPLETIONS"));
    let script = format!("'{BIN}' man | MANWIDTH=80 man -l - 2>&1");
    if let Some(out) = script_if_installed("man", "sh", &script) {
        let text = stdout(&out);
        assert!(out.status.success(), "man: {text}");
        assert!(text.contains("Exit status"), "rendered: {text}");
    } else {
        eprintln!("man is not installed: rendering not checked");
    }
}

#[test]
fn every_command_uses_the_same_exit_codes() {
    for (args, code) in [
        (&["play", "arm-wave", "--fast", "--json"][..], 0),
        (&["budget", "--robot", "so101", "--rate", "5000"], 1),
        (&["decode", "01 02"], 1),
        (&["budget", "--robot", "so101", "--rate", "0"], 2),
        (&["bench", "--seconds", "0"], 2),
        (&["play", "arm-wave", "--rate", "-1"], 2),
        (&["plan", "nothere"], 2),
        (&["decode", "ZZ"], 2),
        (&["init", "--robot", "nothere"], 2),
        (&["completions", "tcsh"], 2),
    ] {
        let out = servobus(args);
        assert_eq!(out.status.code(), Some(code), "{args:?}: {}", stderr(&out));
    }
}

#[test]
fn every_subcommand_help_documents_the_exit_codes() {
    let help = stdout(&servobus(&["--help"]));
    let commands: Vec<&str> = help
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .collect();
    assert!(commands.len() >= 15, "{commands:?}");
    for c in commands {
        let sub = stdout(&servobus(&[c, "--help"]));
        // doctor's 1 means warnings only: it states its own codes instead.
        let codes = if c == "doctor" {
            "Exit status (doctor's own):\n  0  nothing wrong"
        } else {
            "Exit status:\n  0  ok\n  1  a problem"
        };
        assert!(sub.contains(codes), "{c}: {sub}");
    }
}

/// A default build has no `serve`: asking for it (with arguments, or for
/// its help) says which feature it needs and how to build it, exit 2.
#[cfg(not(feature = "zenoh"))]
#[test]
fn serve_in_a_default_build_says_how_to_build_it() {
    for args in [
        &["serve"][..],
        &["serve", "--robot", "so101", "--listen", "tcp/127.0.0.1:0"],
        &["serve", "--help"],
    ] {
        let out = servobus(args);
        let (_, err) = common::exited(&out, 2);
        says(
            &err,
            &[
                "`servobus serve`",
                "the `zenoh` feature",
                "cargo install --path . --features zenoh",
            ],
        );
        assert!(!err.contains("unrecognized"), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    }
    // The commands this build has are listed; `serve` is not among them.
    let help = stdout(&servobus(&["--help"]));
    assert!(
        !help.lines().any(|l| l.trim_start().starts_with("serve ")),
        "{help}"
    );
}

/// The word after `flag` in the comments of `text` (a command may wrap
/// onto the next comment line), without a closing `)`.
fn comment_word_after<'a>(text: &'a str, flag: &str) -> &'a str {
    let words: Vec<&str> = text
        .lines()
        .filter(|l| l.trim_start().starts_with('#'))
        .flat_map(str::split_whitespace)
        .filter(|w| *w != "#")
        .collect();
    let at = words
        .iter()
        .position(|w| *w == flag)
        .unwrap_or_else(|| panic!("no {flag} in the comments of {text}"));
    words.get(at + 1).map_or("", |w| w.trim_end_matches(')'))
}

#[test]
fn init_names_the_file_it_wrote_in_its_commands() {
    for (robot, dir) in [("so101", "arm"), ("hexapod", "."), ("hexapod-2bus", "a/hx")] {
        let root = scratch(&format!("init-commands-{robot}"));
        let out = servobus_in(&root, &["init", "--robot", robot, dir]);
        assert!(out.status.success(), "{}", stderr(&out));
        let written = root.join(dir).join("robot.yaml");
        let text = std::fs::read_to_string(&written).expect("robot.yaml");
        assert!(text.contains("servobus calibrate --robot"), "{text}");
        assert!(
            !text.contains("configs/robots") && !text.contains("THIS_FILE"),
            "{text}"
        );
        // The calibrate command, run where init ran, reads the file written
        // and writes the calibration beside it, where `calibration:` looks.
        let named = comment_word_after(&text, "--robot");
        assert_eq!(
            root.join(named).canonicalize().expect("the file named"),
            written.canonicalize().expect("the file written"),
            "{robot}: {named}"
        );
        let calibration = comment_word_after(&text, "-o");
        assert_eq!(
            root.join(calibration).parent().map(|p| p.to_path_buf()),
            written.parent().map(|p| p.to_path_buf()),
            "{robot}: -o {calibration}"
        );
        // Only comments changed: the YAML is the built-in robot's.
        let shipped =
            std::fs::read_to_string(common::repo(&format!("configs/robots/{robot}.yaml")))
                .expect("the shipped file");
        let yaml = |t: &str| -> Vec<String> {
            t.lines()
                .filter(|l| !l.trim_start().starts_with('#'))
                .map(str::to_owned)
                .collect()
        };
        assert_eq!(yaml(&text), yaml(&shipped), "{robot}");
    }
}
