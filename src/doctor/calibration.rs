//! The checks of the calibration: the homing offset each servo plays
//! with, the firmware it was taken on, and the commands that calibrate and
//! edit the robot file (a built-in robot named by its name).

use servobus_runtime::config::{JointConfig, RobotCalibration};

use super::checks::ServoState;
use super::probe::{finding, Ctx};
use super::{Action, Finding, FixCommand, Severity, Step};

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
            let mut f = self.finding(
                Severity::Warning,
                Step::Calibrate,
                s.id,
                Some("firmware_major"),
            );
            f.problem = format!(
                "firmware is {now}, joint `{}` was calibrated on {then}: the servo may have been \
                 replaced",
                joint.name
            );
            f.run_in("if it was, calibrate again: {}", self.calibrate_command());
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
            f.run_in(
                "nothing to do before play; to set it now: {}",
                self.target.fix_all_command(&self.robot_arg(), false),
            );
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
            f.run_in(
                &format!(
                    "if only the offset was rewritten, store the calibration's in EEPROM: {{}}; \
                     if the servo or its horn was replaced, calibrate again: {}",
                    self.calibrate_command()
                ),
                self.target.write_command(s.id, "offset", want),
            );
        }
        f
    }

    /// The robot as the command line names it: a built-in's name, else
    /// its file.
    pub(crate) fn robot_arg(&self) -> String {
        crate::builtin::argument(&self.robot.path)
    }

    /// `servobus calibrate` for this robot and port, with where the
    /// calibration goes.
    pub(crate) fn calibrate_command(&self) -> FixCommand {
        let output = match &self.robot.calibration {
            RobotCalibration::Missing(path) => path.display().to_string(),
            _ => "calibration.yaml".into(),
        };
        FixCommand::Calibrate {
            robot: self.robot_arg(),
            port: self.target.port.clone(),
            output,
        }
    }

    /// What to do to change the robot file: edit it, or for a built-in
    /// robot, write a copy to edit with `servobus init` first.
    pub(crate) fn edit_robot_file(&self, change: &str) -> String {
        match crate::builtin::builtin_name(&self.robot.path) {
            Some(name) => format!(
                "the built-in robot cannot be edited: `servobus init --robot {name}` writes \
                 robot.yaml; {change} there and pass --robot robot.yaml"
            ),
            None => format!("{change} in {}", self.robot.path.display()),
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
    let then = match crate::builtin::builtin_name(&ctx.robot.path) {
        Some(_) => "then pass --calibration calibration.yaml to play, teach and bench".to_owned(),
        None => format!(
            "then add `calibration: calibration.yaml` to {} (or pass --calibration)",
            ctx.robot.path.display()
        ),
    };
    match &ctx.robot.calibration {
        RobotCalibration::Missing(path) => {
            let mut f = finding(ctx, Severity::Error, Step::Calibrate, None, None);
            f.problem = format!(
                "the robot file names the calibration {}, which does not exist: real servos \
                 are refused until it does",
                path.display()
            );
            f.run(ctx.calibrate_command());
            out.push(f);
        }
        RobotCalibration::None if ctx.real => {
            let mut f = finding(ctx, Severity::Info, Step::Calibrate, None, None);
            f.problem = "not calibrated: calibrate first. Until then the joint angles mean \
                         nothing (each servo horn sits at its own angle), so no joint is checked \
                         against its limits"
                .into();
            f.run_in(&format!("{{}}, {then}"), ctx.calibrate_command());
            out.push(f);
        }
        RobotCalibration::None | RobotCalibration::Unapplied(_) => {
            let mut f = finding(ctx, Severity::Info, Step::Calibrate, None, None);
            f.problem = "no calibration: joint angles count from each servo's middle tick \
                         with the robot file's offset and inverted"
                .into();
            f.run_in(&format!("{{}}, {then}"), ctx.calibrate_command());
            out.push(f);
        }
        RobotCalibration::Applied { .. } => {}
    }
}
