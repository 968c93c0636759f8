//! Outputs written whole or not at all: a refused or failed command leaves
//! an existing file byte-identical, creates no new one (not even empty) and
//! leaves no temporary; a successful one replaces the file; a log that
//! fails during a run still lets the report print, and says so (exit 1).

use crate::common;

use std::path::Path;

use common::{
    arg, exited, repo, says, scratch, servobus, servobus_in, servobus_ok, servobus_unprivileged,
    stdout, write_file, Sim,
};

const WAVE: &str = "configs/motions/arm-wave.yaml";
const SO101: &str = "configs/robots/so101.yaml";
const LEROBOT: &str = "crates/robot/tests/data/so101-lerobot.json";

/// The names in `dir`, sorted (temporaries, which start with `.`, included).
fn names(dir: &Path) -> Vec<String> {
    let entries = std::fs::read_dir(dir).expect("the directory lists");
    let mut names = Vec::new();
    for entry in entries {
        names.push(
            entry
                .expect("an entry")
                .file_name()
                .to_string_lossy()
                .into_owned(),
        );
    }
    names.sort();
    names
}

/// `servobus play` of arm-wave in `dir` with `args`, logging and plotting
/// to `(log, plot)`.
fn play_logged(dir: &Path, args: &[&str], (log, plot): (&str, &str)) -> std::process::Output {
    let wave = repo(WAVE);
    let head = ["play", arg(&wave)];
    servobus_in(
        dir,
        &[&head[..], args, &["--log", log, "--plot", plot]].concat(),
    )
}

/// A fresh, empty scratch directory.
fn empty(name: &str) -> std::path::PathBuf {
    let dir = scratch(name);
    for entry in std::fs::read_dir(&dir).expect("lists") {
        let path = entry.expect("an entry").path();
        if path.is_dir() {
            std::fs::remove_dir_all(&path).expect("removed");
        } else {
            std::fs::remove_file(&path).expect("removed");
        }
    }
    dir
}

/// Yesterday's log and plot in `dir`, with contents no run writes.
fn yesterday(dir: &Path) -> (Vec<u8>, Vec<u8>) {
    let log: Vec<u8> = (0..20_000u32).map(|i| (i * 7 % 251) as u8).collect();
    let plot = b"<svg><!-- yesterday --></svg>".to_vec();
    std::fs::write(dir.join("prev.csv"), &log).expect("old log");
    std::fs::write(dir.join("prev.svg"), &plot).expect("old plot");
    (log, plot)
}

/// `dir` holds exactly yesterday's log and plot, byte for byte.
fn untouched(dir: &Path, (log, plot): &(Vec<u8>, Vec<u8>)) {
    assert_eq!(names(dir), ["prev.csv", "prev.svg"]);
    assert!(std::fs::read(dir.join("prev.csv")).expect("log") == *log);
    assert!(std::fs::read(dir.join("prev.svg")).expect("plot") == *plot);
}

#[test]
fn a_play_refused_for_its_port_leaves_the_log_and_plot_as_they_were() {
    let dir = empty("outputs-port");
    let old = yesterday(&dir);
    let out = play_logged(
        &dir,
        &["--port", "/nonexistent/ttyACM0"],
        ("prev.csv", "prev.svg"),
    );
    let (_, err) = exited(&out, 2);
    says(&err, &["/nonexistent/ttyACM0"]);
    untouched(&dir, &old);

    // A new log and plot are not created either, not even empty.
    let out = play_logged(
        &dir,
        &["--port", "/nonexistent/ttyACM0"],
        ("new.csv", "new.png"),
    );
    exited(&out, 2);
    untouched(&dir, &old);
}

#[test]
fn a_play_refused_for_its_calibration_leaves_the_log_and_plot_as_they_were() {
    let dir = empty("outputs-calibration");
    let cal = scratch("outputs-calibration-cal").join("other.calibration.yaml");
    // LeRobot's calibration of another arm: homing offsets the simulated
    // servos (offset 0) do not hold.
    servobus_ok(&[
        "calibrate",
        "--robot",
        SO101,
        "--from-lerobot",
        arg(&repo(LEROBOT)),
        "-o",
        arg(&cal),
    ]);
    let sim_dir = empty("outputs-calibration-sim");
    let sim = Sim::start(&sim_dir);
    let old = yesterday(&dir);
    let on_sim = ["--port", sim.port(), "--calibration", arg(&cal)];
    let out = play_logged(&dir, &on_sim, ("prev.csv", "prev.svg"));
    let (_, err) = exited(&out, 1);
    says(&err, &["nothing was moved"]);
    untouched(&dir, &old);
    sim.stop();
}

#[test]
fn a_completed_play_replaces_the_log_and_plot() {
    let dir = empty("outputs-done");
    yesterday(&dir);
    let out = play_logged(&dir, &["--fast"], ("prev.csv", "prev.svg"));
    let (text, _) = exited(&out, 0);
    says(&text, &["log: prev.csv", "plot: prev.svg"]);
    assert_eq!(names(&dir), ["prev.csv", "prev.svg"]);
    let log = std::fs::read_to_string(dir.join("prev.csv")).expect("a text log");
    assert!(log.starts_with("time_s,bus,cycle,joint,"), "{}", &log[..60]);
    // arm-wave: six joints, one row each per cycle, over about 5.7 s at 200 Hz.
    assert!(
        log.lines().count() > 6 * 1000,
        "{} rows",
        log.lines().count()
    );
    let plot = std::fs::read_to_string(dir.join("prev.svg")).expect("a text plot");
    assert!(plot.starts_with("<svg"), "{}", &plot[..40]);
    assert!(plot.trim_end().ends_with("</svg>"));

    // A PNG plot is a PNG file.
    let out = servobus_in(
        &dir,
        &["play", arg(&repo(WAVE)), "--fast", "--plot", "run.png"],
    );
    exited(&out, 0);
    let png = std::fs::read(dir.join("run.png")).expect("a PNG");
    assert_eq!(
        png[..8],
        [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n']
    );
    assert_eq!(names(&dir), ["prev.csv", "prev.svg", "run.png"]);
}

#[cfg(target_os = "linux")]
#[test]
fn a_log_on_a_full_disk_still_lets_the_report_print_and_exits_1() {
    let out = servobus(&["play", WAVE, "--fast", "--log", "/dev/full"]);
    let (text, err) = exited(&out, 1);
    // The whole report, then the error naming the file.
    says(&text, &["completed:", "tracking error"]);
    assert!(!text.contains("log: "), "{text}");
    says(
        &err,
        &["error: the log /dev/full is incomplete: cannot write /dev/full: "],
    );

    // The same with --json: the report is still one JSON object.
    let out = servobus(&["play", WAVE, "--fast", "--json", "--log", "/dev/full"]);
    let (text, err) = exited(&out, 1);
    let report: serde_json::Value = serde_json::from_str(&text).expect("one JSON object");
    assert_eq!(report["finish"], "completed", "{report}");
    says(&err, &["cannot write /dev/full"]);
}

#[cfg(unix)]
#[test]
fn a_log_that_fails_during_the_run_is_dropped_and_the_old_one_kept() {
    // A file size limit of 100 blocks of 512 bytes (SIGXFSZ ignored, so
    // that a write past it fails with EFBIG): the log, ~600 KB, fails
    // during the run, as on a disk that fills up.
    let dir = empty("outputs-fsize");
    let old = yesterday(&dir);
    let out = std::process::Command::new("sh")
        .args(["-c", "ulimit -f 100 && trap '' XFSZ && exec \"$0\" \"$@\""])
        .arg(common::BIN)
        .args(["play", arg(&repo(WAVE)), "--fast", "--log", "prev.csv"])
        .current_dir(&dir)
        .output()
        .expect("sh runs");
    let (text, err) = exited(&out, 1);
    says(&text, &["completed:", "tracking error"]);
    says(
        &err,
        &[
            "the log prev.csv cannot be written; the run goes on without it",
            "error: the log prev.csv was not kept: cannot write prev.csv: ",
        ],
    );
    untouched(&dir, &old);
}

#[test]
fn a_directory_given_as_an_output_is_an_input_error() {
    let dir = empty("outputs-dir");
    let old = yesterday(&dir);
    // A directory named as the log, then one named as the plot (with a
    // plot's extension, which a directory may have).
    for (log, plot, said) in [
        ("sub", "prev.svg", "--log: sub is a directory, not a file"),
        (
            "prev.csv",
            "sub.svg",
            "--plot: sub.svg is a directory, not a file",
        ),
    ] {
        let sub = dir.join(if log == "sub" { log } else { plot });
        std::fs::create_dir(&sub).expect("a directory");
        let wave = repo(WAVE);
        let args = ["play", arg(&wave), "--fast", "--log", log, "--plot", plot];
        let out = servobus_in(&dir, &args);
        let (_, err) = exited(&out, 2);
        says(&err, &[said, "nothing was moved"]);
        std::fs::remove_dir(&sub).expect("removed");
        untouched(&dir, &old);
    }
}

#[test]
fn a_directory_no_file_can_be_created_in_refuses_before_the_run() {
    // A directory the run may not write to, holding a log it may write to:
    // the log can be opened, but not replaced by a new file beside it. The
    // tests' user owns the directory; the run is not root (as root it runs
    // as `nobody`, see `servobus_unprivileged`), so mode 0555 holds it.
    let dir = empty("outputs-nobody");
    let old = yesterday(&dir);
    use std::os::unix::fs::PermissionsExt;
    let open = std::fs::Permissions::from_mode(0o666);
    std::fs::set_permissions(dir.join("prev.csv"), open).expect("mode");
    let shut = std::fs::Permissions::from_mode(0o555);
    std::fs::set_permissions(&dir, shut).expect("mode");
    let log = dir.join("prev.csv");
    let args = ["play", "arm-wave", "--fast", "--log", arg(&log)];
    let out = servobus_unprivileged(&repo(""), &args);
    let writable = std::fs::Permissions::from_mode(0o755);
    std::fs::set_permissions(&dir, writable).expect("mode");
    let (_, err) = exited(&out, 2);
    says(
        &err,
        &["--log: cannot write ", "prev.csv", "nothing was moved"],
    );
    untouched(&dir, &old);
}

#[test]
fn a_failed_teach_leaves_no_motion_file() {
    let dir = empty("outputs-teach");
    let robot = repo(SO101);
    let teach = || {
        servobus_in(
            &dir,
            &[
                "teach",
                "--robot",
                arg(&robot),
                "--port",
                "/nonexistent/ttyACM0",
                "--yes",
                "-o",
                "t.yaml",
            ],
        )
    };
    exited(&teach(), 2);
    assert!(names(&dir).is_empty(), "{:?}", names(&dir));

    std::fs::write(dir.join("t.yaml"), "yesterday's take\n").expect("old take");
    exited(&teach(), 2);
    assert_eq!(names(&dir), ["t.yaml"]);
    assert_eq!(
        std::fs::read_to_string(dir.join("t.yaml")).expect("read"),
        "yesterday's take\n"
    );
}

#[test]
fn a_failed_calibrate_leaves_the_calibration_as_it_was() {
    let dir = empty("outputs-calibrate");
    let cal = write_file(&dir, "arm.calibration.yaml", "# yesterday's calibration\n");
    let bad = write_file(&dir, "bad.json", "{\"shoulder_pan\": 7}");
    let import = |json: &Path, out: &str, export: Option<&str>| {
        let mut args = vec![
            "calibrate",
            "--robot",
            SO101,
            "--from-lerobot",
            arg(json),
            "-o",
            out,
        ];
        if let Some(export) = export {
            args.extend(["--to-lerobot", export]);
        }
        servobus(&args)
    };
    let out = import(&bad, arg(&cal), None);
    assert!(!out.status.success());
    // An export to a directory is refused before the calibration is
    // written.
    let out = import(&repo(LEROBOT), arg(&cal), Some(arg(&dir)));
    let (_, err) = exited(&out, 2);
    says(&err, &["is a directory, not a file"]);
    assert_eq!(
        std::fs::read_to_string(&cal).expect("read"),
        "# yesterday's calibration\n"
    );
    assert_eq!(names(&dir), ["arm.calibration.yaml", "bad.json"]);

    // A calibration or an export that cannot be written says which file,
    // exit 1.
    #[cfg(target_os = "linux")]
    {
        let out = import(&repo(LEROBOT), "/dev/full", None);
        let (_, err) = exited(&out, 1);
        says(&err, &["cannot write /dev/full: "]);
        let out = import(&repo(LEROBOT), arg(&cal), Some("/dev/full"));
        let (_, err) = exited(&out, 1);
        says(&err, &["cannot write /dev/full: "]);
        // The calibration itself was complete, and is written.
        let text = std::fs::read_to_string(&cal).expect("read");
        assert!(text.contains("homing_offset: -1389"), "{text}");
        assert_eq!(names(&dir), ["arm.calibration.yaml", "bad.json"]);
    }
}

#[test]
fn a_failed_init_writes_neither_file() {
    let dir = empty("outputs-init");
    // `motion.yaml` cannot be replaced: it is a directory.
    std::fs::create_dir(dir.join("motion.yaml")).expect("a directory");
    let out = servobus(&["init", "--force", arg(&dir)]);
    let (_, err) = exited(&out, 2);
    says(&err, &["motion.yaml is a directory, not a file"]);
    assert_eq!(names(&dir), ["motion.yaml"]);

    // Once it can, both files are written and `init` without --force
    // refuses to overwrite them.
    std::fs::remove_dir(dir.join("motion.yaml")).expect("removed");
    let out = servobus(&["init", arg(&dir)]);
    let (text, _) = exited(&out, 0);
    says(&text, &["robot.yaml", "motion.yaml"]);
    assert_eq!(names(&dir), ["motion.yaml", "robot.yaml"]);
    exited(&servobus(&["init", arg(&dir)]), 2);
}

#[test]
fn a_refused_sim_leaves_the_truth_file_as_it_was() {
    let dir = empty("outputs-truth");
    let truth = write_file(&dir, "truth.csv", "time_s,a\n0.000,1.000\n");
    let out = servobus(&[
        "sim",
        "--robot",
        SO101,
        "--bus",
        "no-such-bus",
        "--truth",
        arg(&truth),
    ]);
    let (_, err) = exited(&out, 2);
    says(&err, &["no bus named `no-such-bus`"]);
    assert_eq!(names(&dir), ["truth.csv"]);
    assert_eq!(
        std::fs::read_to_string(&truth).expect("read"),
        "time_s,a\n0.000,1.000\n"
    );
}

#[cfg(target_os = "linux")]
#[test]
fn a_plan_plot_that_cannot_be_written_names_the_file() {
    let out = servobus(&["plan", WAVE, "--plot", "/dev/full"]);
    let (_, err) = exited(&out, 1);
    says(&err, &["cannot write /dev/full: "]);
    let report = stdout(&out);
    assert!(!report.contains("plot written"), "{report}");
}

#[test]
fn a_plot_is_what_its_name_says_or_refused() {
    let dir = scratch("plot-formats");
    let file = |name: &str| dir.join(name);
    for (args, what) in [
        (vec!["plan", WAVE, "--plot"], "x.png"),
        (vec!["plan", WAVE, "--plot"], "x.jpg"),
        (common::follow_hand("1", &["--plot"]), "x.jpg"),
    ] {
        let path = file(what);
        let mut args = args.clone();
        args.push(arg(&path));
        let out = servobus(&args);
        let (_, err) = exited(&out, 2);
        says(&err, &["--plot", what, "plots are written as SVG (.svg)"]);
        assert!(!path.exists(), "{args:?} wrote {}", path.display());
    }
}

/// A run that ends on a fault (a servo of the pty simulator stops
/// answering 2 s in) still writes its log and plot whole, prints its
/// report, and exits 1 (issue 36: nothing recorded is lost). Whichever
/// fault a loaded machine makes of it (the servo missing, or the whole
/// bus silent), the run ends on it, long before arm-wave's end.
#[test]
fn a_play_ended_by_a_fault_writes_its_log_and_plot_whole() {
    let dir = empty("outputs-fault");
    let sim = Sim::start_with(&dir, &["--faults", "vanish=4@2.0"]);
    let out = play_logged(
        &dir,
        &["--robot", arg(&repo(SO101)), "--port", sim.port(), "--json"],
        ("run.csv", "run.svg"),
    );
    sim.stop();
    let (text, err) = exited(&out, 1);
    let report: serde_json::Value = serde_json::from_str(&text).expect("the report, as JSON");
    assert!(report["fault"]["kind"].is_string(), "{report} {err}");
    let fault_s = common::num(&report["fault"], "time_s");
    // The log: its header and whole rows up to the fault, no temporary.
    let log = std::fs::read_to_string(dir.join("run.csv")).expect("the log is written");
    assert!(log.ends_with('\n'), "the log's last row is cut");
    let mut lines = log.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    assert_eq!(header.first(), Some(&"time_s"), "{header:?}");
    let mut last_s = 0.0;
    let mut rows = 0;
    for line in lines {
        assert_eq!(line.split(',').count(), header.len(), "a cut row: {line}");
        last_s = line
            .split(',')
            .next()
            .and_then(|t| t.parse::<f64>().ok())
            .expect("a time");
        rows += 1;
    }
    assert!(rows > 100, "{rows} rows");
    assert!(
        last_s >= fault_s - 0.1,
        "rows up to {last_s} s, the fault at {fault_s} s"
    );
    // The plot: a whole SVG.
    let plot = std::fs::read_to_string(dir.join("run.svg")).expect("the plot is written");
    assert!(plot.trim_end().ends_with("</svg>"), "the plot is cut");
    let left: Vec<String> = names(&dir)
        .into_iter()
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(left.is_empty(), "temporaries left: {left:?}");
}
