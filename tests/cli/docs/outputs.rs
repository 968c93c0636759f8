//! Whether a file a document says is written is what its name says.

use std::path::Path;

/// The first bytes of every PNG file.
const PNG_MAGIC: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];

/// Checks `file` by its extension: a PNG's magic bytes, an SVG's root
/// element, a CSV's header and rows (`rows_per_s` of them a second by its
/// first column, the time in s, when given), JSON and YAML that parse;
/// any other file must not be empty.
pub fn check(file: &Path, rows_per_s: Option<f64>) -> Result<(), String> {
    let bytes = std::fs::read(file).map_err(|e| format!("not written ({e})"))?;
    let ext = file.extension().and_then(|e| e.to_str()).unwrap_or("");
    if rows_per_s.is_some() && ext != "csv" {
        return Err("a rate is checked on a CSV only".into());
    }
    let text = || String::from_utf8(bytes.clone()).map_err(|_| "not UTF-8 text".to_owned());
    match ext {
        "png" if bytes.starts_with(&PNG_MAGIC) => Ok(()),
        "png" => Err(format!(
            "no PNG: it starts {:?}",
            &bytes[..bytes.len().min(8)]
        )),
        "svg" => {
            let text = text()?;
            let start = text.trim_start();
            let root = start.starts_with("<svg") || start.starts_with("<?xml");
            if root && text.trim_end().ends_with("</svg>") {
                Ok(())
            } else {
                Err("no whole SVG document".into())
            }
        }
        "csv" => csv(&text()?, rows_per_s),
        "json" => serde_json::from_slice::<serde_json::Value>(&bytes)
            .map(drop)
            .map_err(|e| format!("no JSON: {e}")),
        "yaml" | "yml" => match serde_yaml::from_slice::<serde_yaml::Value>(&bytes) {
            Ok(serde_yaml::Value::Mapping(_)) => Ok(()),
            Ok(_) => Err("YAML, but not a mapping".into()),
            Err(e) => Err(format!("no YAML: {e}")),
        },
        _ if bytes.is_empty() => Err("empty".into()),
        _ => Ok(()),
    }
}

/// A header of named columns, rows of as many fields, and the rate.
fn csv(text: &str, rows_per_s: Option<f64>) -> Result<(), String> {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().ok_or("empty")?.split(',').collect();
    if header.len() < 2 || header.iter().any(|h| h.trim().is_empty()) {
        return Err(format!("no header of named columns: {header:?}"));
    }
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    if let Some(bad) = rows.iter().position(|r| r.len() != header.len()) {
        return Err(format!(
            "row {} has {} fields, the header {}",
            bad + 2,
            rows[bad].len(),
            header.len()
        ));
    }
    let Some(want) = rows_per_s else {
        return if rows.is_empty() {
            Err("no rows".into())
        } else {
            Ok(())
        };
    };
    let times: Vec<f64> = rows
        .iter()
        .map(|r| {
            r[0].parse::<f64>()
                .map_err(|_| format!("time `{}` is no number", r[0]))
        })
        .collect::<Result<_, _>>()?;
    if times.len() < 50 {
        return Err(format!("{} rows: too few for a rate", times.len()));
    }
    if times.windows(2).any(|w| w[1] <= w[0]) {
        return Err("times that do not rise".into());
    }
    let span = times[times.len() - 1] - times[0];
    let rate = (times.len() - 1) as f64 / span;
    if (rate - want).abs() <= want * 0.02 {
        Ok(())
    } else {
        Err(format!(
            "{rate:.1} rows a second over {span:.2} s, the doc says {want}"
        ))
    }
}
