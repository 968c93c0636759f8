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
    let mut reader = csv::Reader::from_reader(bytes.as_slice());
    let sheet = Sheet::new(path, &mut reader)?;
    let names: Vec<&str> = robot.joints().map(|j| j.name.as_str()).collect();
    let Some(time_col) = sheet.col("time_s") else {
        return Err(sheet.refuse(1, 1, "no `time_s` column".to_owned()).into());
    };
    let read = match sheet.col("joint") {
        Some(joint_col) => sheet.read_log(&mut reader, &names, time_col, joint_col)?,
        None => sheet.read_columns(&mut reader, robot, &names, time_col)?,
    };
    let rest: Vec<f64> = robot
        .joints()
        .map(|j| robot.units.to_rad(j.rest()))
        .collect();
    Ok(read.into_recording(&sheet, &names, &rest)?)
}

/// A recording's header and the file it came from: every refusal is an
/// input error (exit 2) at its place in the file.
struct Sheet<'a> {
    /// The file read, named in refusals.
    path: &'a Path,
    /// The column names of the first row.
    header: Vec<String>,
}

/// What the rows of a recording gave, before resampling.
struct Series {
    /// Per robot joint, its (time, rad) series.
    per_joint: Vec<Vec<(f64, f64)>>,
    /// The finest decimal place of a position read (None: exponent form).
    decimals: Option<u32>,
    /// The unit the positions were written in.
    units: Units,
    /// Which column of a log was read (`None` for `time_s,<joint>...`).
    column: Option<String>,
}

impl<'a> Sheet<'a> {
    /// Reads the header row of `reader`.
    fn new(path: &'a Path, reader: &mut csv::Reader<&[u8]>) -> Result<Self, ConfigError> {
        let mut sheet = Sheet {
            path,
            header: Vec::new(),
        };
        sheet.header = reader
            .headers()
            .map_err(|e| sheet.refuse(1, 1, e.to_string()))?
            .iter()
            .map(str::to_owned)
            .collect();
        Ok(sheet)
    }

    /// The refusal of the file at `line` and `column` (1-based).
    fn refuse(&self, line: usize, column: usize, what: String) -> ConfigError {
        ConfigError::invalid(self.path, line, column, "", what)
    }

    /// The index of the column named `name`.
    fn col(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// The first column named `<prefix><unit>`, and its unit.
    fn unit_of(&self, prefix: &str) -> Option<(usize, Units)> {
        self.header.iter().enumerate().find_map(|(i, h)| {
            let u = h.strip_prefix(prefix)?;
            Some((i, if u == "rad" { Units::Rad } else { Units::Deg }))
        })
    }

    /// The number in column `c` of a row at `line`; `None` when empty.
    fn number(
        &self,
        row: &csv::StringRecord,
        line: usize,
        c: usize,
    ) -> Result<Option<f64>, ConfigError> {
        let Some(text) = row.get(c).map(str::trim).filter(|s| !s.is_empty()) else {
            return Ok(None);
        };
        text.parse::<f64>().map(Some).map_err(|_| {
            let name = self.header.get(c).map_or("", String::as_str);
            let what = format!("`{text}` in column `{name}` is not a number");
            self.refuse(line, c + 1, what)
        })
    }

    /// The number in column `c` of a row at `line`, refused as `missing`
    /// when empty.
    fn required(
        &self,
        row: &csv::StringRecord,
        line: usize,
        c: usize,
        missing: &str,
    ) -> Result<f64, ConfigError> {
        self.number(row, line, c)?
            .ok_or_else(|| self.refuse(line, 1, missing.to_owned()))
    }

    /// The row at 0-based `index` (after the header), checked against the
    /// row limit.
    fn row(
        &self,
        index: usize,
        row: csv::Result<csv::StringRecord>,
    ) -> Result<csv::StringRecord, ConfigError> {
        let row = row.map_err(|e| self.refuse(index + 2, 1, e.to_string()))?;
        check_rows(self.path, index)?;
        Ok(row)
    }

    /// Reads the rows of a `play --log` file: one row per cycle and joint,
    /// its planned position, else its measured one, else its commanded one.
    fn read_log(
        &self,
        reader: &mut csv::Reader<&[u8]>,
        names: &[&str],
        time_col: usize,
        joint_col: usize,
    ) -> Result<Series, ConfigError> {
        let (Some((cmd, units)), measured) =
            (self.unit_of("commanded_"), self.unit_of("measured_"))
        else {
            let what = "a `play --log` file needs a commanded_<unit> column";
            return Err(self.refuse(1, 1, what.to_owned()));
        };
        let first = self.unit_of("planned_").or(measured).map(|(c, _)| c);
        let mut read = Series::new(names.len(), units);
        read.column = Some(self.header[first.unwrap_or(cmd)].clone());
        for (i, row) in reader.records().enumerate() {
            let row = self.row(i, row)?;
            let t = self.required(&row, i + 2, time_col, "no time")?;
            let Some(j) = row
                .get(joint_col)
                .and_then(|n| names.iter().position(|x| *x == n))
            else {
                continue;
            };
            let found = match first {
                Some(c) => self.number(&row, i + 2, c)?.map(|v| (c, v)),
                None => None,
            };
            let (c, value) = match found {
                Some(found) => found,
                None => (cmd, self.required(&row, i + 2, cmd, "no position")?),
            };
            read.push(j, t, units.to_rad(value), row.get(c));
        }
        Ok(read)
    }

    /// Reads the rows of a CSV of `time_s,<joint>...`: a column per joint,
    /// named `<joint>` or `<joint>_deg` (degrees) or `<joint>_rad`.
    fn read_columns(
        &self,
        reader: &mut csv::Reader<&[u8]>,
        robot: &servobus_config::Robot,
        names: &[&str],
        time_col: usize,
    ) -> Result<Series, ConfigError> {
        let cols: Vec<Option<(usize, Units)>> = names
            .iter()
            .map(|n| {
                self.col(n)
                    .map(|c| (c, Units::Deg))
                    .or_else(|| self.col(&format!("{n}_deg")).map(|c| (c, Units::Deg)))
                    .or_else(|| self.col(&format!("{n}_rad")).map(|c| (c, Units::Rad)))
            })
            .collect();
        if cols.iter().all(Option::is_none) {
            let what = format!(
                "no column names a joint of {} (joints: {})",
                robot.name,
                names.join(", ")
            );
            return Err(self.refuse(1, 1, what));
        }
        let mut read = Series::new(names.len(), Units::Deg);
        for (i, row) in reader.records().enumerate() {
            let row = self.row(i, row)?;
            let t = self.required(&row, i + 2, time_col, "no time")?;
            for (j, c) in cols.iter().enumerate() {
                if let Some((c, u)) = c {
                    let v = self.required(&row, i + 2, *c, "a position is missing")?;
                    read.units = *u;
                    read.push(j, t, u.to_rad(v), row.get(*c));
                }
            }
        }
        Ok(read)
    }
}

impl Series {
    /// No samples yet of `joints` joints, in `units`.
    fn new(joints: usize, units: Units) -> Self {
        Series {
            per_joint: vec![Vec::new(); joints],
            decimals: Some(0),
            units,
            column: None,
        }
    }

    /// Adds joint `j` at `t` at `rad`, written as `text`.
    fn push(&mut self, j: usize, t: f64, rad: f64, text: Option<&str>) {
        self.decimals = finest(self.decimals, text);
        self.per_joint[j].push((t, rad));
    }

    /// Resamples every joint on a common time base (the series with the
    /// most samples), holding a joint the file does not name at `rest`.
    fn into_recording(
        self,
        sheet: &Sheet,
        names: &[&str],
        rest: &[f64],
    ) -> Result<Recording, ConfigError> {
        let series = &self.per_joint;
        let base = series.iter().max_by_key(|s| s.len());
        let mut times: Vec<f64> = Vec::with_capacity(base.map_or(0, Vec::len));
        for &(t, _) in base.into_iter().flatten() {
            if times.last().is_none_or(|&l| t > l) {
                times.push(t);
            }
        }
        if times.len() < 2 {
            return Err(sheet.refuse(1, 1, "fewer than two samples".to_owned()));
        }
        let mut samples = vec![Vec::with_capacity(names.len()); times.len()];
        for (j, s) in series.iter().enumerate() {
            for (i, &t) in times.iter().enumerate() {
                samples[i].push(if s.is_empty() { rest[j] } else { at(s, t) });
            }
        }
        let missing = names
            .iter()
            .zip(series)
            .filter(|(_, s)| s.is_empty())
            .map(|(n, _)| n.to_string())
            .collect();
        // Half a unit of the finest decimal place: the most any number was
        // rounded by (in exponent form, taken as exact).
        let resolution = self.decimals.map_or(0.0, |d| {
            self.units.to_rad(0.5 * 10f64.powi(-(d.min(300) as i32)))
        });
        Ok(Recording {
            times,
            samples,
            missing,
            resolution,
            column: self.column,
        })
    }
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
