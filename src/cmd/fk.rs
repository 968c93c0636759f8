//! `servobus fk` and `servobus ik`: where a pose puts every frame of a
//! robot, and which joint angles put a frame at a point.
//!
//! Both render what the kinematics crate computes from the robot file's
//! `kinematics:` section; angles are in the robot file's units.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::ExitCode;

use serde::Serialize;
use servobus_config::{ik_reason, load_robot, Robot, RobotOptions, Units};
use servobus_kinematics::{ArmIk, ArmTarget, Geometry, IkError, LegIk, Point3, Poses};

use crate::shared::exit::{input, PROBLEM};
use crate::shared::out::outln;

/// Arguments of `servobus fk`.
#[derive(Debug, clap::Args)]
pub struct FkArgs {
    /// The robot: a file, or a built-in name (`servobus list`).
    #[arg(long, value_parser = crate::shared::flags::robot_arg)]
    pub robot: PathBuf,
    /// Joint angles in the robot file's units, as YAML or JSON:
    /// `{shoulder_lift: 30, elbow_flex: -45}`. Joints not named are at 0.
    #[arg(long, default_value = "{}")]
    pub pose: String,
    /// Print one JSON object: `{"frames": {"<name>": {"xyz": [..], "rpy": [..]}}}`.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `servobus ik`.
#[derive(Debug, clap::Args)]
pub struct IkArgs {
    /// The robot: a file, or a built-in name (`servobus list`).
    #[arg(long, value_parser = crate::shared::flags::robot_arg)]
    pub robot: PathBuf,
    /// The named frame to place (`tool`, `foot_<leg>`).
    #[arg(long)]
    pub frame: String,
    /// Where, in mm in the base frame: X,Y,Z.
    #[arg(
        long,
        required = true,
        value_delimiter = ',',
        allow_hyphen_values = true,
        value_parser = crate::shared::args::mm_arg
    )]
    pub xyz: Vec<f64>,
    /// The frame's pitch, in the robot file's units.
    #[arg(long, allow_negative_numbers = true, value_parser = crate::shared::args::angle_arg)]
    pub pitch: Option<f64>,
    /// The frame's roll, in the robot file's units.
    #[arg(long, allow_negative_numbers = true, value_parser = crate::shared::args::angle_arg)]
    pub roll: Option<f64>,
    /// Print one JSON object: `{"frame", "joints": {"<name>": angle}}`, or
    /// `{"frame", "error", "short_mm"?, "joint"?}` when there is no answer.
    #[arg(long)]
    pub json: bool,
}

/// One frame in `fk --json`.
#[derive(Debug, Serialize)]
struct FramePose {
    xyz: [f64; 3],
    rpy: [f64; 3],
}

#[derive(Debug, Serialize)]
struct FkOut {
    frames: BTreeMap<String, FramePose>,
}

/// The robot file and its geometry with the joint limits set.
fn geometry(path: &std::path::Path) -> anyhow::Result<(Robot, Geometry)> {
    let robot = load_robot(path, &RobotOptions::default().any_rate())?;
    let model = robot.geometry().ok_or_else(|| {
        input(format!(
            "robot `{}` ({}) has no `kinematics:` section",
            robot.name,
            robot.path.display()
        ))
    })?;
    Ok((robot, model))
}

/// `--pose` as joint angles in radians, robot order.
fn pose(robot: &Robot, text: &str) -> anyhow::Result<Vec<f64>> {
    servobus_config::parse_pose(robot, text).map_err(|e| input(format!("--pose: {e}")))
}

fn frame_pose(units: Units, pose: &servobus_kinematics::Isometry3<f64>) -> FramePose {
    let t = pose.translation.vector;
    let (r, p, y) = pose.rotation.euler_angles();
    FramePose {
        xyz: [t.x, t.y, t.z],
        // `+ 0.0` prints -0 as 0.
        rpy: [r, p, y].map(|a| units.from_rad(a) + 0.0),
    }
}

/// `v` as printed with `decimals`, without a sign on a rounded zero.
fn shown(v: f64, decimals: i32) -> f64 {
    let scale = 10f64.powi(decimals);
    (v * scale).round() / scale + 0.0
}

/// Runs `servobus fk`.
pub fn fk(args: FkArgs) -> anyhow::Result<ExitCode> {
    let (robot, model) = geometry(&args.robot)?;
    let q = pose(&robot, &args.pose)?;
    let mut poses = Poses::new(&model);
    model.forward(&q, &mut poses);
    let mut rows: Vec<(String, FramePose)> = Vec::new();
    let joints =
        (0..model.joint_count()).filter_map(|i| Some((model.joint_name(i)?, poses.joint(i)?)));
    let frames =
        (0..model.frame_count()).filter_map(|i| Some((model.frame_name(i)?, poses.frame(i)?)));
    for (name, p) in joints.chain(frames) {
        rows.push((name.to_owned(), frame_pose(robot.units, p)));
    }
    if args.json {
        let out = FkOut {
            frames: rows.into_iter().collect(),
        };
        outln!("{}", crate::shared::json::line(&out)?)?;
    } else {
        let u = robot.units;
        outln!(
            "{:<22} {:>9} {:>9} {:>9}   {:>8} {:>8} {:>8}",
            "frame",
            "x mm",
            "y mm",
            "z mm",
            "roll",
            "pitch",
            "yaw"
        )?;
        for (name, f) in rows {
            outln!(
                "{name:<22} {:>9.2} {:>9.2} {:>9.2}   {:>8.2} {:>8.2} {:>8.2} {u}",
                shown(f.xyz[0], 2),
                shown(f.xyz[1], 2),
                shown(f.xyz[2], 2),
                shown(f.rpy[0], 2),
                shown(f.rpy[1], 2),
                shown(f.rpy[2], 2)
            )?;
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// `ik --json` output.
#[derive(Debug, Serialize)]
struct IkOut {
    frame: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    joints: Option<InOrder>,
    #[serde(skip_serializing_if = "Option::is_none")]
    error: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    short_mm: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    joint: Option<String>,
}

/// Joint angles by name, kept in the robot's joint order (a JSON object
/// whose keys come in that order).
#[derive(Debug)]
struct InOrder(Vec<(String, f64)>);

impl Serialize for InOrder {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_map(self.0.iter().map(|(name, angle)| (name, angle)))
    }
}

/// The chain's angles (radians) that put `frame` at the target, from the
/// robot's rest pose: a leg's closed form when the frame is a foot and no
/// orientation is asked for, the arm solver otherwise.
fn solve(
    robot: &Robot,
    model: &Geometry,
    frame: &str,
    target: &ArmTarget,
) -> anyhow::Result<Result<Vec<(usize, f64)>, IkError>> {
    let rest: Vec<f64> = robot
        .joints()
        .map(|j| robot.units.to_rad(j.rest()))
        .collect();
    let setup = |e: IkError| input(e.to_string());
    if target.pitch.is_none() && target.roll.is_none() {
        if let Ok(leg) = LegIk::new(model, frame) {
            let js = leg.joints();
            let previous = js.map(|j| rest[j]);
            return Ok(leg
                .solve(&target.xyz, previous)
                .map(|q| js.iter().copied().zip(q).collect()));
        }
    }
    let arm = ArmIk::new(model, frame).map_err(setup)?;
    let previous: Vec<f64> = arm.joints().iter().map(|&j| rest[j]).collect();
    let mut out = vec![0.0; previous.len()];
    Ok(arm
        .solve(target, &previous, &mut out)
        .map(|()| arm.joints().iter().copied().zip(out).collect()))
}

/// Runs `servobus ik`.
pub fn ik(args: IkArgs) -> anyhow::Result<ExitCode> {
    let (robot, model) = geometry(&args.robot)?;
    let [x, y, z] = args.xyz[..] else {
        return Err(input("--xyz takes three numbers: X,Y,Z (mm)"));
    };
    // --xyz, --pitch and --roll are finite: their parsers refuse the rest.
    let target = ArmTarget {
        xyz: Point3::new(x, y, z),
        pitch: args.pitch.map(|a| robot.units.to_rad(a)),
        roll: args.roll.map(|a| robot.units.to_rad(a)),
    };
    let answer = solve(&robot, &model, &args.frame, &target)?;
    let mut out = IkOut {
        frame: args.frame.clone(),
        joints: None,
        error: None,
        short_mm: None,
        joint: None,
    };
    let code = match &answer {
        Ok(q) => {
            // The model's joint indices are the robot file's joint order.
            let mut q = q.clone();
            q.sort_by_key(|&(j, _)| j);
            let angles = q.iter().filter_map(|&(j, a)| {
                Some((model.joint_name(j)?.to_owned(), robot.units.from_rad(a)))
            });
            out.joints = Some(InOrder(angles.collect()));
            ExitCode::SUCCESS
        }
        Err(e) => {
            out.error = Some(ik_reason(e, robot.units));
            match e {
                IkError::Unreachable { short } => out.short_mm = Some(*short),
                IkError::JointLimit { joint, .. } => out.joint = Some(joint.clone()),
                _ => {}
            }
            ExitCode::from(PROBLEM)
        }
    };
    if args.json {
        outln!("{}", crate::shared::json::line(&out)?)?;
    } else if let Some(joints) = &out.joints {
        // YAML, as `fk --pose` reads it: `fk --pose "$(servobus ik ...)"`.
        outln!(
            "# joint angles in {}, in the robot's order; `fk --pose` takes these lines as they are",
            robot.units
        )?;
        for (name, angle) in &joints.0 {
            let key = format!("{name}:");
            outln!("{key:<23} {:>9.3}", shown(*angle, 3))?;
        }
    } else if let Some(e) = &out.error {
        outln!("no joint angles put `{}` there: {e}", args.frame)?;
    }
    Ok(code)
}
