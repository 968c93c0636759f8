//! The monitor's screen: a summary line, one table row per servo and the
//! keys, drawn with ratatui.

use ratatui::layout::{Constraint, Layout};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Cell, Paragraph, Row as TableRow, Table};

use servobus_config::limits::Fixed;

use super::{Frame, Row};

/// The keys and what they do, as shown at the bottom of the screen.
pub const KEYS: &str = "q quit   Space torque OFF on every servo";

/// What the reply column measures, as shown under the table: one SYNC
/// READ asks every servo and they answer in turn, so a later servo's reply
/// comes after the earlier ones' and its figure is larger without the
/// servo being slower.
pub const REPLY_COLUMN: &str = "reply p99 us: request sent to this servo's reply received, \
     p99 in microseconds; servos answer one SYNC READ in turn, so later ones wait for earlier ones";

const HEADER: [&str; 16] = [
    "ID",
    "joint",
    "model",
    "pos deg",
    "ticks",
    "goal deg",
    "deg/s",
    "load %",
    "cur mA",
    "volt",
    "temp C",
    "torque",
    "status",
    "replies",
    "timeouts",
    "reply p99 us",
];

/// The status column's width, in cells.
const STATUS_WIDTH: u16 = 24;

const WIDTHS: [u16; 16] = [3, 14, 8, 8, 6, 8, 7, 7, 6, 5, 6, 6, STATUS_WIDTH, 8, 8, 12];

/// Where the figures on the screen come from, in words, for a frame's
/// `source` (`bus` or `telemetry`).
pub fn source_text(source: &str) -> &str {
    match source {
        "bus" => "read from the bus by the monitor",
        "telemetry" => "the running motion's telemetry",
        other => other,
    }
}

/// `text` within `width` characters, cut only between words: as many whole
/// words as fit, then `…`.
fn fit_words(text: &str, width: usize) -> String {
    if text.chars().count() <= width {
        return text.to_string();
    }
    let mut kept = String::new();
    for word in text.split(' ') {
        let with = if kept.is_empty() {
            word.to_string()
        } else {
            format!("{kept} {word}")
        };
        if with.chars().count() + 1 > width {
            break;
        }
        kept = with;
    }
    format!("{kept}…")
}

/// The status flags within `width` characters: whole names only, and
/// `+N` for the ones left out.
fn fit_flags(flags: &[&str], width: usize) -> String {
    let names: Vec<String> = flags.iter().map(|f| f.to_uppercase()).collect();
    for kept in (1..=names.len()).rev() {
        let mut text = names[..kept].join(", ");
        if kept < names.len() {
            text.push_str(&format!(" +{}", names.len() - kept));
        }
        if text.chars().count() <= width {
            return text;
        }
    }
    fit_words(&names.join(", "), width)
}

fn opt(v: Option<f64>, decimals: usize) -> String {
    v.map_or_else(|| "-".to_string(), |v| Fixed(v, decimals).to_string())
}

fn row_cells(r: &Row) -> (Vec<Cell<'static>>, Style) {
    let (status, status_style) = if r.is_missing() {
        let why = r.missing.as_deref().unwrap_or("no reply");
        (
            fit_words(&format!("MISSING ({why})"), usize::from(STATUS_WIDTH)),
            Style::default().fg(Color::Red).add_modifier(Modifier::BOLD),
        )
    } else if r.flags.is_empty() {
        ("ok".to_string(), Style::default().fg(Color::Green))
    } else {
        (
            fit_flags(&r.flags, usize::from(STATUS_WIDTH)),
            Style::default()
                .fg(Color::White)
                .bg(Color::Red)
                .add_modifier(Modifier::BOLD),
        )
    };
    let torque = match r.torque {
        Some(true) => "on",
        Some(false) => "off",
        None => "-",
    };
    let cells = vec![
        Cell::from(r.id.to_string()),
        Cell::from(r.joint.clone().unwrap_or_else(|| "-".into())),
        Cell::from(r.model.clone()),
        Cell::from(opt(r.position_deg, 1)),
        Cell::from(
            r.position_ticks
                .map_or_else(|| "-".into(), |t| t.to_string()),
        ),
        Cell::from(opt(r.goal_deg, 1)),
        Cell::from(opt(r.speed_deg_s, 0)),
        Cell::from(opt(r.load_pct, 1)),
        Cell::from(opt(r.current_ma, 0)),
        Cell::from(opt(r.voltage_v, 1)),
        Cell::from(opt(r.temperature_c, 0)),
        Cell::from(torque),
        Cell::from(status).style(status_style),
        Cell::from(r.replies.to_string()),
        Cell::from(r.timeouts.to_string()),
        Cell::from(opt(r.p99_latency_us, 0)),
    ];
    // A missing servo keeps its last values, dimmed.
    let style = if !r.is_missing() {
        Style::default()
    } else {
        Style::default().add_modifier(Modifier::DIM)
    };
    (cells, style)
}

/// Draws `frame` under the heading `title`.
pub fn draw(f: &mut ratatui::Frame<'_>, frame: &Frame, title: &str) {
    let [top, table, bottom] = Layout::vertical([
        Constraint::Length(2),
        Constraint::Min(3),
        Constraint::Length(2),
    ])
    .areas(f.area());
    let summary = Line::from(vec![
        Span::styled(
            title.to_string(),
            Style::default().add_modifier(Modifier::BOLD),
        ),
        Span::raw(format!(
            "   t {:.1} s   read rate {:.1} Hz   bus utilisation {:.1} %   figures: {}",
            frame.time_s,
            frame.read_rate_hz,
            100.0 * frame.utilisation,
            source_text(frame.source)
        )),
    ]);
    f.render_widget(Paragraph::new(summary), top);
    let header = TableRow::new(HEADER.map(Cell::from))
        .style(Style::default().add_modifier(Modifier::BOLD | Modifier::UNDERLINED));
    let rows = frame.servos.iter().map(|r| {
        let (cells, style) = row_cells(r);
        TableRow::new(cells).style(style)
    });
    let widths = WIDTHS.map(Constraint::Length);
    f.render_widget(Table::new(rows, widths).header(header), table);
    let mut keys = vec![Span::styled(
        format!("keys: {KEYS}"),
        Style::default().fg(Color::Cyan),
    )];
    if let Some(note) = &frame.note {
        keys.push(Span::styled(
            format!("   [{note}]"),
            Style::default()
                .fg(Color::Yellow)
                .add_modifier(Modifier::BOLD),
        ));
    }
    let legend = Line::styled(REPLY_COLUMN, Style::default().add_modifier(Modifier::DIM));
    f.render_widget(Paragraph::new(vec![Line::from(keys), legend]), bottom);
}
