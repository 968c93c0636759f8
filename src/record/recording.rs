//! A recorded path read back for `servobus play FILE.csv`.

use std::path::Path;

use servobus_config::{limits, ConfigError, Units};

/// A recorded path read back for `servobus play`: sample times and every
/// robot joint's position, in radians.
pub struct Recording {
    /// Sample times, s, increasing.
    pub times: Vec<f64>,
    /// Per sample, one position per robot joint (robot order), rad.
    pub samples: Vec<Vec<f64>>,
    /// Robot joints the file does not name (held at their rest position).
    pub missing: Vec<String>,
    /// The largest rounding error of the positions as written, rad: half
    /// a unit of the finest decimal in the file (0 for numbers written in
    /// exponent form, taken as exact).
    pub resolution: f64,
    /// What was read of a `play --log` file: its `planned_<unit>` column,
    /// or (an older log) `measured_<unit>`; `None` for `time_s,<joint>...`.
    pub column: Option<String>,
}

/// Reads a recorded path for `robot`: either the CSV that `play --log`
/// writes (one row per cycle and joint) or a CSV of `time_s,<joint>...` (a
/// column per joint, in degrees, or in radians when named `<joint>_rad`).
///
/// Of a log, the `planned_<unit>` column is read: the path that run
/// played, within every limit by construction, on the run's own clock.
/// The `measured_<unit>` column is what the servos did of it, a tracking
/// error and a position tick (0.09 deg on an STS3215) away, and
/// `commanded_<unit>` is the same path sent `lead` early; a log without a
/// planned column (an older one) gives its measured positions, else the
/// commanded ones.
pub fn read_recording(path: &Path, robot: &servobus_config::Robot) -> anyhow::Result<Recording> {
    let bytes = limits::read_capped(path, limits::MAX_RECORDING_BYTES)?;
    // Every refusal is an input error (exit 2) at its place in the file.
    let refuse = |line: usize, column: usize, what: String| {
        ConfigError::invalid(path, line, column, "", what)
    };
    let mut reader = csv::Reader::from_reader(bytes.as_slice());
    let header: Vec<String> = reader
        .headers()
        .map_err(|e| refuse(1, 1, e.to_string()))?
        .iter()
        .map(str::to_owned)
        .collect();
    let names: Vec<&str> = robot.joints().map(|j| j.name.as_str()).collect();
    let rest: Vec<f64> = robot
        .joints()
        .map(|j| robot.units.to_rad(j.rest()))
        .collect();
    // Per robot joint, its (time, rad) series.
    let mut series: Vec<Vec<(f64, f64)>> = vec![Vec::new(); names.len()];
    let col = |n: &str| header.iter().position(|h| h == n);
    let bad = |line: usize, what: &str| refuse(line, 1, what.to_owned());
    // The number in column `c` of a row at `line`; `None` when empty.
    let number = |row: &csv::StringRecord, line: usize, c: usize| {
        let Some(text) = row.get(c).map(str::trim).filter(|s| !s.is_empty()) else {
            return Ok(None);
        };
        text.parse::<f64>().map(Some).map_err(|_| {
            let name = header.get(c).map_or("", String::as_str);
            refuse(
                line,
                c + 1,
                format!("`{text}` in column `{name}` is not a number"),
            )
        })
    };
    // The finest decimal place of a position read (None: exponent form),
    // the unit they are in, and which column of a log was read.
    let mut decimals: Option<u32> = Some(0);
    let mut file_units = Units::Deg;
    let mut column = None;
    let Some(time_col) = col("time_s") else {
        return Err(refuse(1, 1, "no `time_s` column".to_owned()).into());
    };
    if let Some(joint_col) = col("joint") {
        let unit_of = |prefix: &str| {
            header.iter().enumerate().find_map(|(i, h)| {
                let u = h.strip_prefix(prefix)?;
                Some((i, if u == "rad" { Units::Rad } else { Units::Deg }))
            })
        };
        let (Some((cmd, units)), measured) = (unit_of("commanded_"), unit_of("measured_")) else {
            let what = "a `play --log` file needs a commanded_<unit> column";
            return Err(refuse(1, 1, what.to_owned()).into());
        };
        let planned = unit_of("planned_");
        file_units = units;
        column = Some(header[planned.or(measured).map_or(cmd, |(c, _)| c)].clone());
        for (i, row) in reader.records().enumerate() {
            let row = row.map_err(|e| refuse(i + 2, 1, e.to_string()))?;
            check_rows(path, i)?;
            let num = |c: usize| number(&row, i + 2, c);
            let t = num(time_col)?.ok_or_else(|| bad(i + 2, "no time"))?;
            let Some(j) = row
                .get(joint_col)
                .and_then(|n| names.iter().position(|x| *x == n))
            else {
                continue;
            };
            let first = planned.or(measured).map(|(c, _)| c);
            let (c, value) = match first.map(|c| num(c).map(|v| v.map(|v| (c, v)))) {
                Some(Ok(Some(found))) => found,
                Some(Err(e)) => return Err(e.into()),
                _ => (cmd, num(cmd)?.ok_or_else(|| bad(i + 2, "no position"))?),
            };
            decimals = finest(decimals, row.get(c));
            series[j].push((t, units.to_rad(value)));
        }
    } else {
        let cols: Vec<Option<(usize, Units)>> = names
            .iter()
            .map(|n| {
                col(n)
                    .map(|c| (c, Units::Deg))
                    .or_else(|| col(&format!("{n}_deg")).map(|c| (c, Units::Deg)))
                    .or_else(|| col(&format!("{n}_rad")).map(|c| (c, Units::Rad)))
            })
            .collect();
        if cols.iter().all(Option::is_none) {
            let what = format!(
                "no column names a joint of {} (joints: {})",
                robot.name,
                names.join(", ")
            );
            return Err(refuse(1, 1, what).into());
        }
        for (i, row) in reader.records().enumerate() {
            let row = row.map_err(|e| refuse(i + 2, 1, e.to_string()))?;
            check_rows(path, i)?;
            let num = |c: usize| number(&row, i + 2, c);
            let t = num(time_col)?.ok_or_else(|| bad(i + 2, "no time"))?;
            for (j, c) in cols.iter().enumerate() {
                if let Some((c, u)) = c {
                    let v = num(*c)?.ok_or_else(|| bad(i + 2, "a position is missing"))?;
                    decimals = finest(decimals, row.get(*c));
                    file_units = *u;
                    series[j].push((t, u.to_rad(v)));
                }
            }
        }
    }
    // A common time base: the series with the most samples.
    let base = series
        .iter()
        .max_by_key(|s| s.len())
        .cloned()
        .unwrap_or_default();
    let mut times: Vec<f64> = Vec::with_capacity(base.len());
    for &(t, _) in &base {
        if times.last().is_none_or(|&l| t > l) {
            times.push(t);
        }
    }
    if times.len() < 2 {
        return Err(refuse(1, 1, "fewer than two samples".to_owned()).into());
    }
    let mut samples = vec![Vec::with_capacity(names.len()); times.len()];
    for (j, s) in series.iter().enumerate() {
        for (i, &t) in times.iter().enumerate() {
            samples[i].push(if s.is_empty() { rest[j] } else { at(s, t) });
        }
    }
    let missing = names
        .iter()
        .zip(&series)
        .filter(|(_, s)| s.is_empty())
        .map(|(n, _)| n.to_string())
        .collect();
    // Half a unit of the finest decimal place: the most any number was
    // rounded by (in exponent form, taken as exact).
    let resolution = decimals.map_or(0.0, |d| {
        file_units.to_rad(0.5 * 10f64.powi(-(d.min(300) as i32)))
    });
    Ok(Recording {
        times,
        samples,
        missing,
        resolution,
        column,
    })
}

/// The finest decimal place so far (`None` once a number in exponent form
/// was read: its rounding is not told by its places) and that of `text`.
fn finest(so_far: Option<u32>, text: Option<&str>) -> Option<u32> {
    let text = text.unwrap_or_default().trim();
    if text.contains(['e', 'E']) {
        return None;
    }
    let places = text.split_once('.').map_or(0, |(_, f)| f.len() as u32);
    so_far.map(|d| d.max(places))
}

/// Refuses row `index` (0-based, after the header) past
/// [`limits::MAX_RECORDING_ROWS`].
fn check_rows(path: &Path, index: usize) -> Result<(), ConfigError> {
    if index < limits::MAX_RECORDING_ROWS {
        return Ok(());
    }
    let e = limits::LimitError::Rows;
    Err(ConfigError::invalid(path, index + 2, 1, "", e.to_string()))
}

/// The series at `t`, linearly interpolated (held beyond its ends).
fn at(s: &[(f64, f64)], t: f64) -> f64 {
    let i = s.partition_point(|p| p.0 <= t);
    match i {
        0 => s[0].1,
        i if i >= s.len() => s[s.len() - 1].1,
        i => {
            let ((ta, a), (tb, b)) = (s[i - 1], s[i]);
            if tb > ta {
                a + (b - a) * (t - ta) / (tb - ta)
            } else {
                b
            }
        }
    }
}
