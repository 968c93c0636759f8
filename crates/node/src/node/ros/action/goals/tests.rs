//! Goal life: tolerances, ends, cancels, results; two joints of three.

use super::*;

fn names() -> Vec<String> {
    ["pan", "lift", "elbow"]
        .iter()
        .map(|s| s.to_string())
        .collect()
}

fn id(n: u8) -> Uuid {
    Uuid([n; 16])
}

/// A goal over `pan` and `elbow`, from 0 to 10 s on the stream clock,
/// ending at 0.5 rad for both.
fn track(path: Option<f64>) -> Track {
    let tol = |p| Tolerance {
        position: p,
        velocity: None,
    };
    Track {
        joints: vec![0, 2],
        names: vec!["pan".into(), "elbow".into()],
        path: vec![tol(path); 2],
        goal: vec![tol(Some(0.01)); 2],
        goal_time: 1.0,
        start: 0.0,
        end: 10.0,
        last: vec![0.5, 0.5],
        generation: 7,
    }
}

/// One cycle at `now`: the path at `planned` for every joint, the
/// joints measured at `measured`, still.
fn run(goals: &mut Goals, now: f64, planned: f64, measured: [f64; 3]) -> Vec<Change> {
    let m = measured.map(Some);
    let c = Cycle {
        now,
        lead: 0.02,
        generation: 7,
        planned: &[planned; 3],
        measured: &m,
        velocity: &[0.0; 3],
        commanded_velocity: &[0.0; 3],
    };
    goals.cycle(&c, &names())
}

fn result(goals: &Goals, n: u8) -> GetResultResponse {
    goals.result(id(n)).expect("ended")
}

#[test]
fn tolerances_follow_control_msgs_zero_default_negative_none() {
    let given = |name: &str, position, velocity| JointTolerance {
        name: name.into(),
        position,
        velocity,
        acceleration: 0.0,
    };
    let goal = tolerances(
        &[
            given("pan", 0.0, 0.2),
            given("elbow", -1.0, 0.0),
            given("lift", 0.3, 0.0),
        ],
        &["pan".into(), "elbow".into()],
        &names(),
        true,
    )
    .expect("tolerances");
    assert_eq!(goal[0].position, Some(DEFAULT_GOAL_POSITION));
    assert_eq!(goal[0].velocity, Some(0.2));
    assert_eq!(goal[1], Tolerance::default(), "-1: no limit");
    let path = tolerances(&[], &["pan".into()], &names(), false).expect("tolerances");
    assert_eq!(
        path,
        vec![Tolerance::default()],
        "no path tolerance by default"
    );
    let why = tolerances(&[given("thumb", 0.1, 0.0)], &[], &names(), false).unwrap_err();
    assert!(why.contains("`thumb`"), "{why}");
}

#[test]
fn a_goal_within_its_tolerances_succeeds_at_its_end_plus_the_lead() {
    let mut goals = Goals::default();
    goals.accept(id(1), RosTime::default(), track(Some(0.1)));
    assert_eq!(goals.running().map(|g| g.id), Some(id(1)));
    assert!(
        run(&mut goals, 5.0, 0.25, [0.3, 9.0, 0.2]).is_empty(),
        "within the path"
    );
    assert!(
        goals.result(id(1)).is_none(),
        "get_result waits while it runs"
    );
    // At the end, not yet past the lead: still running.
    assert!(run(&mut goals, 10.01, 0.5, [0.5, 9.0, 0.5]).is_empty());
    assert_eq!(
        run(&mut goals, 10.03, 0.5, [0.505, 9.0, 0.495]),
        vec![Change::Ended(id(1))]
    );
    let r = result(&goals, 1);
    assert_eq!(r.status, GoalStatus::STATUS_SUCCEEDED);
    assert_eq!(r.result.error_code, Fjt::SUCCESSFUL);
    assert!(goals.running().is_none());
}

#[test]
fn a_path_tolerance_broken_aborts_and_stops_naming_the_joint() {
    let mut goals = Goals::default();
    goals.accept(id(2), RosTime::default(), track(Some(0.05)));
    assert!(run(&mut goals, 2.0, 0.3, [0.33, 0.0, 0.27]).is_empty());
    // The lift is not in the goal: far from the path, it does not count.
    assert!(run(&mut goals, 2.1, 0.3, [0.3, 5.0, 0.3]).is_empty());
    assert_eq!(
        run(&mut goals, 2.2, 0.3, [0.3, 0.3, 0.2]),
        vec![Change::Stop(id(2))]
    );
    let r = result(&goals, 2);
    assert_eq!(r.status, GoalStatus::STATUS_ABORTED);
    assert_eq!(r.result.error_code, Fjt::PATH_TOLERANCE_VIOLATED);
    assert!(
        r.result.error_string.contains("`elbow` was 0.1000 rad"),
        "{r:?}"
    );
    assert!(r.result.error_string.contains("2.200 s"), "{r:?}");
}

#[test]
fn a_goal_not_reached_within_its_goal_time_aborts() {
    let mut goals = Goals::default();
    goals.accept(id(3), RosTime::default(), track(None));
    // Past the end, 0.1 rad short: waits out the goal time, then aborts.
    assert!(run(&mut goals, 10.5, 0.5, [0.4, 0.0, 0.5]).is_empty());
    assert!(run(&mut goals, 11.0, 0.5, [0.4, 0.0, 0.5]).is_empty());
    assert_eq!(
        run(&mut goals, 11.1, 0.5, [0.4, 0.0, 0.5]),
        vec![Change::Ended(id(3))]
    );
    let r = result(&goals, 3);
    assert_eq!(r.result.error_code, Fjt::GOAL_TOLERANCE_VIOLATED);
    assert!(
        r.result
            .error_string
            .contains("`pan` was 0.1000 rad from its goal"),
        "{r:?}"
    );
}

#[test]
fn another_input_takes_over_and_a_newer_goal_replaces() {
    let mut goals = Goals::default();
    goals.accept(id(4), RosTime::default(), track(None));
    let m = [Some(0.0); 3];
    let c = Cycle {
        now: 1.0,
        lead: 0.0,
        generation: 8,
        planned: &[0.0; 3],
        measured: &m,
        velocity: &[0.0; 3],
        commanded_velocity: &[0.0; 3],
    };
    assert_eq!(goals.cycle(&c, &names()), vec![Change::Ended(id(4))]);
    assert!(result(&goals, 4).result.error_string.contains("took over"));
    goals.accept(id(5), RosTime::default(), track(None));
    assert_eq!(goals.preempt(), Some(id(5)));
    let r = result(&goals, 5);
    assert_eq!(r.status, GoalStatus::STATUS_CANCELED);
    assert!(r.result.error_string.contains("newer goal"));
    assert_eq!(goals.preempt(), None);
}

#[test]
fn a_cancel_stops_the_goal_and_it_is_canceled_once_still() {
    let mut goals = Goals::default();
    goals.accept(id(6), RosTime::from_ns(5), track(None));
    let named = |n: u8| CancelGoalRequest {
        goal_info: GoalInfo {
            goal_id: id(n),
            stamp: RosTime::default(),
        },
    };
    let (r, stop) = goals.cancel(&named(9), 1.0);
    assert_eq!(r.return_code, CancelGoalResponse::ERROR_UNKNOWN_GOAL_ID);
    assert!(!stop);
    let (r, stop) = goals.cancel(&named(6), 1.0);
    assert!(stop);
    assert_eq!(r.return_code, CancelGoalResponse::ERROR_NONE);
    assert_eq!(r.goals_canceling.len(), 1);
    assert_eq!(
        goals.status().status_list[0].status,
        GoalStatus::STATUS_CANCELING
    );
    assert!(goals.result(id(6)).is_none(), "canceling: not ended yet");
    // Still moving: canceling; then still.
    let m = [Some(0.0); 3];
    let moving = Cycle {
        now: 1.1,
        lead: 0.0,
        generation: 7,
        planned: &[0.0; 3],
        measured: &m,
        velocity: &[0.0; 3],
        commanded_velocity: &[0.0, 0.3, 0.0],
    };
    assert!(goals.cycle(&moving, &names()).is_empty());
    assert_eq!(
        run(&mut goals, 1.2, 0.0, [0.0; 3]),
        vec![Change::Ended(id(6))]
    );
    assert_eq!(result(&goals, 6).status, GoalStatus::STATUS_CANCELED);
    let (r, _) = goals.cancel(&named(6), 2.0);
    assert_eq!(r.return_code, CancelGoalResponse::ERROR_GOAL_TERMINATED);
    // "Every goal" with none running: rejected.
    let (r, stop) = goals.cancel(&CancelGoalRequest::default(), 2.0);
    assert_eq!(
        (r.return_code, stop),
        (CancelGoalResponse::ERROR_REJECTED, false)
    );
}

#[test]
fn results_answer_refused_unknown_and_ended_goals_and_the_list_stays_bounded() {
    let mut goals = Goals::default();
    goals.refuse(
        id(7),
        RosTime::default(),
        Fjt::INVALID_GOAL,
        "past a limit".into(),
    );
    let r = result(&goals, 7);
    assert_eq!(r.status, GoalStatus::STATUS_UNKNOWN);
    assert_eq!(r.result.error_string, "past a limit");
    assert!(
        goals.status().status_list.is_empty(),
        "refused goals are not listed"
    );
    assert_eq!(
        result(&goals, 200).result.error_string,
        "no goal has this id"
    );
    for n in 10..40 {
        goals.accept(id(n), RosTime::default(), track(None));
        goals.preempt();
    }
    goals.accept(id(40), RosTime::default(), track(None));
    assert_eq!(goals.list.len(), KEPT);
    assert_eq!(goals.running().map(|g| g.id), Some(id(40)));
    assert_eq!(goals.finish("the run ended"), vec![id(40)]);
    assert_eq!(result(&goals, 40).status, GoalStatus::STATUS_ABORTED);
}
