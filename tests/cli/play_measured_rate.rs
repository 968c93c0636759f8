//! `play --port` checks its rate against the adapter it measured (the
//! start-up probe of `latency_us: auto`, the one `budget --port` runs), not
//! only against the robot file's figures, which know no adapter latency.

use crate::common;

use common::{error, num, servobus, Sim};

/// The number after `what` in `text`.
fn number_after(text: &str, what: &str) -> Option<f64> {
    let rest = &text[text.find(what)? + what.len()..];
    let end = rest
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(rest.len());
    rest[..end].parse().ok()
}

#[test]
fn play_port_refuses_a_rate_its_measured_adapter_cannot_hold() {
    let dir = common::scratch("play-measured-rate");
    // Every reply 1.5 ms late: an adapter that slow. The SO-101's cycle is
    // then about 880 us of wire, 300 of turnarounds, 1500 of latency and
    // the pty's hand-offs, under 370 Hz; the robot file alone (no latency)
    // allows 776 Hz on the simulator's link.
    let sim = Sim::start_with(&dir, &["--faults", "delay=1,delay_us=1500"]);
    let budget =
        common::servobus_json(&["budget", "--robot", "so101", "--port", sim.port(), "--json"]);
    let promised = num(&budget["buses"][0], "max_rate_hz");
    assert!(promised < 400.0, "{budget}");
    let out = servobus(&[
        "play",
        common::arg(&common::repo("configs/motions/arm-wave.yaml")),
        "--port",
        sim.port(),
        "--rate",
        "600",
        "--json",
    ]);
    let text = error(&out, 2);
    common::says(&text, &["bus `arm`", sim.port(), "measured", "600 Hz"]);
    // The maximum it names is the one budget --port printed (measured
    // again, so within what a loaded machine moves a median PING).
    let enforced = number_after(&text, "fastest rate that fits is ")
        .or_else(|| number_after(&text, "maximum rate of "))
        .expect("the maximum is named");
    assert!(
        (enforced - promised).abs() <= 0.1 * promised,
        "{enforced} vs {promised}: {text}"
    );
}
