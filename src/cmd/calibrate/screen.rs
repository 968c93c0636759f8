//! What `servobus calibrate` shows while it measures: each step's text,
//! then every joint as the procedure reads it.
//!
//! | step              | on a terminal (redrawn 10 times a second)      | without one (a log)                         |
//! |-------------------|------------------------------------------------|---------------------------------------------|
//! | hold the pose     | each joint's tick now and how far it moved     | the joints once, as the step ends           |
//! | sweep every joint | min, max and now per joint, following the sweep | a joint's range each time it grew 20 deg, then all once as the step ends |
//!
//! The pose's step measures no range: it shows none (a min and max that
//! stand still while the joints move would look like a sweep not seen).

use std::io::{BufRead, IsTerminal, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use servobus_config::Robot;
use servobus_robot::calibrate::{LiveJoint, Operator, Step};

use crate::shared::out::{out, outln};

/// Without a terminal, a swept joint's line is written again each time its
/// range has grown by this much since its last line, deg: a sweep end to
/// end is a dozen lines per joint, not one per reading.
const LOG_EVERY_DEG: f64 = 20.0;

/// A terminal's table is redrawn at most this often.
const REDRAW: Duration = Duration::from_millis(100);

/// The joints' table of the step under way.
pub(super) struct Table {
    names: Vec<String>,
    deg_per_tick: Vec<f64>,
    /// The step under way sweeps the joints (their range is measured).
    sweeping: bool,
    /// Each joint's tick at the step's first reading.
    origin: Vec<i64>,
    /// Without a terminal: each joint's range as last logged.
    logged: Vec<(i64, i64)>,
}

impl Table {
    /// The table of joints `names`, with ticks of `deg_per_tick` degrees.
    pub(super) fn new(names: Vec<String>, deg_per_tick: Vec<f64>) -> Self {
        Table {
            names,
            deg_per_tick,
            sweeping: false,
            origin: Vec::new(),
            logged: Vec::new(),
        }
    }

    /// `step` begins.
    pub(super) fn begin(&mut self, step: Step) {
        self.sweeping = step == Step::Sweep;
        self.origin.clear();
        self.logged.clear();
    }

    /// One line per joint, each ended by `end_of_line` and a newline: in
    /// the sweep, its lowest and highest tick so far, the tick now and the
    /// degrees swept; before it, the tick now and how far the joint moved
    /// since the step began.
    pub(super) fn render(&mut self, joints: &[LiveJoint], end_of_line: &str) -> String {
        if self.origin.is_empty() {
            self.origin = joints.iter().map(|j| j.now).collect();
        }
        let mut out = String::new();
        for (k, j) in joints.iter().enumerate() {
            let line = if self.sweeping {
                self.range_line(k, j)
            } else {
                let moved = (j.now - self.origin.get(k).copied().unwrap_or(j.now)) as f64;
                format!(
                    "{}  now {:>6}  (moved {:.0} deg)",
                    self.name(k),
                    j.now,
                    moved.abs() * self.dpt(k)
                )
            };
            out.push_str(&line);
            out.push_str(end_of_line);
            out.push('\n');
        }
        out
    }

    /// Without a terminal: the lines of the swept joints whose range grew
    /// by [`LOG_EVERY_DEG`] since their last line (none before the sweep).
    pub(super) fn log(&mut self, joints: &[LiveJoint]) -> String {
        if !self.sweeping {
            return String::new();
        }
        if self.logged.is_empty() {
            self.logged = joints.iter().map(|j| (j.min, j.max)).collect();
        }
        let mut out = String::new();
        for (k, j) in joints.iter().enumerate() {
            let Some(&(min, max)) = self.logged.get(k) else {
                continue;
            };
            let grown = (min - j.min) + (j.max - max);
            if grown as f64 * self.dpt(k) >= LOG_EVERY_DEG {
                self.logged[k] = (j.min, j.max);
                out.push_str(&self.range_line(k, j));
                out.push('\n');
            }
        }
        out
    }

    fn range_line(&self, k: usize, j: &LiveJoint) -> String {
        format!(
            "{}  min {:>6}  max {:>6}  now {:>6}  ({:.0} deg swept)",
            self.name(k),
            j.min,
            j.max,
            j.now,
            (j.max - j.min) as f64 * self.dpt(k)
        )
    }

    /// Joint `k`'s name, indented and padded to the longest name.
    fn name(&self, k: usize) -> String {
        let width = self.names.iter().map(String::len).max().unwrap_or(0);
        let name = self.names.get(k).map_or("?", String::as_str);
        format!("  {name:<width$}")
    }

    fn dpt(&self, k: usize) -> f64 {
        self.deg_per_tick.get(k).copied().unwrap_or(0.0)
    }
}

/// The person at the terminal (or, without one, the robot's stillness).
pub(super) struct Terminal {
    table: Table,
    pose: String,
    interactive: bool,
    live: bool,
    entered: Arc<AtomicBool>,
    shown: Option<Duration>,
    lines: usize,
    /// Without a terminal: the latest readings, summed up once when the
    /// step ends (a log, not a redrawn table).
    latest: Vec<LiveJoint>,
}

impl Terminal {
    pub(super) fn new(robot: &Robot, interactive: bool) -> Self {
        let entered = Arc::new(AtomicBool::new(false));
        if interactive {
            let flag = Arc::clone(&entered);
            std::thread::spawn(move || {
                for line in std::io::stdin().lock().lines() {
                    if line.is_err() {
                        break;
                    }
                    flag.store(true, Ordering::SeqCst);
                }
            });
        }
        let pose = robot
            .joints()
            .zip(&robot.calibration_pose)
            .map(|(j, p)| format!("{} {p}", j.name))
            .collect::<Vec<_>>()
            .join(", ");
        Terminal {
            table: Table::new(
                robot.joints().map(|j| j.name.clone()).collect(),
                robot.joints().map(|j| j.model.deg_per_tick()).collect(),
            ),
            pose: format!("{pose} ({})", robot.units),
            interactive,
            live: std::io::stdout().is_terminal(),
            entered,
            shown: None,
            lines: 0,
            latest: Vec::new(),
        }
    }

    fn ends(&self) -> &'static str {
        if self.interactive {
            "Press Enter when done."
        } else {
            "The step ends once the robot has moved and then been held still for 2 s."
        }
    }
}

impl Operator for Terminal {
    fn step(&mut self, step: Step) {
        self.shown = None;
        self.lines = 0;
        if !self.latest.is_empty() {
            // The step that ended, as it ended.
            let latest = std::mem::take(&mut self.latest);
            // The live display: a reader gone does not stop the
            // calibration (its result is saved and said on stderr).
            let _ = out!("{}", self.table.render(&latest, ""));
        }
        self.table.begin(step);
        let text = match step {
            Step::TorqueOff => {
                "1. Torque is off on every servo: the joints move freely. Support the robot."
                    .to_owned()
            }
            Step::HoldPose => format!(
                "2. Hold the robot in its calibration pose (see the robot file): {}. {}",
                self.pose,
                self.ends()
            ),
            Step::Sweep => format!(
                "3. Move every joint first towards positive angles, then through its whole range, \
                 end stop to end stop; then back to the pose. {}",
                self.ends()
            ),
            Step::Done => "4. Done: checking the sweep, then writing the calibration.".to_owned(),
        };
        let _ = outln!("{text}");
        let _ = std::io::stdout().flush();
    }

    fn watch(&mut self, at: Duration, joints: &[LiveJoint]) {
        if !self.live {
            self.latest = joints.to_vec();
            let log = self.table.log(joints);
            if !log.is_empty() {
                let _ = out!("{log}");
                let _ = std::io::stdout().flush();
            }
            return;
        }
        if self.shown.is_some_and(|s| at < s + REDRAW) {
            return;
        }
        self.shown = Some(at);
        let mut out = String::new();
        if self.lines > 0 {
            out.push_str(&format!("\x1b[{}A", self.lines));
        }
        out.push_str(&self.table.render(joints, "\x1b[K"));
        self.lines = joints.len();
        let _ = out!("{out}");
        let _ = std::io::stdout().flush();
    }

    fn confirmed(&mut self) -> bool {
        self.entered.swap(false, Ordering::SeqCst)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn joint(min: i64, max: i64, now: i64) -> LiveJoint {
        LiveJoint { min, max, now }
    }

    /// The table of an arm with two joints of 0.088 deg ticks (4096 a
    /// turn).
    fn table() -> Table {
        let dpt = 360.0 / 4096.0;
        Table::new(vec!["pan".into(), "shoulder_lift".into()], vec![dpt; 2])
    }

    #[test]
    fn the_sweep_shows_min_and_max_following_each_reading() {
        let mut t = table();
        t.begin(Step::Sweep);
        // The pan swept up, then down past where it began; the lift still.
        let screens = [
            [joint(2048, 2048, 2048), joint(1000, 1000, 1000)],
            [joint(2048, 2400, 2400), joint(1000, 1000, 1000)],
            [joint(2048, 3000, 2700), joint(1000, 1000, 1000)],
            [joint(1500, 3000, 1500), joint(1000, 1000, 1000)],
        ];
        let shown: Vec<String> = screens.iter().map(|s| t.render(s, "")).collect();
        assert_eq!(
            shown[0],
            "  pan            min   2048  max   2048  now   2048  (0 deg swept)\n  \
             shoulder_lift  min   1000  max   1000  now   1000  (0 deg swept)\n"
        );
        let pan: Vec<&str> = shown.iter().filter_map(|s| s.lines().next()).collect();
        assert_eq!(
            pan[1..],
            [
                "  pan            min   2048  max   2400  now   2400  (31 deg swept)",
                "  pan            min   2048  max   3000  now   2700  (84 deg swept)",
                "  pan            min   1500  max   3000  now   1500  (132 deg swept)",
            ]
        );
    }

    #[test]
    fn holding_the_pose_shows_no_range_only_where_each_joint_is() {
        let mut t = table();
        t.begin(Step::HoldPose);
        // The procedure's min and max stand still while the pose is held
        // (no range is measured yet): the screen does not show them.
        t.render(&[joint(2048, 2048, 2048), joint(1000, 1000, 1000)], "");
        let shown = t.render(&[joint(2048, 2048, 2400), joint(1000, 1000, 1000)], "");
        assert_eq!(
            shown,
            "  pan            now   2400  (moved 31 deg)\n  \
             shoulder_lift  now   1000  (moved 0 deg)\n"
        );
        assert!(!shown.contains("min") && !shown.contains("max"), "{shown}");
    }

    #[test]
    fn without_a_terminal_the_sweep_is_logged_as_each_range_grows() {
        let mut t = table();
        let lift = joint(1000, 1000, 1000);
        // Nothing is logged while the pose is held.
        t.begin(Step::HoldPose);
        assert_eq!(t.log(&[joint(2048, 2048, 2400), lift]), "");
        t.begin(Step::Sweep);
        assert_eq!(t.log(&[joint(2048, 2048, 2048), lift]), "");
        // 100 ticks (8.8 deg): not yet; 250 (22 deg): the pan's line.
        assert_eq!(t.log(&[joint(2048, 2148, 2148), lift]), "");
        assert_eq!(
            t.log(&[joint(2048, 2298, 2298), lift]),
            "  pan            min   2048  max   2298  now   2298  (22 deg swept)\n"
        );
        // Then counted from that line: the lift's 230 ticks down, and the
        // pan's 100 more are not enough.
        assert_eq!(
            t.log(&[joint(2048, 2398, 2398), joint(770, 1000, 770)]),
            "  shoulder_lift  min    770  max   1000  now    770  (20 deg swept)\n"
        );
    }
}
