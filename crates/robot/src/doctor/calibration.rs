//! The checks of the calibration: the homing offset each servo plays
//! with, the firmware it was taken on, and the fixes that calibrate and
//! edit the robot file (a built-in robot named by its name).

use servobus_config::{JointConfig, RobotCalibration};

use super::checks::ServoState;
use super::probe::{finding, Ctx};
use super::{Action, Advice, Change, Edit, Finding, Fix, RobotFile, SetupStep as Step, Severity};

impl Ctx<'_> {
    /// The servo against the joint's calibration: the homing offset the
    /// calibration plays with, and the firmware it was taken on.
    pub(crate) fn calibration(&self, s: &ServoState, joint: &JointConfig, out: &mut Vec<Finding>) {
        let Some(cal) = &joint.calibration else {
            return;
        };
        let want = cal.play_frame().homing_offset;
        if let Some(offset) = s.value("offset").filter(|&o| o != want) {
            out.push(self.offset_finding(s, joint, offset, cal.homing_offset, want));
        }
        let (major, minor) = s.firmware();
        let now = format!("{major}.{minor}");
        if let Some(then) = cal.firmware.as_deref().filter(|&v| v != now) {
            let register = Some("firmware_major");
            let mut f = self.finding(Severity::Warning, Step::Calibrate, s.id, register);
            f.problem = format!(
                "firmware is {now}, joint `{}` was calibrated on {then}: the servo may have been \
                 replaced",
                joint.name
            );
            f.advice = Advice::CalibrateIfReplaced(self.calibrate_command());
            out.push(f);
        }
    }

    /// Servo `s` holds homing offset `offset` where its joint's calibration
    /// plays with `want` and was taken with `taken`.
    ///
    /// The calibration's own offset is what a servo holds after a power-up
    /// when its range crosses the seam: play sets the play frame's for the
    /// session, so nothing is wrong. Any other offset was written since
    /// (another tool's calibration) or belongs to another servo: play
    /// refuses it.
    fn offset_finding(
        &self,
        s: &ServoState,
        joint: &JointConfig,
        offset: i32,
        taken: i32,
        want: i32,
    ) -> Finding {
        let session = offset == taken;
        let severity = if session {
            Severity::Info
        } else {
            Severity::Error
        };
        let register = s.register("offset");
        let mut f = self.finding(severity, Step::Calibrate, s.id, register.map(|r| r.name));
        f.measured = Some(offset);
        f.action = Some(Action::Offset {
            id: s.id,
            value: want,
            store_only: !session,
            series: s.series,
        });
        if session {
            f.problem = format!(
                "homing offset {offset} is not set for this session: joint `{}`'s range crosses \
                 the seam and plays with {want}, which play sets (until power-off)",
                joint.name
            );
            f.advice = Advice::SetOffsetNow(self.target.fix_all_command(&self.robot_arg(), false));
        } else {
            f.problem = format!(
                "homing offset is {offset}, joint `{}`'s calibration was taken with {taken}{}: \
                 the offset was rewritten since (by another tool?) or the servo was replaced, \
                 so play refuses it",
                joint.name,
                if want == taken {
                    String::new()
                } else {
                    format!(" and plays with {want}")
                }
            );
            f.advice = Advice::StoreOrCalibrate {
                store: self.target.write_command(s.id, "offset", want),
                calibrate: self.calibrate_command(),
            };
        }
        f
    }

    /// The robot as a program names it: a built-in's name, else its file.
    pub(crate) fn robot_arg(&self) -> String {
        servobus_config::builtin::argument(&self.robot.path)
    }

    /// Calibrating this robot on this port, with where the calibration
    /// goes.
    pub(crate) fn calibrate_command(&self) -> Fix {
        // The file the robot file names, else the one a commented-out
        // `# calibration:` line of it suggests, else a plain name.
        let output = match &self.robot.calibration {
            RobotCalibration::Missing(path) => path.display().to_string(),
            _ => servobus_config::builtin::file_text(&self.robot.path)
                .as_deref()
                .and_then(servobus_config::builtin::commented_calibration)
                .unwrap_or("calibration.yaml")
                .to_owned(),
        };
        Fix::Calibrate {
            robot: self.robot_arg(),
            port: self.target.port.clone(),
            output,
        }
    }

    /// `change` to this robot's file (a built-in robot's is copied first).
    pub(crate) fn edit_robot_file(&self, change: Change) -> Edit {
        Edit {
            robot: self.robot_file(),
            change,
        }
    }

    /// This robot's file: a built-in's name, else its path.
    pub(crate) fn robot_file(&self) -> RobotFile {
        match servobus_config::builtin::builtin_name(&self.robot.path) {
            Some(name) => RobotFile::Builtin(name.to_owned()),
            None => RobotFile::File(self.robot.path.clone()),
        }
    }
}

/// Present position `pos` of servo `s` as it reads in its joint's play
/// frame: a servo whose homing offset is not the play frame's yet (play
/// sets it) reads the same shaft angle `offset - want` ticks higher.
pub(crate) fn play_frame_tick(s: &ServoState, joint: &JointConfig, pos: i32) -> i32 {
    let want = joint
        .calibration
        .as_ref()
        .map(|c| c.play_frame().homing_offset);
    match (
        s.value("offset"),
        want,
        i32::try_from(joint.model.resolution),
    ) {
        (Some(offset), Some(want), Ok(turn)) if offset != want && turn > 0 => {
            (pos + offset - want).rem_euclid(turn)
        }
        _ => pos,
    }
}

/// Whether the robot has the calibration it names (said once, with its
/// first bus). Real servos without one are told to calibrate first.
pub(crate) fn robot_findings(ctx: &Ctx<'_>, out: &mut Vec<Finding>) {
    let first = || Advice::CalibrateFirst {
        calibrate: ctx.calibrate_command(),
        robot: ctx.robot_file(),
    };
    match &ctx.robot.calibration {
        RobotCalibration::Missing(path) => {
            let mut f = finding(ctx, Severity::Error, Step::Calibrate, None, None);
            f.problem = format!(
                "the robot file names the calibration {}, which does not exist: real servos \
                 are refused until it does",
                path.display()
            );
            f.advice = Advice::Run(ctx.calibrate_command());
            out.push(f);
        }
        RobotCalibration::None if ctx.real => {
            let mut f = finding(ctx, Severity::Info, Step::Calibrate, None, None);
            f.problem = "not calibrated: calibrate first. Until then the joint angles mean \
                         nothing (each servo horn sits at its own angle), so no joint is checked \
                         against its limits"
                .into();
            f.advice = first();
            out.push(f);
        }
        RobotCalibration::None | RobotCalibration::Unapplied(_) => {
            let mut f = finding(ctx, Severity::Info, Step::Calibrate, None, None);
            f.problem = "no calibration: joint angles count from each servo's middle tick \
                         with the robot file's offset and inverted"
                .into();
            f.advice = first();
            out.push(f);
        }
        RobotCalibration::Applied { .. } => {}
    }
}
