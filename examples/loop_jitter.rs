//! The bare control loop on the real clock: how evenly does it tick?
//!
//! Runs an empty cycle at a fixed rate for a fixed time with the runtime's
//! [`Pacer`] (absolute deadlines, sleep then spin) and prints the period
//! error (how far each interval between cycle starts is from the period),
//! the wake-up lateness, overruns and the total drift (median lateness of
//! the last tenth of the run against the first).
//!
//! ```text
//! cargo run --release --example loop_jitter -- --rate 1000 --seconds 60
//! cargo run --release --example loop_jitter -- --rate 1000 --seconds 60 --core 1 --fifo 80
//! ```

use std::time::Duration;

use clap::Parser;
use servobus_driver::{Clock, SystemClock};
use servobus_runtime::pacer::Pacer;
use servobus_runtime::rt::{self, RtOptions};
use servobus_runtime::stats::Histogram;

/// Measure the period error of the bare control loop.
#[derive(Parser, Debug)]
struct Args {
    /// Loop rate, Hz.
    #[arg(long, default_value_t = 1000.0)]
    rate: f64,
    /// How long to run, s.
    #[arg(long, default_value_t = 10.0)]
    seconds: f64,
    /// Spin for this long before each deadline instead of sleeping, us.
    #[arg(long, default_value_t = 200)]
    spin_us: u64,
    /// Pin the loop thread to this core.
    #[arg(long)]
    core: Option<usize>,
    /// Run the loop thread under SCHED_FIFO at this priority.
    #[arg(long)]
    fifo: Option<i32>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

fn us(d: Duration) -> f64 {
    d.as_secs_f64() * 1e6
}

/// CPU time the hypervisor gave to other guests ("steal", summed over all
/// cores), in milliseconds, where the kernel reports it. On a shared virtual
/// machine this is time in which no scheduling policy inside the guest can
/// run the loop.
fn steal_ms() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/stat").ok()?;
    let cpu = stat.lines().find(|l| l.starts_with("cpu "))?;
    let ticks: f64 = cpu.split_whitespace().nth(8)?.parse().ok()?;
    // USER_HZ is 100 on every Linux architecture's user-space ABI.
    Some(ticks * 10.0)
}

fn main() {
    let args = Args::parse();
    if !(args.rate.is_finite() && args.rate > 0.0 && args.seconds > 0.0) {
        eprintln!("error: --rate and --seconds must be positive");
        std::process::exit(2);
    }
    let rt_report = rt::apply(RtOptions {
        core: args.core,
        fifo_priority: args.fifo,
    });
    for w in &rt_report.warnings {
        eprintln!("warning: {w}");
    }
    let period = Duration::from_nanos((1e9 / args.rate).round() as u64);
    let cycles = (args.seconds * args.rate).round() as u64;
    let clock = SystemClock::new();
    let start = clock.now() + Duration::from_millis(10);
    let mut pacer = Pacer::new(clock, start, period).with_spin(Duration::from_micros(args.spin_us));
    let mut period_error = Histogram::new(Duration::from_millis(100));
    let mut lateness = Histogram::new(Duration::from_millis(100));
    // Lateness over the first and the last tenth of the run: their medians
    // show whether cycle starts move away from the deadlines over time.
    let tenth = (cycles / 10).max(1);
    let mut early = Histogram::new(Duration::from_millis(100));
    let mut late = Histogram::new(Duration::from_millis(100));
    let steal_before = steal_ms();
    let first = pacer.wait();
    let mut last = first;
    let mut ran = 1u64;
    while last.index + 1 < cycles {
        let tick = pacer.wait();
        let expected = period * u32::try_from(tick.index - last.index).unwrap_or(u32::MAX);
        let interval = tick.woke - last.woke;
        period_error.record(interval.abs_diff(expected));
        lateness.record(tick.lateness());
        if tick.index < tenth {
            early.record(tick.lateness());
        } else if tick.index >= cycles.saturating_sub(tenth) {
            late.record(tick.lateness());
        }
        last = tick;
        ran += 1;
    }
    let steal = match (steal_before, steal_ms()) {
        (Some(a), Some(b)) => Some(b - a),
        _ => None,
    };
    // Drift: how much later (or earlier) than their deadlines the cycles of
    // the last tenth started than those of the first tenth, median against
    // median so that one late wake-up does not count as drift. Deadlines are
    // absolute (start + k x period), so the loop's own clock cannot drift.
    let span = last.woke - first.deadline;
    let drift_us = us(late.quantile(0.5)) - us(early.quantile(0.5));
    let steal_json = steal.map_or("null".to_owned(), |ms| format!("{ms:.0}"));
    let scheduling = if rt_report.fifo_priority.is_some() || rt_report.pinned.is_some() {
        let core = rt_report
            .pinned
            .map_or("not pinned".to_owned(), |c| format!("pinned to core {c}"));
        let fifo = rt_report
            .fifo_priority
            .map_or("normal priority".to_owned(), |p| {
                format!("SCHED_FIFO priority {p}")
            });
        format!("real-time ({core}, {fifo})")
    } else {
        "normal".to_owned()
    };
    if args.json {
        println!(
            "{{\"rate_hz\":{},\"seconds\":{},\"scheduling\":\"{}\",\"cycles\":{},\"overruns\":{},\
             \"period_error_us\":{{\"p50\":{},\"p99\":{},\"max\":{}}},\
             \"lateness_us\":{{\"p50\":{},\"p99\":{},\"max\":{}}},\"drift_us\":{:.3},\"steal_ms\":{}}}",
            args.rate,
            args.seconds,
            scheduling,
            ran,
            pacer.overruns(),
            us(period_error.quantile(0.5)),
            us(period_error.quantile(0.99)),
            us(period_error.max()),
            us(lateness.quantile(0.5)),
            us(lateness.quantile(0.99)),
            us(lateness.max()),
            drift_us,
            steal_json
        );
    } else {
        println!(
            "{} Hz for {} s, {scheduling} scheduling, spin {} us",
            args.rate, args.seconds, args.spin_us
        );
        println!("cycles        {ran} ({} overruns)", pacer.overruns());
        println!(
            "period error  p50 {:.0} us  p99 {:.0} us  max {:.0} us",
            us(period_error.quantile(0.5)),
            us(period_error.quantile(0.99)),
            us(period_error.max())
        );
        println!(
            "lateness      p50 {:.0} us  p99 {:.0} us  max {:.0} us",
            us(lateness.quantile(0.5)),
            us(lateness.quantile(0.99)),
            us(lateness.max())
        );
        println!(
            "total drift   {drift_us:.3} us over {:.3} s",
            span.as_secs_f64()
        );
        if let Some(ms) = steal {
            println!("cpu steal     {ms:.0} ms (time the hypervisor ran other guests)");
        }
    }
}
